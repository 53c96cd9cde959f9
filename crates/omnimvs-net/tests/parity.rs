//! Parity with PyTorch: `scripts/net_parity/make_parity.py` built the same layout with random
//! weights, saved the checkpoint and its outputs on deterministic inputs
//! (`tests/fixtures/parity/`). Our forward pass must match to 1e-4 on every backend of the
//! build: `cpu` (flex) always, `libtorch` with the `libtorch` feature, and the wgpu backend
//! named by `OMNIMVS_TEST_WGPU` (e.g. `wgpu-cpu` on Mesa's lavapipe) with the `wgpu` feature.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use std::path::{Path, PathBuf};

use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_net::weights::{import_pytorch, inspect_pytorch};
use omnimvs_net::{Backend, Layout, NetConfig, OmniMvsNet, SweepGrid, SweepInput, SweepTaps};

mod support;

const TOLERANCE: f32 = 1e-4;

/// The backends this build can test, with their devices.
fn test_devices() -> Vec<(Backend, Device)> {
    support::test_backends()
        .into_iter()
        .map(|b| (b, b.device().unwrap()))
        .collect()
}

fn fixture_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/parity")
}

struct Meta {
    config: NetConfig,
}

fn meta() -> Meta {
    let text = std::fs::read_to_string(fixture_dir().join("parity.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let get = |k: &str| v[k].as_u64().unwrap() as usize;
    Meta {
        config: NetConfig {
            channels: get("channels"),
            num_invdepth: get("num_invdepth"),
            out_height: get("out_height"),
            out_width: get("out_width"),
            num_cameras: get("num_cameras"),
            input_height: get("input_height"),
            input_width: get("input_width"),
            phi_deg: 45.0,
            layout: Layout::Published,
            ..NetConfig::paper()
        },
    }
}

fn read_f32(name: &str) -> Vec<f32> {
    let bytes = std::fs::read(fixture_dir().join(format!("{name}.f32"))).unwrap();
    bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect()
}

/// Mirror of `grid_value` in the script.
fn grid_value(c: &NetConfig, cam: usize, sphere: usize, row: usize, col: usize) -> (f32, f32) {
    use std::f64::consts::PI;
    let a = 2.0 * PI * (col as f64 + 0.5) / c.out_width as f64 + cam as f64 * PI / 2.0;
    let r = 0.15 + 0.8 * (row as f64 + 0.5) / c.out_height as f64;
    let s = sphere as f64;
    let mut x = 1.05 * r * a.cos() + 0.01 * s * (a + row as f64).sin();
    let mut y = 1.05 * r * a.sin() - 0.01 * s * (a - col as f64).cos();
    if (cam + row + 3 * col + sphere).is_multiple_of(11) {
        x = -2e5 / (c.input_width as f64 - 1.0) - 1.0;
        y = -2e5 / (c.input_height as f64 - 1.0) - 1.0;
    }
    (x as f32, y as f32)
}

fn grids(c: &NetConfig) -> Vec<SweepGrid> {
    (0..c.num_cameras)
        .map(|cam| {
            let mut coords = Vec::new();
            for s in 0..c.num_spheres() {
                for row in 0..c.out_height {
                    for col in 0..c.out_width {
                        let (x, y) = grid_value(c, cam, s, row, col);
                        coords.extend([x, y]);
                    }
                }
            }
            SweepGrid::new(c.num_spheres(), c.out_height, c.out_width, coords).unwrap()
        })
        .collect()
}

/// Mirror of `image_value` in the script.
fn images(c: &NetConfig, device: &Device) -> Vec<Tensor<4>> {
    (0..c.num_cameras)
        .map(|cam| {
            let cf = cam as f64;
            let mut data = Vec::new();
            for row in 0..c.input_height {
                for col in 0..c.input_width {
                    let (r, k) = (row as f64, col as f64);
                    let v = (0.37 * r + 1.3 * cf).sin() * (0.23 * k - 0.7 * cf).cos()
                        + 0.5 * (0.05 * r * k + cf).sin();
                    data.push(v as f32);
                }
            }
            Tensor::from_data(
                TensorData::new(data, [1, 1, c.input_height, c.input_width]),
                device,
            )
        })
        .collect()
}

fn max_abs_diff<const D: usize>(ours: Tensor<D>, golden: &[f32], what: &str) -> f32 {
    let ours = ours.into_data().try_into_vec_as::<f32>().unwrap();
    assert_eq!(ours.len(), golden.len(), "{what}: sizes differ");
    let diff = ours
        .iter()
        .zip(golden)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0f32, f32::max);
    eprintln!("{what}: max |ours - torch| = {diff:.3e}");
    diff
}

fn load_net(device: &Device) -> (NetConfig, OmniMvsNet) {
    let config = meta().config;
    let net = import_pytorch(&fixture_dir().join("parity.pt"), &config, device).unwrap();
    assert_eq!(net.config, config);
    (config, net)
}

#[test]
fn checkpoint_metadata_is_read() {
    let info = inspect_pytorch(&fixture_dir().join("parity.pt")).unwrap();
    assert_eq!(info.channels, 4);
    assert_eq!(info.num_cameras, 4);
    assert_eq!(info.layout, Layout::Published);
}

#[test]
fn differentiable_forward_matches_pytorch() {
    for (backend, device) in test_devices() {
        eprintln!("backend {backend}");
        differentiable_forward_matches_pytorch_on(&device);
    }
}

fn differentiable_forward_matches_pytorch_on(device: &Device) {
    let device = device.clone();
    let (config, net) = load_net(&device);
    let grids = grids(&config);
    let images = images(&config, &device);
    let feature = net.features(images[0].clone());
    assert!(max_abs_diff(feature.clone(), &read_f32("feature0"), "feature0") < TOLERANCE);
    let [_, _, rows, cols] = feature.dims();
    let taps = SweepTaps::for_grids(&grids, [rows, cols], &device);
    let warped = taps[0].warp(feature.clone(), 0..4).squeeze_dim::<4>(0);
    assert!(max_abs_diff(warped, &read_f32("warped0"), "warped0[:4]") < TOLERANCE);
    // [1, C, N/2, H/2, W/2] -> the script's [N/2, C, H/2, W/2]
    let spherical = net
        .spherical_sweep
        .forward(feature, &taps[0], 5)
        .squeeze_dim::<4>(0)
        .swap_dims(0, 1);
    assert!(max_abs_diff(spherical, &read_f32("spherical0"), "spherical0") < TOLERANCE);

    let out = net.forward(&images, &taps, &net.identity_order()).unwrap();
    assert!(max_abs_diff(out.cost.clone(), &read_f32("cost"), "cost") < TOLERANCE);
    assert!(max_abs_diff(out.index.clone(), &read_f32("index"), "index") < TOLERANCE);
    assert!(max_abs_diff(out.entropy(), &read_f32("entropy"), "entropy") < TOLERANCE);
}

#[test]
fn inference_paths_match_pytorch() {
    for (backend, device) in test_devices() {
        eprintln!("backend {backend}");
        inference_paths_match_pytorch_on(&device);
    }
}

fn inference_paths_match_pytorch_on(device: &Device) {
    let device = device.clone();
    let (config, net) = load_net(&device);
    let grids = grids(&config);
    let images = images(&config, &device);
    let order = net.identity_order();
    let out = net.infer(&images, &grids, &order).unwrap();
    assert!(max_abs_diff(out.cost, &read_f32("cost"), "infer cost") < TOLERANCE);
    assert!(max_abs_diff(out.index, &read_f32("index"), "infer index") < TOLERANCE);
    let folded = net.fold_batch_norm();
    let out = folded.infer(&images, &grids, &order).unwrap();
    assert!(max_abs_diff(out.cost.clone(), &read_f32("cost"), "folded cost") < TOLERANCE);
    assert!(max_abs_diff(out.index.clone(), &read_f32("index"), "folded index") < TOLERANCE);
    assert!(max_abs_diff(out.entropy(), &read_f32("entropy"), "folded entropy") < TOLERANCE);
    let taps = SweepTaps::for_grids(&grids, config.feature_size(), &device);
    let (out, _) = folded
        .infer_timed_with(&images, SweepInput::Device(&taps), &order)
        .unwrap();
    assert!(max_abs_diff(out.index, &read_f32("index"), "device-sweep index") < TOLERANCE);
}
