//! The smallest cascade and its inputs, shared by the cascade tests of `omnimvs-net` and
//! `omnimvs-train` (included with `#[path]`).

#![allow(dead_code)] // each test file uses a part

use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_net::NetConfig;

/// The smallest cascade: a `16 x 64` output, `N = 32`, 8 coarse spheres, `48 x 50` inputs.
pub fn micro_config() -> NetConfig {
    let mut config = NetConfig {
        num_invdepth: 32,
        out_height: 16,
        out_width: 64,
        input_height: 48,
        input_width: 50,
        ..NetConfig::cascade()
    };
    config.cascade.feature_channels = [4, 4, 8];
    config.cascade.groups = [2, 2, 4];
    config.cascade.coarse_spheres = 8;
    config.cascade.coarse_channels = [4, 4, 8];
    config.cascade.stage_hypotheses = [4, 3];
    config.cascade.stage_channels = [4, 4];
    config
}

/// One textured image per camera of `config`'s input size (values in -1.6..1.6).
pub fn micro_images(config: &NetConfig) -> Vec<Vec<f32>> {
    (0..config.num_cameras)
        .map(|cam| {
            (0..config.input_height * config.input_width)
                .map(|i| {
                    let (r, c) = (
                        (i / config.input_width) as f32,
                        (i % config.input_width) as f32,
                    );
                    ((0.7 * c + 1.3 * r + cam as f32).sin() + (0.31 * c * r).cos()) * 0.8
                })
                .collect()
        })
        .collect()
}

/// [`micro_images`] as `[1, 1, H, W]` tensors on `device`.
pub fn micro_image_tensors(config: &NetConfig, device: &Device) -> Vec<Tensor<4>> {
    micro_images(config)
        .into_iter()
        .map(|img| {
            Tensor::<4>::from_data(
                TensorData::new(img, [1, 1, config.input_height, config.input_width]),
                device,
            )
        })
        .collect()
}

/// Largest absolute difference between two equally long slices.
pub fn max_difference(a: &[f32], b: &[f32]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0f32, f32::max)
}
