//! Bilinear sampling: every bilinear read, warp and resize of the workspace goes through this
//! module.
//!
//! Pixel centres are at integer positions (`(0, 0)` is the centre of the top-left pixel). The
//! functions differ in what happens at the border (zero padding, "missing", clamping) and in
//! the order of their floating-point operations, which is part of their contract: each one
//! reproduces, to the bit, the reference computation it stands for (PyTorch's `grid_sample`
//! and `interpolate`, or the classical pipeline's texel blend), so that lookup tables, sweeps
//! and network outputs stay byte-identical whichever caller uses them.
//!
//! * [`BilinearTap`]: the four neighbours of one sample and their weights, zero padding
//!   ([`BilinearTap::from_pixel`] in `f64`, [`BilinearTap::grid_sample`] in `f32` as PyTorch
//!   computes it); [`BilinearTap::apply`] blends a plane.
//! * [`lerp_2d`] and [`mix_2d`]: the blend of four known neighbours, as nested linear
//!   interpolations (`a + t (b - a)`) or as weighted sums (`a (1 - t) + b t`).
//! * [`sample_inside`], [`sample_inside_f64`], [`sample_channels_inside`]: a sample only where
//!   all four neighbours are inside.
//! * [`grid_sample_plane`]: a plane sampled at normalised positions, with what is missing.
//! * [`upsample_half_pixel`] and [`resize_align_corners`]: whole-image resizes.

use rayon::prelude::*;

use crate::GrayImage;

/// The four neighbours of a sample position and their bilinear weights; a
/// neighbour outside the source image has weight 0 (and index 0).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BilinearTap {
    /// Row-major indices into the source plane: top-left, top-right,
    /// bottom-left, bottom-right.
    pub index: [u32; 4],
    /// Bilinear weights; zero for neighbours outside the source.
    pub weight: [f32; 4],
}

impl BilinearTap {
    /// The tap of a fractional source pixel `(col, row)` in an image of
    /// `width x height`, the fractions computed in `f64`, the weights as
    /// `(1 - fx) (1 - fy)`, ... in `f32`. Non-finite positions give an empty tap.
    pub fn from_pixel(col: f64, row: f64, width: usize, height: usize) -> Self {
        if !(col.is_finite() && row.is_finite()) {
            return Self::default();
        }
        let x0 = col.floor();
        let y0 = row.floor();
        let fx = (col - x0) as f32;
        let fy = (row - y0) as f32;
        let (x0, y0) = (x0 as i64, y0 as i64);
        Self::from_corners(
            x0,
            y0,
            [
                (1.0 - fx) * (1.0 - fy),
                fx * (1.0 - fy),
                (1.0 - fx) * fy,
                fx * fy,
            ],
            width,
            height,
        )
    }

    /// The tap of a position normalised as in the lookup table
    /// (`x = col/(width-1)*2-1`, `y = row/(height-1)*2-1`), through [`Self::from_pixel`].
    pub fn from_normalized(x: f32, y: f32, width: usize, height: usize) -> Self {
        let col = (f64::from(x) + 1.0) / 2.0 * (width as f64 - 1.0);
        let row = (f64::from(y) + 1.0) / 2.0 * (height as f64 - 1.0);
        Self::from_pixel(col, row, width, height)
    }

    /// The tap of the normalised position `(x, y)` in a `height x width` source, computed in
    /// `f32` with the same formulas as PyTorch's `grid_sample` (bilinear, zero padding,
    /// `align_corners=True`). Non-finite positions give an empty tap.
    #[inline]
    pub fn grid_sample(x: f32, y: f32, height: usize, width: usize) -> Self {
        let ix = (x + 1.0) / 2.0 * (width as f32 - 1.0);
        let iy = (y + 1.0) / 2.0 * (height as f32 - 1.0);
        if !(ix.is_finite() && iy.is_finite()) {
            return Self::default();
        }
        let ix_nw = floor(ix);
        let iy_nw = floor(iy);
        let (dx, dy) = (ix - ix_nw, iy - iy_nw);
        let (ex, ey) = (ix_nw + 1.0 - ix, iy_nw + 1.0 - iy);
        // The corners' columns and rows as integers (the floors are whole numbers, and any
        // beyond an i32 lies outside the source either way): the same tests as in `f32`.
        let (x0, y0) = (ix_nw as i64, iy_nw as i64);
        Self::from_corners(x0, y0, [ex * ey, dx * ey, ex * dy, dx * dy], width, height)
    }

    /// The corners `(x0, y0)`, `(x0 + 1, y0)`, `(x0, y0 + 1)`, `(x0 + 1, y0 + 1)` with their
    /// weights, those outside the source left empty.
    #[inline]
    fn from_corners(x0: i64, y0: i64, weight: [f32; 4], width: usize, height: usize) -> Self {
        let mut tap = Self::default();
        let (width, height) = (width as i64, height as i64);
        let corners = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)];
        for (k, (cx, cy)) in corners.into_iter().enumerate() {
            if (0..width).contains(&cx) && (0..height).contains(&cy) {
                tap.index[k] = (cy * width + cx) as u32;
                tap.weight[k] = weight[k];
            }
        }
        tap
    }

    /// Whether every weight is zero (the sample lies entirely outside).
    pub fn is_empty(&self) -> bool {
        self.weight == [0.0; 4]
    }

    /// The sum of the weights: 1 inside, less where neighbours lie outside.
    pub fn seen_weight(&self) -> f32 {
        self.weight.iter().sum()
    }

    /// The blended value from a source plane (a sum from 0 in corner order).
    #[inline]
    pub fn apply(&self, plane: &[f32]) -> f32 {
        let mut acc = 0.0;
        for k in 0..4 {
            acc += self.weight[k] * plane[self.index[k] as usize];
        }
        acc
    }
}

/// `value.floor()` for a finite `value`, without a call: the default x86-64 target has no
/// rounding instruction, so `f32::floor` is a library function, and the cascade takes
/// millions of taps a frame. Truncation toward zero, one less where that rounded up; exact for
/// every finite value whose floor fits an `i32`. Beyond that both answers lie outside any
/// image, so the taps they give are the same (empty).
#[inline]
fn floor(value: f32) -> f32 {
    let truncated = value as i32 as f32;
    if truncated > value {
        truncated - 1.0
    } else {
        truncated
    }
}

/// Bilinear sample of a row-major plane at fractional `(col, row)`, zero
/// outside (the align-corners convention: pixel centres at integers).
pub fn sample_bilinear(plane: &[f32], width: usize, height: usize, col: f64, row: f64) -> f32 {
    BilinearTap::from_pixel(col, row, width, height).apply(plane)
}

/// The blend of the neighbours `a b / c d` (top-left, top-right, bottom-left, bottom-right)
/// at fractions `(fx, fy)` as nested linear interpolations, `top = a + fx (b - a)`, then
/// `top + fy (bottom - top)`: the classical pipeline's texel blend.
#[inline]
pub fn lerp_2d([a, b, c, d]: [f32; 4], fx: f32, fy: f32) -> f32 {
    let top = a + fx * (b - a);
    let bottom = c + fx * (d - c);
    top + fy * (bottom - top)
}

/// The blend of the neighbours `a b / c d` at fractions `(fx, fy)` as weighted sums,
/// `top = a (1 - fx) + b fx`, then `top (1 - fy) + bottom fy`: PyTorch's `interpolate`.
#[inline]
pub fn mix_2d([a, b, c, d]: [f32; 4], fx: f32, fy: f32) -> f32 {
    let top = a * (1.0 - fx) + b * fx;
    let bottom = c * (1.0 - fx) + d * fx;
    top * (1.0 - fy) + bottom * fy
}

/// The top-left corner and the fractions of a sample at `(col, row)` whose four neighbours
/// all lie inside a `width x height` image; `None` otherwise (and for NaN or infinite
/// positions: `as` saturates, so no `+ 1` can wrap).
#[inline]
pub fn inside_corner(col: f32, row: f32, width: usize, height: usize) -> Option<(usize, f32, f32)> {
    if !(col >= 0.0 && row >= 0.0) {
        return None;
    }
    let (x0, y0) = (col as usize, row as usize);
    if x0 >= width.saturating_sub(1) || y0 >= height.saturating_sub(1) {
        return None;
    }
    Some((y0 * width + x0, col - x0 as f32, row - y0 as f32))
}

/// [`lerp_2d`] of a plane at `(col, row)`, `None` unless the four neighbours are inside.
#[inline]
pub fn sample_inside(
    plane: &[f32],
    width: usize,
    height: usize,
    col: f32,
    row: f32,
) -> Option<f32> {
    let (i, fx, fy) = inside_corner(col, row, width, height)?;
    let j = i + width;
    Some(lerp_2d(
        [plane[i], plane[i + 1], plane[j], plane[j + 1]],
        fx,
        fy,
    ))
}

/// Bilinear value of an image at `(col, row)` in `f64`, `None` unless the four neighbours
/// are inside: `a (1 - fc) (1 - fr) + b fc (1 - fr) + c (1 - fc) fr + d fc fr`.
pub fn sample_inside_f64(image: &GrayImage, col: f64, row: f64) -> Option<f64> {
    let (c0, r0) = (col.floor(), row.floor());
    if c0 < 0.0 || r0 < 0.0 || c0 + 1.0 >= image.width as f64 || r0 + 1.0 >= image.height as f64 {
        return None;
    }
    let (fc, fr) = (col - c0, row - r0);
    let (c0, r0) = (c0 as usize, r0 as usize);
    let at = |r: usize, c: usize| f64::from(image.data[r * image.width + c]);
    Some(
        at(r0, c0) * (1.0 - fc) * (1.0 - fr)
            + at(r0, c0 + 1) * fc * (1.0 - fr)
            + at(r0 + 1, c0) * (1.0 - fc) * fr
            + at(r0 + 1, c0 + 1) * fc * fr,
    )
}

/// Bilinear sample of every channel of an interleaved map (`data[(y * width + x) * channels
/// + c]`) at `(x, y)` into `out`; false unless the four neighbours are inside. The weights
/// are `(1 - fx) (1 - fy)`, `fx (1 - fy)`, `(1 - fx) fy`, `fx fy`, summed in corner order.
#[inline]
pub fn sample_channels_inside(
    data: &[f32],
    [width, height, channels]: [usize; 3],
    x: f32,
    y: f32,
    out: &mut [f32],
) -> bool {
    let Some((corner, fx, fy)) = inside_corner(x, y, width, height) else {
        return false;
    };
    let c = channels;
    let i = corner * c;
    let j = i + width * c;
    let (w00, w01, w10, w11) = (
        (1.0 - fx) * (1.0 - fy),
        fx * (1.0 - fy),
        (1.0 - fx) * fy,
        fx * fy,
    );
    for (k, o) in out.iter_mut().enumerate().take(c) {
        *o = w00 * data[i + k] + w01 * data[i + c + k] + w10 * data[j + k] + w11 * data[j + c + k];
    }
    true
}

/// Samples of a `rows x cols` plane at the normalised positions `coords` (`(x, y)` pairs, as
/// [`BilinearTap::grid_sample`] reads them) and, for each, 1 where the sample is missing (its
/// neighbours inside carry less than `min_seen_weight` of the weight; its value is then 0).
///
/// A sample whose four neighbours all lie inside the plane (nearly all of them) is read
/// directly, with the weights and the sum in the order of [`BilinearTap::apply`] (the same
/// value to the bit); one a whole pixel or more outside is missing at once; the others, on the
/// border, go through the tap.
pub fn grid_sample_plane(
    coords: &[f32],
    plane: &[f32],
    rows: usize,
    cols: usize,
    min_seen_weight: f32,
) -> (Vec<f32>, Vec<f32>) {
    let (w, h) = (cols as f32 - 1.0, rows as f32 - 1.0);
    coords
        .chunks_exact(2)
        .map(|xy| {
            let ix = (xy[0] + 1.0) / 2.0 * w;
            let iy = (xy[1] + 1.0) / 2.0 * h;
            // Inside with a margin, so that truncation is the floor and all four corners are
            // in the plane; NaN fails the tests.
            if ix >= 0.0 && iy >= 0.0 && ix < w - 1.0 && iy < h - 1.0 {
                let (x0, y0) = (ix as usize, iy as usize);
                let (fx, fy) = (x0 as f32, y0 as f32);
                let (dx, dy) = (ix - fx, iy - fy);
                let (ex, ey) = (fx + 1.0 - ix, fy + 1.0 - iy);
                let i = y0 * cols + x0;
                let value = ex * ey * plane[i]
                    + dx * ey * plane[i + 1]
                    + ex * dy * plane[i + cols]
                    + dx * dy * plane[i + cols + 1];
                return (value, 0.0);
            }
            // A whole pixel or more outside (or NaN): no neighbour inside, missing, as the
            // tap would find (most of a camera's unseen samples; only the border band needs
            // it).
            if !(ix > -1.0 && iy > -1.0 && ix < w + 1.0 && iy < h + 1.0) {
                return (0.0, 1.0);
            }
            let tap = BilinearTap::grid_sample(xy[0], xy[1], rows, cols);
            if tap.seen_weight() < min_seen_weight {
                return (0.0, 1.0);
            }
            // An iterator sum, as the border band has always been summed (it starts from
            // -0.0, where `apply` starts from 0.0).
            let value: f32 = tap
                .index
                .iter()
                .zip(&tap.weight)
                .map(|(&i, &wt)| wt * plane[i as usize])
                .sum();
            (value, 0.0)
        })
        .unzip()
}

/// PyTorch's `interpolate(mode="bilinear", align_corners=False)` of `[c, h, w]` to `[c, oh,
/// ow]` (source positions clamped at the borders, no wrap).
pub fn upsample_half_pixel(input: &[f32], [c, h, w]: [usize; 3], [oh, ow]: [usize; 2]) -> Vec<f32> {
    let taps = |out: usize, len: usize| -> Vec<(usize, usize, f32)> {
        let scale = len as f64 / out as f64;
        (0..out)
            .map(|o| {
                let src = ((o as f64 + 0.5) * scale - 0.5).max(0.0);
                let i0 = (src.floor() as usize).min(len - 1);
                let i1 = (i0 + 1).min(len - 1);
                (i0, i1, (src - i0 as f64) as f32)
            })
            .collect()
    };
    let (rows, cols) = (taps(oh, h), taps(ow, w));
    let mut out = vec![0f32; c * oh * ow];
    out.par_chunks_mut(oh * ow)
        .enumerate()
        .for_each(|(ch, plane)| {
            let src = &input[ch * h * w..(ch + 1) * h * w];
            for (y, &(r0, r1, fr)) in rows.iter().enumerate() {
                for (x, &(c0, c1, fc)) in cols.iter().enumerate() {
                    let corners = [
                        src[r0 * w + c0],
                        src[r0 * w + c1],
                        src[r1 * w + c0],
                        src[r1 * w + c1],
                    ];
                    plane[y * ow + x] = mix_2d(corners, fc, fr);
                }
            }
        });
    out
}

/// Downscaling by more than this factor first smooths ([`resize_align_corners`]).
const ANTIALIAS_FACTOR: f64 = 1.5;

/// Resizes a gray image to `width x height` by bilinear interpolation with corners aligned
/// (pixel `(0, 0)` and the last pixel keep their place), so that lookup-table coordinates,
/// normalised the same way, stay valid. Downscaling by more than 1.5 first smooths with a
/// `[1, 2, 1] / 4` kernel per halving to limit aliasing.
pub fn resize_align_corners(image: &GrayImage, width: usize, height: usize) -> GrayImage {
    if image.width == width && image.height == height {
        return image.clone();
    }
    let mut src = image.clone();
    let factor = (image.width as f64 / width as f64).max(image.height as f64 / height as f64);
    let mut f = factor;
    while f > ANTIALIAS_FACTOR {
        src = blur_121(&src);
        f /= 2.0;
    }
    let scale = |from: usize, to: usize| {
        if to > 1 {
            (from as f64 - 1.0) / (to as f64 - 1.0)
        } else {
            0.0
        }
    };
    let (sx, sy) = (scale(src.width, width), scale(src.height, height));
    let mut data = Vec::with_capacity(width * height);
    for row in 0..height {
        for col in 0..width {
            data.push(src.sample(col as f64 * sx, row as f64 * sy));
        }
    }
    GrayImage {
        width,
        height,
        data,
    }
}

/// Separable `[1, 2, 1] / 4` smoothing with clamped borders.
fn blur_121(image: &GrayImage) -> GrayImage {
    let (w, h) = (image.width, image.height);
    let at = |d: &[f32], r: usize, c: usize| d[r * w + c];
    let mut tmp = vec![0f32; w * h];
    for r in 0..h {
        for c in 0..w {
            let l = at(&image.data, r, c.saturating_sub(1));
            let m = at(&image.data, r, c);
            let rr = at(&image.data, r, (c + 1).min(w - 1));
            tmp[r * w + c] = 0.25 * l + 0.5 * m + 0.25 * rr;
        }
    }
    let mut data = vec![0f32; w * h];
    for r in 0..h {
        for c in 0..w {
            let u = at(&tmp, r.saturating_sub(1), c);
            let m = at(&tmp, r, c);
            let d = at(&tmp, (r + 1).min(h - 1), c);
            data[r * w + c] = 0.25 * u + 0.5 * m + 0.25 * d;
        }
    }
    GrayImage {
        width: w,
        height: h,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_interpolates_and_pads_with_zero() {
        // 2x2 image [[1, 2], [3, 4]].
        let img = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(sample_bilinear(&img, 2, 2, 0.0, 0.0), 1.0);
        assert_eq!(sample_bilinear(&img, 2, 2, 1.0, 1.0), 4.0);
        assert!((sample_bilinear(&img, 2, 2, 0.5, 0.5) - 2.5).abs() < 1e-6);
        // Half a pixel left of the image: half the weight is outside (zero).
        assert!((sample_bilinear(&img, 2, 2, -0.5, 0.0) - 0.5).abs() < 1e-6);
        assert_eq!(sample_bilinear(&img, 2, 2, -1e5, 0.0), 0.0);
        assert_eq!(sample_bilinear(&img, 2, 2, f64::NAN, 0.0), 0.0);
    }

    #[test]
    fn normalized_corners_hit_corner_pixels() {
        let t = BilinearTap::from_normalized(-1.0, -1.0, 800, 768);
        assert_eq!(t.index[0], 0);
        assert!((t.weight[0] - 1.0).abs() < 1e-6);
        let t = BilinearTap::from_normalized(1.0, 1.0, 800, 768);
        assert_eq!(t.index[0], 800 * 768 - 1);
        assert!((t.weight[0] - 1.0).abs() < 1e-4);
    }

    #[test]
    fn the_inline_floor_is_f32_floor_on_finite_values() {
        // Integers, halves, values just off an integer, both signs, the ends of f32's exact
        // integers and beyond.
        let mut values = vec![
            0.0f32,
            1.0,
            -1.0,
            0.5,
            -0.5,
            1e-7,
            -1e-7,
            16_777_216.0,
            -16_777_217.0,
        ];
        for i in -3000..3000 {
            let v = i as f32 * 0.37;
            values.extend([
                v,
                v.next_up(),
                v.next_down(),
                v.round(),
                v.round().next_down(),
            ]);
        }
        for v in values {
            assert_eq!(floor(v), v.floor(), "{v}");
        }
        // Beyond an i32 the two differ, and both corners lie outside: the same (empty) taps.
        for x in [3e9f32, -3e9, 1e30, -1e30] {
            assert!(BilinearTap::grid_sample(x, 0.0, 768, 800).is_empty(), "{x}");
            assert!(BilinearTap::grid_sample(0.0, x, 768, 800).is_empty(), "{x}");
        }
    }

    #[test]
    fn taps_interpolate_inside_and_drop_outside_neighbours() {
        // 3 x 5 source; x = 0 is column 2, y = 0 is row 1 exactly.
        let taps = BilinearTap::grid_sample(0.0, 0.0, 3, 5);
        assert_eq!(taps.index[0], 7);
        assert!((taps.weight[0] - 1.0).abs() < 1e-6);
        assert!(taps.weight[1..].iter().all(|w| w.abs() < 1e-6));
        // Halfway between columns 3 and 4 of the last row: the south neighbours are outside.
        let taps = BilinearTap::grid_sample(0.75, 1.0, 3, 5);
        assert_eq!(&taps.index[..2], &[13, 14]);
        assert!((taps.weight[0] - 0.5).abs() < 1e-6 && (taps.weight[1] - 0.5).abs() < 1e-6);
        assert_eq!(&taps.weight[2..], &[0.0, 0.0]);
        // The reference marks invalid entries with a pixel of -1e5.
        assert!(BilinearTap::grid_sample(-1e5, 0.0, 3, 5).is_empty());
        assert!(BilinearTap::grid_sample(f32::NAN, 0.0, 3, 5).is_empty());
    }

    #[test]
    fn resize_keeps_corners_and_linear_ramps() {
        let (w, h) = (9, 5);
        let data = (0..h)
            .flat_map(|r| (0..w).map(move |c| (2 * c + 3 * r) as f32))
            .collect();
        let image = GrayImage {
            width: w,
            height: h,
            data,
        };
        // 9x5 -> 7x4 (factor < 1.5, no smoothing): corners keep their place and a
        // linear ramp stays linear under bilinear sampling.
        let near = resize_align_corners(&image, 7, 4);
        assert!((near.data[0] - image.data[0]).abs() < 1e-4);
        assert!((near.data[7 * 4 - 1] - image.data[w * h - 1]).abs() < 1e-4);
        let want = 2.0 * 4.0 + 3.0 * (2.0 * 4.0 / 3.0);
        assert!((near.data[2 * 7 + 3] - want).abs() < 1e-4);
        // 9x5 -> 5x3 smooths with [1, 2, 1] first, which is exact on a ramp away
        // from the clamped borders.
        let small = resize_align_corners(&image, 5, 3);
        assert!((small.data[5 + 2] - (2.0 * 4.0 + 3.0 * 2.0)).abs() < 1e-4);
        let same = resize_align_corners(&image, w, h);
        assert_eq!(same, image);
    }
}
