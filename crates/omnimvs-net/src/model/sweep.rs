//! Spherical sweep layer: warp a camera's features onto the swept spheres through the
//! precomputed bilinear taps of its lookup table, then the stride-2 "transference" conv.

use std::ops::Range;

use burn::module::Module;
use burn::tensor::{Device, Int, Tensor, TensorData};
use omnimvs_core::interp::BilinearTap;

use super::blocks::ConvBn2d;
use crate::error::NetError;
use crate::taps::{SweepGrid, grid_taps, warp_features};

/// One camera's bilinear taps as device tensors, for a given feature-map size.
///
/// The warp is `out[c, s] = sum_k w_k[s] * f[c, i_k[s]]`, a gather (`select`) and a multiply,
/// so gradients flow back to the features as scatter-adds; invalid neighbours have weight 0.
#[derive(Clone, Debug)]
pub struct SweepTaps {
    /// Number of spheres.
    pub num_spheres: usize,
    /// Rows of the equirectangular grid.
    pub height: usize,
    /// Columns of the equirectangular grid.
    pub width: usize,
    /// Feature-map size `[rows, cols]` the taps index into.
    pub src_size: [usize; 2],
    /// Flat source indices of the four neighbours, each `[num_spheres * height * width]`.
    pub indices: [Tensor<1, Int>; 4],
    /// Weights of the four neighbours, each `[1, num_spheres * height * width]`.
    pub weights: [Tensor<2>; 4],
}

impl SweepTaps {
    /// Precomputes the taps of `grid` for feature maps of `src_size = [rows, cols]`.
    pub fn new(grid: &SweepGrid, src_size: [usize; 2], device: &Device) -> Self {
        let taps = grid_taps(grid, src_size[0], src_size[1]);
        Self::from_taps(&taps, grid, src_size, device)
    }

    /// The taps `taps` of `grid` (from [`grid_taps`]) for feature maps of `src_size`, as
    /// device tensors.
    pub fn from_taps(
        taps: &[BilinearTap],
        grid: &SweepGrid,
        src_size: [usize; 2],
        device: &Device,
    ) -> Self {
        debug_assert_eq!(taps.len(), grid.num_spheres * grid.samples_per_sphere());
        let n = taps.len();
        let indices = std::array::from_fn(|k| {
            let data: Vec<i64> = taps.iter().map(|t| i64::from(t.index[k])).collect();
            Tensor::<1, Int>::from_data(TensorData::new(data, [n]), device)
        });
        let weights = std::array::from_fn(|k| {
            let data: Vec<f32> = taps.iter().map(|t| t.weight[k]).collect();
            Tensor::<2>::from_data(TensorData::new(data, [1, n]), device)
        });
        Self {
            num_spheres: grid.num_spheres,
            height: grid.height,
            width: grid.width,
            src_size,
            indices,
            weights,
        }
    }

    /// The taps of every camera's grid, for feature maps of `src_size = [rows, cols]`.
    pub fn for_grids(grids: &[SweepGrid], src_size: [usize; 2], device: &Device) -> Vec<Self> {
        grids
            .iter()
            .map(|g| Self::new(g, src_size, device))
            .collect()
    }

    /// Bilinear warp of `feature` `[B, C, rows, cols]` onto `spheres`:
    /// `[B, spheres.len(), C, height, width]`.
    pub fn warp(&self, feature: Tensor<4>, spheres: Range<usize>) -> Tensor<5> {
        let [batch, channels, rows, cols] = feature.dims();
        debug_assert_eq!(
            [rows, cols],
            self.src_size,
            "feature size differs from the taps'"
        );
        let per_sphere = self.height * self.width;
        let samples = spheres.start * per_sphere..spheres.end * per_sphere;
        let flat = feature.reshape([batch * channels, rows * cols]); // [B*C, rows*cols]
        let mut out: Option<Tensor<2>> = None;
        for k in 0..4 {
            let index = self.indices[k].clone().slice([samples.clone()]); // [S]
            let weight = self.weights[k].clone().slice([0..1, samples.clone()]); // [1, S]
            let tap = flat.clone().select(1, index) * weight; // [B*C, S]
            out = Some(match out {
                Some(acc) => acc + tap,
                None => tap,
            });
        }
        let n = spheres.len();
        let out = out
            .unwrap_or_else(|| Tensor::zeros([batch * channels, n * per_sphere], &flat.device()));
        out.reshape([batch, channels, n, self.height, self.width]) // [B, C, n, H, W]
            .swap_dims(1, 2) // [B, n, C, H, W]
    }
}

/// The transference convolution (`spherical_sweep.transfer_conv`): 3x3, stride 2, no batch
/// norm, no ReLU, applied to every sphere's warped features.
#[derive(Module, Debug)]
pub struct SphericalSweep {
    /// The 3x3 stride-2 convolution.
    pub transfer_conv: ConvBn2d,
}

impl SphericalSweep {
    /// Builds the layer for `CH = channels`.
    pub fn new(channels: usize, device: &Device) -> Self {
        Self {
            transfer_conv: ConvBn2d::new([channels, channels], 3, 2, 1, 1, false, false, device),
        }
    }

    /// The transference convolution also on the host ([`ConvBn2d::with_host_conv`]).
    #[must_use]
    pub fn with_host_convs(self) -> Self {
        Self {
            transfer_conv: self.transfer_conv.with_host_conv(),
        }
    }

    /// Transference of warped features `[B, n, C, H, W]` -> `[B, C, n, H/2, W/2]`.
    pub fn transfer(&self, warped: Tensor<5>) -> Tensor<5> {
        let [batch, n, channels, height, width] = warped.dims();
        let x = warped.reshape([batch * n, channels, height, width]); // [B*n, C, H, W]
        let x = self.transfer_conv.forward(x, None); // [B*n, C, H/2, W/2]
        let [_, _, h2, w2] = x.dims();
        x.reshape([batch, n, channels, h2, w2]).swap_dims(1, 2) // [B, C, n, H/2, W/2]
    }

    /// Sweeps one camera's features `[B, C, rows, cols]` with its taps, `chunk` spheres at a
    /// time: `[B, C, N/2, H/2, W/2]`. Differentiable with respect to the features.
    pub fn forward(&self, feature: Tensor<4>, taps: &SweepTaps, chunk: usize) -> Tensor<5> {
        let chunk = chunk.max(1);
        let parts: Vec<Tensor<5>> = (0..taps.num_spheres)
            .step_by(chunk)
            .map(|start| {
                let end = (start + chunk).min(taps.num_spheres);
                self.transfer(taps.warp(feature.clone(), start..end)) // [B, C, n, H/2, W/2]
            })
            .collect();
        Tensor::cat(parts, 2) // [B, C, N/2, H/2, W/2]
    }

    /// Inference sweep on the host with the fused warp kernel (no gradient, skips invalid
    /// samples), `chunk` spheres at a time: `[1, C, N/2, H/2, W/2]` for a `[1, C, rows, cols]`
    /// feature map.
    ///
    /// # Errors
    /// [`NetError::Shape`] for a batch other than 1.
    pub fn forward_host(
        &self,
        feature: Tensor<4>,
        grid: &SweepGrid,
        chunk: usize,
    ) -> Result<Tensor<5>, NetError> {
        let [batch, channels, rows, cols] = feature.dims();
        if batch != 1 {
            return Err(NetError::Shape {
                what: "feature batch for the host sweep".into(),
                expected: vec![1, channels, rows, cols],
                actual: vec![batch, channels, rows, cols],
            });
        }
        let device = feature.device();
        let data = feature
            .into_data()
            .try_into_vec_as::<f32>()
            .map_err(|e| NetError::Shape {
                what: format!("feature data ({e:?})"),
                expected: vec![],
                actual: vec![],
            })?;
        let chunk = chunk.max(1);
        let mut parts = Vec::new();
        for start in (0..grid.num_spheres).step_by(chunk) {
            let end = (start + chunk).min(grid.num_spheres);
            let warped = warp_features(&data, channels, rows, cols, grid, start..end)?;
            let warped = Tensor::<5>::from_data(
                TensorData::new(warped, [1, end - start, channels, grid.height, grid.width]),
                &device,
            ); // [1, n, C, H, W]
            parts.push(self.transfer(warped)); // [1, C, n, H/2, W/2]
        }
        Ok(Tensor::cat(parts, 2)) // [1, C, N/2, H/2, W/2]
    }
}
