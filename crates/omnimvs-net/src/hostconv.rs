//! 2D and 3D convolutions on the host, for inference on a CPU.
//!
//! burn's `flex` backend runs a 2D convolution as a 3D one: it copies the whole input to
//! channels-last order on one thread, builds each im2col tile with a bounds check per tap and
//! channel, multiplies, then scatters the product back element by element. With the few
//! channels of the cascade (8 to 96) those copies cost more than the multiplication: in a
//! `perf` profile of `omnimvs infer` the convolution took about 30 % of the samples,
//! of which the GEMM kernels were under half. Here each im2col row (one input channel and one
//! kernel tap over a band of output rows) is copied from the channels-first input in runs,
//! the band's output starts as the bias, the GEMM adds into it, and the residual and ReLU
//! follow while the band is in cache. The panorama's longitude wrap is part of the
//! addressing ([`Padding::wrap_cols`]), so it needs no concatenated copy of the input.
//!
//! The values are those of the convolution the layer describes, summed in another order: a
//! test compares them with burn's to 1e-4 relative. No gradient: training keeps burn's
//! modules ([`HostConv::from_conv`] reads a trained, batch-norm-folded layer).

use std::marker::PhantomData;

use burn::module::Param;
use burn::nn::conv::{Conv2d, Conv3d};
use burn::nn::{PaddingConfig2d, PaddingConfig3d};
use burn::tensor::{Device, Tensor, TensorData};
use rayon::prelude::*;

use crate::error::NetError;
use crate::tensor::read_values;

/// Padding of a host convolution: zero rows above and below; zero columns left and right, or
/// the columns of the other side when they wrap around (a panorama's longitude).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Padding {
    /// Rows added above and below.
    pub rows: usize,
    /// Columns added left and right.
    pub cols: usize,
    /// Whether the added columns come from the other side (circular) instead of zeros.
    pub wrap_cols: bool,
}

/// Floats of im2col a band aims at (1 MiB: within a core's L2 cache with the GEMM's packing).
const BAND_FLOATS: usize = 1 << 18;

/// A 2D or 3D convolution (one group) with its weights laid out for the GEMM. A 2D one is a
/// 3D one of depth 1: its sizes are `[depth, rows, columns]` with depth 1 throughout.
#[derive(Clone, Debug)]
pub struct HostConv {
    c_in: usize,
    c_out: usize,
    /// `[kd, kh, kw]`.
    kernel: [usize; 3],
    /// Along depth, rows, columns.
    stride: [usize; 3],
    /// Along depth, rows, columns.
    dilation: [usize; 3],
    /// Zero planes added before and after along depth.
    depth_pad: usize,
    padding: Padding,
    /// `[c_out, c_in * kd * kh * kw]`, row-major: burn's `[O, I, (kd,) kh, kw]` as it is.
    weight: Vec<f32>,
    /// `[c_out]` (zeros without a bias).
    bias: Vec<f32>,
}

/// Sizes of one call: input `[batch, c_in, d, h, w]`, output `[batch, c_out, od, oh, ow]`.
#[derive(Clone, Copy, Debug)]
struct Sizes {
    d: usize,
    h: usize,
    w: usize,
    oh: usize,
    ow: usize,
}

impl HostConv {
    /// The host form of a burn convolution `conv` (its batch norm, if any, folded in first),
    /// with its own padding; `extra_cols` more columns each side, wrapping around when
    /// `wrap_cols` (the panorama's circular padding, applied before `conv` in the tensor
    /// path). `None` when the layer is of a kind this kernel does not run (groups, uneven
    /// padding, `Same`): the caller keeps burn's path.
    pub fn from_conv(conv: &Conv2d, extra_cols: usize, wrap_cols: bool) -> Option<Self> {
        if conv.groups != 1 {
            return None;
        }
        let (rows, cols) = match conv.padding {
            PaddingConfig2d::Valid => (0, 0),
            PaddingConfig2d::Explicit(top, left, bottom, right)
                if top == bottom && left == right =>
            {
                (top, left)
            }
            _ => return None,
        };
        // Zero columns inside wrapped ones would need a second padding stage.
        if wrap_cols && cols != 0 {
            return None;
        }
        let [c_out, c_in, kh, kw] = conv.weight.val().dims();
        let (weight, bias) = weights_and_bias(conv.weight.val(), conv.bias.as_ref(), c_out)?;
        Self::new(
            [c_in, c_out],
            [kh, kw],
            conv.stride,
            conv.dilation,
            Padding {
                rows,
                cols: cols + extra_cols,
                wrap_cols,
            },
            weight,
            bias,
        )
        .ok()
    }

    /// The host form of a burn 3D convolution `conv` (its batch norm, if any, folded in
    /// first), with its own zero padding. `None` for groups or `Same` padding (burn's path).
    pub fn from_conv3d(conv: &Conv3d) -> Option<Self> {
        if conv.groups != 1 {
            return None;
        }
        let [pd, ph, pw] = match conv.padding {
            PaddingConfig3d::Valid => [0; 3],
            PaddingConfig3d::Explicit(d, h, w) => [d, h, w],
            _ => return None,
        };
        let [c_out, c_in, kd, kh, kw] = conv.weight.val().dims();
        let (weight, bias) = weights_and_bias(conv.weight.val(), conv.bias.as_ref(), c_out)?;
        Self::build(
            [c_in, c_out],
            [kd, kh, kw],
            conv.stride,
            conv.dilation,
            pd,
            Padding {
                rows: ph,
                cols: pw,
                wrap_cols: false,
            },
            weight,
            bias,
        )
        .ok()
    }

    /// A 2D convolution from its weights `[c_out, c_in, kh, kw]` (row-major) and bias.
    ///
    /// # Errors
    /// [`NetError::Shape`] when the weights or the bias do not have the sizes given, or a
    /// size, stride or dilation is zero.
    pub fn new(
        channels: [usize; 2],
        kernel: [usize; 2],
        stride: [usize; 2],
        dilation: [usize; 2],
        padding: Padding,
        weight: Vec<f32>,
        bias: Vec<f32>,
    ) -> Result<Self, NetError> {
        Self::build(
            channels,
            [1, kernel[0], kernel[1]],
            [1, stride[0], stride[1]],
            [1, dilation[0], dilation[1]],
            0,
            padding,
            weight,
            bias,
        )
    }

    #[allow(clippy::too_many_arguments)]
    fn build(
        channels: [usize; 2],
        kernel: [usize; 3],
        stride: [usize; 3],
        dilation: [usize; 3],
        depth_pad: usize,
        padding: Padding,
        weight: Vec<f32>,
        bias: Vec<f32>,
    ) -> Result<Self, NetError> {
        let [c_in, c_out] = channels;
        if [c_in, c_out].contains(&0)
            || kernel.contains(&0)
            || stride.contains(&0)
            || dilation.contains(&0)
        {
            return Err(shape_error(
                "channels, kernel, stride and dilation (none zero)",
                [&channels[..], &kernel[..]].concat(),
                [&stride[..], &dilation[..]].concat(),
            ));
        }
        let taps: usize = kernel.iter().product();
        if weight.len() != c_out * c_in * taps {
            return Err(shape_error(
                "weights",
                [&[c_out, c_in][..], &kernel[..]].concat(),
                vec![weight.len()],
            ));
        }
        if bias.len() != c_out {
            return Err(shape_error("bias", vec![c_out], vec![bias.len()]));
        }
        Ok(Self {
            c_in,
            c_out,
            kernel,
            stride,
            dilation,
            depth_pad,
            padding,
            weight,
            bias,
        })
    }

    /// Output channels.
    pub fn out_channels(&self) -> usize {
        self.c_out
    }

    /// The output's depth, rows and columns for an input of `d x h x w`, `None` when the
    /// kernel does not fit (or a wrap is wider than the input).
    fn output_size3(&self, d: usize, h: usize, w: usize) -> Option<[usize; 3]> {
        let span = |axis: usize, size: usize, pad: usize| {
            let padded = size + 2 * pad;
            let reach = self.dilation[axis] * (self.kernel[axis] - 1) + 1;
            (padded >= reach).then(|| (padded - reach) / self.stride[axis] + 1)
        };
        if self.padding.wrap_cols && self.padding.cols > w {
            return None;
        }
        Some([
            span(0, d, self.depth_pad)?,
            span(1, h, self.padding.rows)?,
            span(2, w, self.padding.cols)?,
        ])
    }

    /// The output's rows and columns for an input of `h x w` (a 2D convolution), `None` when
    /// the kernel does not fit (or a wrap is wider than the input).
    pub fn output_size(&self, h: usize, w: usize) -> Option<[usize; 2]> {
        self.output_size3(1, h, w).map(|[_, oh, ow]| [oh, ow])
    }

    /// Runs a 2D convolution on `input` `[batch, c_in, h, w]` (row-major), adds `residual`
    /// (`[batch, c_out, oh, ow]`) when given, then a ReLU when `relu`: `[batch, c_out, oh,
    /// ow]` and `[oh, ow]`.
    ///
    /// # Errors
    /// [`NetError::Shape`] when the input or the residual do not have the sizes given, or the
    /// kernel does not fit the input.
    pub fn forward(
        &self,
        input: &[f32],
        dims: [usize; 4],
        residual: Option<&[f32]>,
        relu: bool,
    ) -> Result<(Vec<f32>, [usize; 2]), NetError> {
        let [batch, c_in, h, w] = dims;
        let (out, [_, oh, ow]) = self.forward3d(input, [batch, c_in, 1, h, w], residual, relu)?;
        Ok((out, [oh, ow]))
    }

    /// [`HostConv::forward`] for a 3D convolution: `input` `[batch, c_in, d, h, w]`, output
    /// `[batch, c_out, od, oh, ow]` and `[od, oh, ow]`.
    ///
    /// # Errors
    /// [`NetError::Shape`] when the input or the residual do not have the sizes given, or the
    /// kernel does not fit the input.
    pub fn forward3d(
        &self,
        input: &[f32],
        dims: [usize; 5],
        residual: Option<&[f32]>,
        relu: bool,
    ) -> Result<(Vec<f32>, [usize; 3]), NetError> {
        let [batch, c_in, d, h, w] = dims;
        if c_in != self.c_in || input.len() != batch * c_in * d * h * w {
            return Err(shape_error(
                "input",
                vec![batch, self.c_in, d, h, w],
                vec![input.len()],
            ));
        }
        let Some([od, oh, ow]) = self.output_size3(d, h, w) else {
            return Err(shape_error(
                "input size for the kernel",
                self.kernel.to_vec(),
                vec![d, h, w],
            ));
        };
        let plane = od * oh * ow;
        if let Some(r) = residual
            && r.len() != batch * self.c_out * plane
        {
            return Err(shape_error(
                "residual",
                vec![batch, self.c_out, od, oh, ow],
                vec![r.len()],
            ));
        }
        let sizes = Sizes { d, h, w, oh, ow };
        // Output rows of all depths in one run: row `r` is depth `r / oh`, row `r % oh`.
        let out_rows = od * oh;
        let k = self.c_in * self.kernel.iter().product::<usize>();
        let band_rows = (BAND_FLOATS / (k * ow).max(1)).clamp(1, out_rows);
        let bands_per_image = out_rows.div_ceil(band_rows);
        let in_image = c_in * d * h * w;
        let out_image = self.c_out * plane;
        let mut out = vec![0.0f32; batch * out_image];
        // Every band of every image on its own, written where it belongs in the output (no
        // band buffers, no copies after them).
        let total = batch * bands_per_image;
        let dst = OutputBase::new(&mut out);
        (0..total).into_par_iter().for_each(|i| {
            let (b, band) = (i / bands_per_image, i % bands_per_image);
            let row0 = band * band_rows;
            let rows = band_rows.min(out_rows - row0);
            let image = &input[b * in_image..(b + 1) * in_image];
            let res = residual.map(|r| &r[b * out_image..(b + 1) * out_image]);
            let rows_of = BandRows {
                first: b * out_image + row0 * ow,
                len: rows * ow,
                channel_stride: plane,
            };
            self.band(image, sizes, row0, rows, res, relu, dst, rows_of);
        });
        Ok((out, [od, oh, ow]))
    }

    /// Output rows `row0 .. row0 + rows` (over all depths) of one image into `dst`, at
    /// `rows_of`: the band's `[c_out, rows * ow]` values, channels `plane` apart.
    #[allow(clippy::too_many_arguments)]
    fn band(
        &self,
        image: &[f32],
        s: Sizes,
        row0: usize,
        rows: usize,
        residual: Option<&[f32]>,
        relu: bool,
        dst: OutputBase<'_>,
        rows_of: BandRows,
    ) {
        let n = rows * s.ow;
        let direct = self.kernel == [1, 1, 1]
            && self.stride == [1, 1, 1]
            && self.depth_pad == 0
            && self.padding.rows == 0
            && self.padding.cols == 0;
        for (o, &b) in self.bias.iter().enumerate() {
            // SAFETY: `rows_of` is this band's (`forward3d`), one channel's slice at a time.
            #[allow(unsafe_code)]
            unsafe { dst.channel(rows_of, o) }.fill(b);
        }
        if direct {
            // A 1x1 convolution reads the input's rows as they are: one copy per channel.
            let mut col = Vec::with_capacity(self.c_in * n);
            let volume = s.d * s.h * s.w;
            for c in 0..self.c_in {
                let at = c * volume + row0 * s.w;
                col.extend_from_slice(&image[at..at + n]);
            }
            gemm_add(self.c_out, n, self.c_in, &self.weight, &col, dst, rows_of);
        } else {
            let col = self.im2col(image, s, row0, rows);
            let k = self.c_in * self.kernel.iter().product::<usize>();
            gemm_add(self.c_out, n, k, &self.weight, &col, dst, rows_of);
        }
        for o in 0..self.c_out {
            // SAFETY: as for the bias above; `gemm_add` has returned.
            #[allow(unsafe_code)]
            let chunk = unsafe { dst.channel(rows_of, o) };
            if let Some(r) = residual {
                let plane = r.len() / self.c_out;
                let at = o * plane + row0 * s.ow;
                for (v, r) in chunk.iter_mut().zip(&r[at..at + n]) {
                    *v += r;
                }
            }
            if relu {
                for v in chunk.iter_mut() {
                    *v = v.max(0.0);
                }
            }
        }
    }

    /// The im2col matrix of output rows `row0 .. row0 + rows` (over all depths):
    /// `[c_in * kd * kh * kw, rows * ow]`, a row per input channel and tap.
    fn im2col(&self, image: &[f32], s: Sizes, row0: usize, rows: usize) -> Vec<f32> {
        let [kd, kh, kw] = self.kernel;
        let [sd, sh, sw] = self.stride;
        let [dd, dh, dw] = self.dilation;
        let (pd, ph, pw) = (self.depth_pad, self.padding.rows, self.padding.cols);
        let n = rows * s.ow;
        let mut col = vec![0.0f32; self.c_in * kd * kh * kw * n];
        let volume = s.d * s.h * s.w;
        let mut at = 0;
        for c in 0..self.c_in {
            let channel = &image[c * volume..(c + 1) * volume];
            for kz in 0..kd {
                for ky in 0..kh {
                    for kx in 0..kw {
                        let dst_row = &mut col[at..at + n];
                        at += n;
                        for r in 0..rows {
                            let (oz, oy) = ((row0 + r) / s.oh, (row0 + r) % s.oh);
                            let iz = (oz * sd + kz * dd) as isize - pd as isize;
                            let iy = (oy * sh + ky * dh) as isize - ph as isize;
                            if iz < 0 || iz >= s.d as isize || iy < 0 || iy >= s.h as isize {
                                continue; // zero rows (already zero)
                            }
                            let from = (iz as usize * s.h + iy as usize) * s.w;
                            let src = &channel[from..from + s.w];
                            let dst = &mut dst_row[r * s.ow..(r + 1) * s.ow];
                            // Input column of output column `ox`: `ox * sw + offset - pw`.
                            self.copy_columns(src, dst, kx * dw, sw, pw);
                        }
                    }
                }
            }
        }
        col
    }

    /// `dst[ox] = src[ox * stride + offset - pad]`, zero or wrapped outside `src`.
    fn copy_columns(&self, src: &[f32], dst: &mut [f32], offset: usize, stride: usize, pad: usize) {
        let w = src.len() as isize;
        let shift = offset as isize - pad as isize;
        if stride == 1 {
            // Output columns whose input lies inside `src`: one run.
            let first = (-shift).clamp(0, dst.len() as isize) as usize;
            let end = (w - shift).clamp(first as isize, dst.len() as isize) as usize;
            if end > first {
                let from = (first as isize + shift) as usize;
                dst[first..end].copy_from_slice(&src[from..from + (end - first)]);
            }
            if self.padding.wrap_cols {
                let len = dst.len();
                for ox in (0..first).chain(end..len) {
                    dst[ox] = src[(ox as isize + shift).rem_euclid(w) as usize];
                }
            }
        } else {
            for (ox, v) in dst.iter_mut().enumerate() {
                let ix = (ox * stride) as isize + shift;
                if (0..w).contains(&ix) {
                    *v = src[ix as usize];
                } else if self.padding.wrap_cols {
                    *v = src[ix.rem_euclid(w) as usize];
                }
            }
        }
    }
}

/// The values of one band in a convolution's output: `len` values of each output channel,
/// the first channel's from `first`, the next ones `channel_stride` further each.
#[derive(Clone, Copy, Debug)]
struct BandRows {
    first: usize,
    len: usize,
    channel_stride: usize,
}

/// The start of a convolution's output `Vec`, shared by the bands that fill it in parallel.
///
/// Each band writes only its own [`BandRows`]: the rows of one image that no other band
/// has (bands cut an image's output rows into disjoint ranges, and images lie apart), inside
/// the output (`HostConv::forward3d` sizes it as every image's channels times their rows).
/// So no two threads ever touch the same value, and the `Vec` is neither read nor moved
/// while the bands run (`forward3d` waits for all of them).
#[derive(Clone, Copy)]
struct OutputBase<'a> {
    ptr: *mut f32,
    /// The output's length: every range handed out is checked against it.
    len: usize,
    _out: PhantomData<&'a mut [f32]>,
}

// SAFETY: the pointer is only used as described on `OutputBase`: disjoint writes from the
// bands of one `forward3d` call, which holds the output borrowed for `'a`.
#[allow(unsafe_code)]
unsafe impl Send for OutputBase<'_> {}
// SAFETY: as for `Send`.
#[allow(unsafe_code)]
unsafe impl Sync for OutputBase<'_> {}

impl<'a> OutputBase<'a> {
    /// The base of `out`, borrowed for as long as bands write into it.
    fn new(out: &'a mut [f32]) -> Self {
        Self {
            ptr: out.as_mut_ptr(),
            len: out.len(),
            _out: PhantomData,
        }
    }

    /// Whether `channels` rows of the band `rows` lie inside the output.
    fn holds(self, rows: BandRows, channels: usize) -> bool {
        channels == 0
            || (channels - 1)
                .checked_mul(rows.channel_stride)
                .and_then(|at| at.checked_add(rows.first))
                .and_then(|at| at.checked_add(rows.len))
                .is_some_and(|end| end <= self.len)
    }

    /// The band's values of output channel `o`.
    ///
    /// # Safety
    /// `rows` must be the calling band's own (see [`OutputBase`]), and the caller must hold no
    /// other slice of them while it uses this one. (That the range lies inside the output is
    /// asserted here.)
    #[allow(unsafe_code)]
    unsafe fn channel(self, rows: BandRows, o: usize) -> &'a mut [f32] {
        assert!(self.holds(rows, o + 1), "band rows outside the output");
        // SAFETY: inside the output (asserted above); the band's own, one slice at a time (the
        // caller's contract).
        unsafe {
            std::slice::from_raw_parts_mut(
                self.ptr.add(rows.first + o * rows.channel_stride),
                rows.len,
            )
        }
    }
}

/// `c[m, n] += a[m, k] b[k, n]` on this thread, `a` and `b` row-major and contiguous, `c` the
/// band `rows` of the output at `dst` (its row `i` channel `i`'s values).
fn gemm_add(
    m: usize,
    n: usize,
    k: usize,
    a: &[f32],
    b: &[f32],
    dst: OutputBase<'_>,
    rows: BandRows,
) {
    assert!(
        a.len() >= m * k && b.len() >= k * n && rows.len == n && dst.holds(rows, m),
        "gemm_add: slices shorter than {m}x{k} and {k}x{n}, or a band of {} values, not {n}, \
         or {m} rows of it outside the output",
        rows.len
    );
    if m == 0 || n == 0 || k == 0 {
        return;
    }
    // SAFETY: the assertion above keeps every element `gemm` reads (`a`: m x k, row stride k;
    // `b`: k x n, row stride n) inside its slice, and the m rows of n values it writes, row `i`
    // at `rows.first + i * rows.channel_stride`, inside the output: the band's own values
    // (`OutputBase`), which alias neither input (those are borrowed, the output is the `Vec`
    // being filled); one thread (`Parallelism::None`).
    #[allow(unsafe_code)]
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            dst.ptr.add(rows.first),
            1,
            rows.channel_stride as isize,
            true,
            a.as_ptr(),
            1,
            k as isize,
            b.as_ptr(),
            1,
            n as isize,
            1.0f32,
            1.0f32,
            false,
            false,
            false,
            gemm::Parallelism::None,
        );
    }
}

/// The inputs of [`host_forward`] handed back when the host kernel does not take them: the
/// caller runs burn's path on them instead.
pub type Declined<const D: usize> = Box<(Tensor<D>, Option<Tensor<D>>)>;

/// `host` on a tensor `[B, C_in, H, W]` (a 2D convolution) or `[B, C_in, D, H, W]` (3D), plus
/// `residual` of the output's shape when given, then a ReLU when `relu`: the output on the
/// input's device.
///
/// The tensors are taken by value: a tensor that holds its values alone hands them over
/// without a copy (a clone kept by the caller would make burn copy them, twice for `f32`).
///
/// # Errors
/// The inputs back ([`Declined`]) when the tensor has another rank, or its values do not read
/// as `f32` or do not fit the kernel: the callers then take burn's path.
pub fn host_forward<const D: usize>(
    host: &HostConv,
    x: Tensor<D>,
    residual: Option<Tensor<D>>,
    relu: bool,
) -> Result<Tensor<D>, Declined<D>> {
    let device = x.device();
    let dims = x.dims();
    // A 2D map is a volume of depth 1.
    let volume = match *dims.as_slice() {
        [b, c, h, w] => [b, c, 1, h, w],
        [b, c, d, h, w] => [b, c, d, h, w],
        _ => return Err(Box::new((x, residual))),
    };
    let input = x.into_data();
    let residual = residual.map(Tensor::into_data);
    let values = input.as_slice::<f32>().ok();
    let residual_values = residual.as_ref().map(|r| r.as_slice::<f32>().ok());
    let out = match (values, residual_values) {
        (Some(values), None) => host.forward3d(values, volume, None, relu).ok(),
        (Some(values), Some(Some(r))) => host.forward3d(values, volume, Some(r), relu).ok(),
        _ => None,
    };
    let Some((out, [od, oh, ow])) = out else {
        let back = |data: TensorData| Tensor::from_data(data, &device);
        return Err(Box::new((back(input), residual.map(back))));
    };
    let mut shape = dims;
    shape[1] = host.out_channels();
    shape[D - 2] = oh;
    shape[D - 1] = ow;
    if D == 5 {
        shape[2] = od;
    }
    Ok(Tensor::from_data(TensorData::new(out, shape), &device))
}

/// Whether the host kernels are the better path on `device`: burn flex, whose own
/// convolutions copy more than they multiply. libtorch (oneDNN) and GPUs keep theirs.
pub fn pays_on(device: &Device) -> bool {
    *device == Device::flex()
}

/// A layer's weights and its bias (zeros without one) as values; `None` when they do not read
/// as `f32`.
fn weights_and_bias<const D: usize>(
    weight: Tensor<D>,
    bias: Option<&Param<Tensor<1>>>,
    c_out: usize,
) -> Option<(Vec<f32>, Vec<f32>)> {
    let weight = read_values(weight, "weights").ok()?;
    let bias = match bias {
        Some(b) => read_values(b.val(), "bias").ok()?,
        None => vec![0.0; c_out],
    };
    Some((weight, bias))
}

/// A shape error of the host convolution.
fn shape_error(what: &str, expected: Vec<usize>, actual: Vec<usize>) -> NetError {
    NetError::Shape {
        what: format!("{what} (host convolution)"),
        expected,
        actual,
    }
}
