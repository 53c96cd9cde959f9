//! A camera image prepared for matching: compact texels that carry both the
//! gray value and whether a bilinear sample there is trustworthy.

use omnimvs_camera::ValidityMask;
use omnimvs_core::GrayImage;
use omnimvs_core::interp::{inside_corner, lerp_2d};
use omnimvs_sweep::SphereProjector;

use crate::StereoError;

/// Fixed-point steps per gray level in a texel.
const TEXEL_SCALE: f32 = 128.0;

/// One camera's image for matching. Each texel is a `u16`: bit 0 says
/// whether the 2x2 block `(x..=x+1, y..=y+1)` used by a bilinear sample with
/// top-left corner `(x, y)` is entirely valid, bits 1-15 hold the gray value
/// (clamped to `[0, 255]`) in 1/128 steps. Two bytes per pixel keep all
/// four images of a rig in cache, which is what bounds the warping speed.
///
/// Samples come out normalised to zero mean and unit variance over the
/// camera's valid pixels (the paper feeds normalised gray images to every
/// method; ZNCC itself does not depend on it, only the variance floor
/// [`crate::ZNCC_VARIANCE_EPS`] does).
#[derive(Debug, Clone)]
pub struct CameraView {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<u16>,
    /// Mean gray value over the valid pixels.
    pub mean: f32,
    /// `1 / std` over the valid pixels (0 for a constant image).
    pub inv_std: f32,
}

impl CameraView {
    /// Prepares camera `camera_number` (1-based, for messages).
    ///
    /// # Errors
    /// [`StereoError::SizeMismatch`] when the mask size differs from the
    /// image's.
    pub fn new(
        image: &GrayImage,
        mask: Option<&ValidityMask>,
        camera_number: usize,
    ) -> Result<Self, StereoError> {
        let (w, h) = (image.width, image.height);
        if let Some(m) = mask
            && (m.width as usize != w || m.height as usize != h)
        {
            return Err(StereoError::SizeMismatch {
                camera: camera_number,
                what: "validity mask",
                found_w: m.width as usize,
                found_h: m.height as usize,
                want_w: w,
                want_h: h,
            });
        }
        let ok = |i: usize| mask.is_none_or(|m| m.valid[i]);
        let (mut sum, mut sum_sq, mut n) = (0f64, 0f64, 0usize);
        for (i, &v) in image.data.iter().enumerate() {
            if ok(i) {
                let v = f64::from(v.clamp(0.0, 255.0));
                sum += v;
                sum_sq += v * v;
                n += 1;
            }
        }
        let mean = if n > 0 { sum / n as f64 } else { 0.0 };
        let var = if n > 0 {
            sum_sq / n as f64 - mean * mean
        } else {
            0.0
        };
        let inv_std = if var > 1e-9 { 1.0 / var.sqrt() } else { 0.0 };
        let mut texels: Vec<u16> = image
            .data
            .iter()
            .map(|&v| ((v.clamp(0.0, 255.0) * TEXEL_SCALE).round() as u16) << 1)
            .collect();
        for y in 0..h.saturating_sub(1) {
            for x in 0..w.saturating_sub(1) {
                let i = y * w + x;
                if ok(i) && ok(i + 1) && ok(i + w) && ok(i + w + 1) {
                    texels[i] |= 1;
                }
            }
        }
        Ok(Self {
            width: w,
            height: h,
            texels,
            mean: mean as f32,
            inv_std: inv_std as f32,
        })
    }

    /// The first half of [`Self::sample`] for a run of positions: the index
    /// of each sample's top-left texel (`-1` where the 2x2 block is not
    /// inside the image) and its fractional offsets, from position `start`
    /// on. Together with [`Self::sample_at`] it gives exactly what
    /// `sample` gives.
    pub fn taps(&self, start: usize, cols: &[f32], rows: &[f32], taps: &mut Taps) {
        let n = cols.len().min(rows.len()).min(taps.index.len());
        for i in start..n {
            match inside_corner(cols[i], rows[i], self.width, self.height) {
                Some((index, fx, fy)) => {
                    taps.index[i] = index as i32;
                    taps.fx[i] = fx;
                    taps.fy[i] = fy;
                }
                None => taps.index[i] = -1,
            }
        }
    }

    /// [`Self::taps`] eight positions at a time with AVX2 (the same
    /// conversions and subtractions); returns how many leading positions it did.
    #[cfg(target_arch = "x86_64")]
    pub fn taps_v3(
        &self,
        simd: pulp::x86::V3,
        cols: &[f32],
        rows: &[f32],
        taps: &mut Taps,
    ) -> usize {
        use pulp::{as_arrays, as_arrays_mut, bytemuck::cast};
        let (width, last_col, last_row) = (
            self.width as i32,
            (self.width - 1) as f32,
            (self.height - 1) as f32,
        );
        simd.vectorize(
            #[inline(always)]
            || {
                let (cols, _) = as_arrays::<8, f32>(cols);
                let (rows, _) = as_arrays::<8, f32>(rows);
                let (index, _) = as_arrays_mut::<8, i32>(&mut taps.index);
                let (fx, _) = as_arrays_mut::<8, f32>(&mut taps.fx);
                let (fy, _) = as_arrays_mut::<8, f32>(&mut taps.fy);
                let n = cols.len().min(rows.len()).min(index.len());
                let n = n.min(fx.len()).min(fy.len());
                let zero = simd.splat_f32x8(0.0);
                let (last_col, last_row) = (simd.splat_f32x8(last_col), simd.splat_f32x8(last_row));
                let width = simd.splat_i32x8(width);
                let none = simd.splat_i32x8(-1);
                for i in 0..n {
                    let (col, row) = (cast(cols[i]), cast(rows[i]));
                    let inside = simd.and_m32x8(
                        simd.and_m32x8(simd.cmp_ge_f32x8(col, zero), simd.cmp_ge_f32x8(row, zero)),
                        simd.and_m32x8(
                            simd.cmp_lt_f32x8(col, last_col),
                            simd.cmp_lt_f32x8(row, last_row),
                        ),
                    );
                    let x0 = simd.convert_f32x8_to_i32x8(col);
                    let y0 = simd.convert_f32x8_to_i32x8(row);
                    let at = simd.wrapping_add_i32x8(simd.wrapping_mul_i32x8(y0, width), x0);
                    index[i] = cast(simd.select_i32x8(inside, at, none));
                    fx[i] = cast(simd.sub_f32x8(col, simd.convert_i32x8_to_f32x8(x0)));
                    fy[i] = cast(simd.sub_f32x8(row, simd.convert_i32x8_to_f32x8(y0)));
                }
                n * 8
            },
        )
    }

    /// The second half of [`Self::sample`]: the normalised bilinear sample
    /// of one tap (`index`, `fx`, `fy` as [`Self::taps`] wrote them), `None`
    /// where it is outside or touches an invalid pixel.
    #[inline]
    pub fn sample_at(&self, index: i32, fx: f32, fy: f32) -> Option<f32> {
        let i0 = usize::try_from(index).ok()?;
        let [t00, t01] = *self.texels.get(i0..)?.first_chunk::<2>()?;
        if t00 & 1 == 0 {
            return None;
        }
        let [t10, t11] = *self.texels.get(i0 + self.width..)?.first_chunk::<2>()?;
        let v = |t: u16| f32::from(t >> 1);
        let gray = lerp_2d([v(t00), v(t01), v(t10), v(t11)], fx, fy) * (1.0 / TEXEL_SCALE);
        Some((gray - self.mean) * self.inv_std)
    }

    /// Bilinear sample at fractional `(col, row)`, normalised; `None` when
    /// any of the four neighbours is outside the image or invalid.
    #[inline]
    pub fn sample(&self, col: f32, row: f32) -> Option<f32> {
        let (i, fx, fy) = inside_corner(col, row, self.width, self.height)?;
        let t00 = self.texels[i];
        if t00 & 1 == 0 {
            return None;
        }
        let j = i + self.width;
        let v = |t: u16| f32::from(t >> 1);
        let corners = [
            v(t00),
            v(self.texels[i + 1]),
            v(self.texels[j]),
            v(self.texels[j + 1]),
        ];
        let gray = lerp_2d(corners, fx, fy) * (1.0 / TEXEL_SCALE);
        Some((gray - self.mean) * self.inv_std)
    }
}

impl CameraView {
    /// The texels that [`Self::sample_at`] reads for the taps `index` (the scalar loads of
    /// a run of samples; the arithmetic is then [`Self::blend`]'s, eight at a time).
    pub fn gather(&self, index: &[i32], pairs: &mut TexelPairs) {
        let (t, w) = (&self.texels, self.width);
        let out = pairs.top.iter_mut().zip(pairs.bottom.iter_mut());
        for (&i, (top, bottom)) in index.iter().zip(out) {
            (*top, *bottom) = usize::try_from(i)
                .ok()
                .and_then(|i0| {
                    let [t00, t01] = *t.get(i0..)?.first_chunk::<2>()?;
                    let [t10, t11] = *t.get(i0 + w..)?.first_chunk::<2>()?;
                    Some((
                        u32::from(t00) | (u32::from(t01) << 16),
                        u32::from(t10) | (u32::from(t11) << 16),
                    ))
                })
                .unwrap_or((0, 0));
        }
    }

    /// [`Self::sample_at`] from the texels [`Self::gather`] read, for taps `start..`: the
    /// normalised value (0 where there is none) and 1 where there is none (0 otherwise).
    /// Bit for bit what `sample_at` gives.
    pub fn blend(
        &self,
        start: usize,
        taps: &Taps,
        pairs: &TexelPairs,
        values: &mut [f32],
        missing: &mut [f32],
    ) {
        let n = values.len().min(missing.len()).min(pairs.top.len());
        for i in start..n {
            let (top, bottom) = (pairs.top[i], pairs.bottom[i]);
            if top & 1 == 0 {
                (values[i], missing[i]) = (0.0, 1.0);
                continue;
            }
            let (a, b) = ((top & 0xffff) >> 1, top >> 17);
            let (c, d) = ((bottom & 0xffff) >> 1, bottom >> 17);
            let corners = [a as f32, b as f32, c as f32, d as f32];
            let gray = lerp_2d(corners, taps.fx[i], taps.fy[i]) * (1.0 / TEXEL_SCALE);
            (values[i], missing[i]) = ((gray - self.mean) * self.inv_std, 0.0);
        }
    }

    /// [`Self::blend`] eight taps at a time with AVX2 (the operations of
    /// [`omnimvs_core::interp::lerp_2d`] in the same order, no fused multiply-add); returns how
    /// many leading taps it did.
    #[cfg(target_arch = "x86_64")]
    pub fn blend_v3(
        &self,
        simd: pulp::x86::V3,
        taps: &Taps,
        pairs: &TexelPairs,
        values: &mut [f32],
        missing: &mut [f32],
    ) -> usize {
        use pulp::{as_arrays, as_arrays_mut, bytemuck::cast};
        let (mean, inv_std) = (self.mean, self.inv_std);
        simd.vectorize(
            #[inline(always)]
            || {
                let (top, _) = as_arrays::<8, u32>(&pairs.top);
                let (bottom, _) = as_arrays::<8, u32>(&pairs.bottom);
                let (fx, _) = as_arrays::<8, f32>(&taps.fx);
                let (fy, _) = as_arrays::<8, f32>(&taps.fy);
                let (values, _) = as_arrays_mut::<8, f32>(values);
                let (missing, _) = as_arrays_mut::<8, f32>(missing);
                let n = top.len().min(bottom.len()).min(fx.len()).min(fy.len());
                let n = n.min(values.len()).min(missing.len());
                let (zero, one) = (simd.splat_f32x8(0.0), simd.splat_f32x8(1.0));
                let scale = simd.splat_f32x8(1.0 / TEXEL_SCALE);
                let (mean, inv_std) = (simd.splat_f32x8(mean), simd.splat_f32x8(inv_std));
                let high_bit = simd.splat_u32x8(1 << 31);
                let float = |v: pulp::u32x8| simd.convert_i32x8_to_f32x8(cast(v));
                for i in 0..n {
                    let (t, u): (pulp::u32x8, pulp::u32x8) = (cast(top[i]), cast(bottom[i]));
                    let valid = simd.cmp_ge_u32x8(simd.shl_const_u32x8::<31>(t), high_bit);
                    let a = float(simd.shr_const_u32x8::<17>(simd.shl_const_u32x8::<16>(t)));
                    let b = float(simd.shr_const_u32x8::<17>(t));
                    let c = float(simd.shr_const_u32x8::<17>(simd.shl_const_u32x8::<16>(u)));
                    let d = float(simd.shr_const_u32x8::<17>(u));
                    let (x, y) = (cast(fx[i]), cast(fy[i]));
                    let upper = simd.add_f32x8(a, simd.mul_f32x8(x, simd.sub_f32x8(b, a)));
                    let lower = simd.add_f32x8(c, simd.mul_f32x8(x, simd.sub_f32x8(d, c)));
                    let gray = simd.mul_f32x8(
                        simd.add_f32x8(upper, simd.mul_f32x8(y, simd.sub_f32x8(lower, upper))),
                        scale,
                    );
                    let v = simd.mul_f32x8(simd.sub_f32x8(gray, mean), inv_std);
                    values[i] = cast(simd.select_f32x8(valid, v, zero));
                    missing[i] = cast(simd.select_f32x8(valid, zero, one));
                }
                n * 8
            },
        )
    }
}

/// The scratch of sampling one camera along a run of grid pixels on one sphere, and the
/// one place that chains the sampling kernels the way the matcher uses them: positions
/// ([`SphereProjector::project_run`]), taps, texels, blend (AVX2 where the CPU has it).
#[derive(Debug, Clone, Default)]
pub struct RunSampler {
    cols: Vec<f32>,
    rows: Vec<f32>,
    table_pos: Vec<f32>,
    taps: Taps,
    texels: TexelPairs,
    values: Vec<f32>,
    missing: Vec<f32>,
}

impl RunSampler {
    /// Room for runs of up to `n` grid pixels.
    pub fn new(n: usize) -> Self {
        Self {
            cols: vec![0.0; n],
            rows: vec![0.0; n],
            table_pos: vec![0.0; n],
            taps: Taps::new(n),
            texels: TexelPairs::new(n),
            values: vec![0.0; n],
            missing: vec![0.0; n],
        }
    }

    /// `view` sampled where grid pixels `start..start + n` (row-major) meet the sphere of
    /// inverse depth `inv_depth` (1/m) through `projector`: per pixel the normalised value
    /// (0 where there is none) and 1 where it is missing (0 otherwise), as
    /// [`CameraView::sample`] would give them. `n` at most the room of [`Self::new`].
    pub fn sample(
        &mut self,
        projector: &SphereProjector,
        view: &CameraView,
        start: usize,
        n: usize,
        inv_depth: f32,
    ) -> (&[f32], &[f32]) {
        let (cols, rows) = (&mut self.cols[..n], &mut self.rows[..n]);
        projector.project_run(start, inv_depth, cols, rows, &mut self.table_pos);
        #[cfg(target_arch = "x86_64")]
        let v3 = pulp::x86::V3::try_new();
        #[cfg(target_arch = "x86_64")]
        let done = v3.map_or(0, |simd| view.taps_v3(simd, cols, rows, &mut self.taps));
        #[cfg(not(target_arch = "x86_64"))]
        let done = 0;
        view.taps(done, cols, rows, &mut self.taps);
        view.gather(&self.taps.index[..n], &mut self.texels);
        let (values, missing) = (&mut self.values[..n], &mut self.missing[..n]);
        #[cfg(target_arch = "x86_64")]
        let done = v3.map_or(0, |simd| {
            view.blend_v3(simd, &self.taps, &self.texels, values, missing)
        });
        #[cfg(not(target_arch = "x86_64"))]
        let done = 0;
        view.blend(done, &self.taps, &self.texels, values, missing);
        (values, missing)
    }
}

/// The texels of a run of taps ([`CameraView::gather`]), two per `u32`: `top[i]` holds the
/// top-left texel in its low half and its right neighbour in the high half, `bottom[i]` the
/// two below; both 0 (validity bit clear) where the tap is outside the image.
#[derive(Debug, Clone, Default)]
pub struct TexelPairs {
    pub top: Vec<u32>,
    pub bottom: Vec<u32>,
}

impl TexelPairs {
    /// Room for `n` samples.
    pub fn new(n: usize) -> Self {
        Self {
            top: vec![0; n],
            bottom: vec![0; n],
        }
    }
}

/// Texel indices and fractional offsets of a run of bilinear samples
/// ([`CameraView::taps`]).
#[derive(Debug, Clone, Default)]
pub struct Taps {
    pub index: Vec<i32>,
    pub fx: Vec<f32>,
    pub fy: Vec<f32>,
}

impl Taps {
    /// Room for `n` samples.
    pub fn new(n: usize) -> Self {
        Self {
            index: vec![-1; n],
            fx: vec![0.0; n],
            fy: vec![0.0; n],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn taps_then_sample_at_equal_sample_bit_for_bit() {
        // A 13 x 9 image with a hole in its mask.
        let (w, h) = (13, 9);
        let img = GrayImage {
            width: w,
            height: h,
            data: (0..w * h).map(|i| ((i * 37) % 251) as f32 + 0.3).collect(),
        };
        let mask = ValidityMask {
            width: w as u32,
            height: h as u32,
            valid: (0..w * h).map(|i| i % 17 != 5).collect(),
        };
        let v = CameraView::new(&img, Some(&mask), 1).unwrap();
        let mut rng = omnimvs_core::rng::SplitMix64::new(3);
        let mut cols: Vec<f32> = (0..203)
            .map(|_| (rng.next_f64() * 15.0 - 1.0) as f32)
            .collect();
        let mut rows: Vec<f32> = (0..203)
            .map(|_| (rng.next_f64() * 11.0 - 1.0) as f32)
            .collect();
        // Edges and oddities: the last full block, just past it, NaN, huge.
        let odd = [
            (11.999, 7.999),
            (12.0, 3.0),
            (3.0, 8.0),
            (0.0, 0.0),
            (-0.0, 2.5),
            (f32::NAN, 1.0),
            (2.0, f32::NAN),
            (1e12, 1.0),
            (-1.0, -1.0),
            (f32::INFINITY, 2.0),
        ];
        for (k, &(c, r)) in odd.iter().enumerate() {
            cols[k * 9] = c;
            rows[k * 9] = r;
        }
        let plain: Vec<Option<u32>> = cols
            .iter()
            .zip(&rows)
            .map(|(&c, &r)| v.sample(c, r).map(f32::to_bits))
            .collect();
        assert!(plain.iter().filter(|s| s.is_some()).count() > 50);
        assert!(plain.iter().filter(|s| s.is_none()).count() > 20);
        let mut taps = Taps::new(cols.len());
        v.taps(0, &cols, &rows, &mut taps);
        let two_step: Vec<Option<u32>> = (0..cols.len())
            .map(|i| {
                v.sample_at(taps.index[i], taps.fx[i], taps.fy[i])
                    .map(f32::to_bits)
            })
            .collect();
        assert_eq!(two_step, plain);
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            let mut taps = Taps::new(cols.len());
            let done = v.taps_v3(simd, &cols, &rows, &mut taps);
            assert_eq!(done, 200);
            v.taps(done, &cols, &rows, &mut taps);
            let vector: Vec<Option<u32>> = (0..cols.len())
                .map(|i| {
                    v.sample_at(taps.index[i], taps.fx[i], taps.fy[i])
                        .map(f32::to_bits)
                })
                .collect();
            assert_eq!(vector, plain);
        }
        // Gathered texels blended, plainly and eight at a time: the same bits again.
        let as_pair = |s: Option<u32>| s.map_or((0, 1f32.to_bits()), |b| (b, 0));
        let expected: Vec<(u32, u32)> = plain.iter().map(|&s| as_pair(s)).collect();
        let mut pairs = TexelPairs::new(cols.len());
        v.gather(&taps.index, &mut pairs);
        let blended = |done: usize, values: &mut Vec<f32>, missing: &mut Vec<f32>| {
            v.blend(done, &taps, &pairs, values, missing);
            values
                .iter()
                .zip(missing.iter())
                .map(|(a, b)| (a.to_bits(), b.to_bits()))
                .collect::<Vec<_>>()
        };
        let (mut values, mut missing) = (vec![7.0; cols.len()], vec![7.0; cols.len()]);
        assert_eq!(blended(0, &mut values, &mut missing), expected);
        #[cfg(target_arch = "x86_64")]
        if let Some(simd) = pulp::x86::V3::try_new() {
            let (mut values, mut missing) = (vec![7.0; cols.len()], vec![7.0; cols.len()]);
            let done = v.blend_v3(simd, &taps, &pairs, &mut values, &mut missing);
            assert_eq!(done, 200);
            assert_eq!(blended(done, &mut values, &mut missing), expected);
        }
    }

    #[test]
    fn samples_bilinearly_normalised_and_rejects_invalid_taps() {
        let img = GrayImage {
            width: 3,
            height: 2,
            data: vec![0.0, 10.0, 200.0, 30.0, 40.0, 50.0],
        };
        let mask = ValidityMask {
            width: 3,
            height: 2,
            valid: vec![true, true, false, true, true, true],
        };
        let v = CameraView::new(&img, Some(&mask), 1).unwrap();
        // Statistics over the 5 valid pixels: mean 26, variance 344.
        assert!((v.mean - 26.0).abs() < 1e-4);
        assert!((v.inv_std - 1.0 / 344f32.sqrt()).abs() < 1e-6);
        let norm = |g: f32| (g - 26.0) / 344f32.sqrt();
        assert!((v.sample(0.0, 0.0).unwrap() - norm(0.0)).abs() < 1e-5);
        assert!(
            v.sample(1.0, 0.0).is_none(),
            "the block at x = 1 touches the invalid pixel"
        );
        let mid = v.sample(0.5, 0.5).unwrap();
        assert!((mid - norm(20.0)).abs() < 1e-4);
        let q = v.sample(0.25, 0.0).unwrap();
        assert!((q - norm(2.5)).abs() < 1e-4);
        assert!(v.sample(-0.1, 0.0).is_none());
        assert!(v.sample(0.0, 1.0).is_none(), "last row has no block below");
        let bad = ValidityMask {
            width: 2,
            height: 2,
            valid: vec![true; 4],
        };
        assert!(CameraView::new(&img, Some(&bad), 2).is_err());
    }
}
