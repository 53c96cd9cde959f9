//! The same weights and input give the same inverse-depth map on every backend of the build
//! (max difference under 1e-3 index), with the sweep on the host and on the device.
//!
//! The default build compares the two sweep paths of `cpu` (flex); `--features libtorch` adds
//! libtorch on the CPU; `--features wgpu` with `OMNIMVS_TEST_WGPU=wgpu-cpu` (Mesa's lavapipe)
//! or `=wgpu` adds a wgpu device.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::Path;

use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_net::synthetic::synthetic_grids;
use omnimvs_net::weights::load_any;
use omnimvs_net::{Backend, NetConfig, SweepInput, SweepTaps};

mod support;
use support::test_backends;

const TOLERANCE: f32 = 1e-3;

fn bundled_model() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/omnimvs-tiny.safetensors")
}

/// Smooth deterministic images, one per camera.
fn images(c: &NetConfig, device: &Device) -> Vec<Tensor<4>> {
    (0..c.num_cameras)
        .map(|cam| {
            let data: Vec<f32> = (0..c.input_height * c.input_width)
                .map(|i| {
                    let (r, k) = ((i / c.input_width) as f32, (i % c.input_width) as f32);
                    (0.21 * r + cam as f32).sin() * (0.17 * k).cos() + 0.3 * (0.03 * r * k).sin()
                })
                .collect();
            Tensor::from_data(
                TensorData::new(data, [1, 1, c.input_height, c.input_width]),
                device,
            )
        })
        .collect()
}

/// Index map of the bundled `tiny` model on `backend`, host sweep or device sweep.
fn index_map(backend: Backend, device_sweep: bool) -> Vec<f32> {
    let device = backend.device().unwrap();
    let net = load_any(&bundled_model(), &NetConfig::tiny(), &device)
        .unwrap()
        .fold_batch_norm();
    let config = net.config.clone();
    let grids = synthetic_grids(&config);
    let taps = SweepTaps::for_grids(&grids, config.feature_size(), &device);
    let sweep = if device_sweep {
        SweepInput::Device(&taps)
    } else {
        SweepInput::Host(&grids)
    };
    let (out, _) = net
        .infer_timed_with(&images(&config, &device), sweep, &net.identity_order())
        .unwrap();
    out.index.into_data().try_into_vec_as::<f32>().unwrap()
}

#[test]
fn every_backend_gives_the_same_index_map() {
    let reference = index_map(Backend::Cpu, false);
    let spread = reference.iter().fold(0.0f32, |m, &v| m.max(v))
        - reference.iter().fold(f32::MAX, |m, &v| m.min(v));
    assert!(spread > 1.0, "degenerate reference map (spread {spread})");
    for backend in test_backends() {
        for device_sweep in [false, true] {
            let map = index_map(backend, device_sweep);
            assert_eq!(map.len(), reference.len());
            let diff = map
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            eprintln!("{backend} (device sweep {device_sweep}): max |index - cpu| = {diff:.2e}");
            assert!(diff < TOLERANCE, "{backend}: {diff}");
        }
    }
}
