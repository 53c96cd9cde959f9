//! Layer shapes at the tiny preset, the sweep against a direct bilinear warp and its
//! gradient against finite differences.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use burn::tensor::ops::{GridSampleOptions, GridSamplePaddingMode, InterpolateMode};
use burn::tensor::{Device, Distribution, Tensor, TensorData};
use omnimvs_net::model::DEFAULT_SWEEP_CHUNK;
use omnimvs_net::taps::warp_features;
use omnimvs_net::{Layout, NetConfig, OmniMvsNet, SweepGrid, SweepTaps};

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::max_difference;

/// A grid that sweeps a circle of growing radius per sphere, with a band of invalid
/// entries and samples that fall partly outside the source.
fn test_grid(num_spheres: usize, height: usize, width: usize) -> SweepGrid {
    let mut coords = Vec::with_capacity(num_spheres * height * width * 2);
    for s in 0..num_spheres {
        for row in 0..height {
            for col in 0..width {
                let a = std::f32::consts::TAU * col as f32 / width as f32;
                let r = 0.2 + 0.9 * row as f32 / height as f32 + 0.01 * s as f32;
                if row == height / 2 && col % 3 == 0 {
                    coords.extend([-2e5f32, -2e5]);
                } else {
                    coords.extend([r * a.cos(), r * a.sin() * 1.02]);
                }
            }
        }
    }
    SweepGrid::new(num_spheres, height, width, coords).unwrap()
}

fn to_vec<const D: usize>(t: Tensor<D>) -> Vec<f32> {
    t.into_data().try_into_vec_as::<f32>().unwrap()
}

#[test]
fn every_stage_has_the_table_1_shape_at_the_tiny_preset() {
    let device = Device::flex();
    for layout in [Layout::Published, Layout::Iccv] {
        let config = NetConfig::tiny().with_layout(layout);
        let net = OmniMvsNet::new(&config, &device).unwrap();
        assert_eq!(net.feature_layers.layers.len(), layout.num_feature_convs());
        let (ch, cams) = (config.channels, config.num_cameras);
        let [fh, fw] = config.feature_size();
        let (n2, h2, w2) = (
            config.num_spheres(),
            config.out_height / 2,
            config.out_width / 2,
        );

        let image = Tensor::<4>::random(
            [1, 1, config.input_height, config.input_width],
            Distribution::Normal(0.0, 1.0),
            &device,
        );
        let feature = net.features(image.clone());
        assert_eq!(feature.dims(), [1, ch, fh, fw]);

        let grid = test_grid(n2, config.out_height, config.out_width);
        let taps = SweepTaps::new(&grid, [fh, fw], &device);
        let warped = taps.warp(feature.clone(), 0..3);
        assert_eq!(
            warped.dims(),
            [1, 3, ch, config.out_height, config.out_width]
        );
        let spherical = net
            .spherical_sweep
            .forward(feature, &taps, DEFAULT_SWEEP_CHUNK);
        assert_eq!(spherical.dims(), [1, ch, n2, h2, w2]);

        let concat = Tensor::cat(vec![spherical.clone(); cams], 1);
        let fused = net.cost_computes.fusion.forward(concat, None);
        assert_eq!(fused.dims(), [1, 2 * ch, n2, h2, w2]);
        let mut c = net.cost_computes.convs[0].forward(fused.clone(), None);
        let mut expected = [1, 2 * ch, n2, h2, w2];
        for (i, conv) in net.cost_computes.convs.iter().enumerate().skip(1) {
            if i % 3 == 0 {
                expected = [
                    1,
                    if i == 3 {
                        4 * ch
                    } else if i == 12 {
                        8 * ch
                    } else {
                        4 * ch
                    },
                    expected[2] / 2,
                    expected[3] / 2,
                    expected[4] / 2,
                ];
            }
            c = conv.forward(c, None);
            assert_eq!(c.dims(), expected, "3Dconv{}", i + 1);
        }
        let cost = net.cost_computes.regularize(fused);
        assert_eq!(
            cost.dims(),
            [
                1,
                1,
                config.num_invdepth,
                config.out_height,
                config.out_width
            ]
        );

        let images = vec![image; cams];
        let all_taps = vec![taps; cams];
        let out = net.forward(&images, &all_taps, &[3, 0, 1, 2]).unwrap();
        assert_eq!(
            out.cost.dims(),
            [1, config.num_invdepth, config.out_height, config.out_width]
        );
        assert_eq!(out.index.dims(), [1, config.out_height, config.out_width]);
        let index = to_vec(out.index.clone());
        assert!(
            index
                .iter()
                .all(|&i| (0.0..=(config.num_invdepth - 1) as f32).contains(&i))
        );
        let entropy = to_vec(out.entropy());
        let max_entropy = (config.num_invdepth as f32).ln();
        assert!(
            entropy
                .iter()
                .all(|&e| (-1e-5..=max_entropy + 1e-4).contains(&e))
        );
    }
}

#[test]
fn invalid_configurations_and_orders_are_rejected() {
    let device = Device::flex();
    let bad = NetConfig {
        out_width: 100,
        ..NetConfig::tiny()
    };
    let err = OmniMvsNet::new(&bad, &device).unwrap_err().to_string();
    assert!(err.contains("out_width"), "{err}");
    let net = OmniMvsNet::new(&NetConfig::tiny(), &device).unwrap();
    assert!(net.check_order(&[0, 1, 2, 3]).is_ok());
    assert!(net.check_order(&[0, 1, 1, 3]).is_err());
    assert!(net.check_order(&[0, 1, 2]).is_err());
    assert!(net.check_order(&[0, 1, 2, 4]).is_err());
}

#[test]
fn sweep_equals_a_direct_bilinear_warp() {
    let device = Device::flex();
    let (channels, rows, cols) = (3, 17, 23);
    let grid = test_grid(4, 8, 12);
    let feature = Tensor::<4>::random(
        [1, channels, rows, cols],
        Distribution::Normal(0.0, 1.0),
        &device,
    );
    let taps = SweepTaps::new(&grid, [rows, cols], &device);
    let ours = to_vec(taps.warp(feature.clone(), 0..4)); // [1, 4, C, 8, 12]
    let host = warp_features(&to_vec(feature.clone()), channels, rows, cols, &grid, 0..4).unwrap();
    assert!(max_difference(&ours, &host) < 1e-6);

    let options = GridSampleOptions::new(InterpolateMode::Bilinear)
        .with_padding_mode(GridSamplePaddingMode::Zeros)
        .with_align_corners(true);
    let per_sphere = grid.height * grid.width * 2;
    for s in 0..4 {
        let coords = grid.coords[s * per_sphere..(s + 1) * per_sphere].to_vec();
        // Invalid entries (-2e5) are far outside: grid_sample gives zero there too.
        let g = Tensor::<4>::from_data(
            TensorData::new(coords, [1, grid.height, grid.width, 2]),
            &device,
        );
        let direct = to_vec(feature.clone().grid_sample_2d(g, options.clone())); // [1, C, 8, 12]
        let n = channels * grid.height * grid.width;
        let diff = max_difference(&ours[s * n..(s + 1) * n], &direct);
        assert!(diff < 1e-5, "sphere {s}: {diff}");
    }
}

#[test]
fn sweep_gradient_matches_finite_differences() {
    let device = Device::flex();
    let (channels, rows, cols) = (2, 9, 11);
    let grid = test_grid(3, 6, 10);
    let feature_data: Vec<f32> = (0..channels * rows * cols)
        .map(|i| ((i * 37 % 101) as f32 / 50.0) - 1.0)
        .collect();
    let weights_data: Vec<f32> = (0..3 * channels * 6 * 10)
        .map(|i| ((i * 53 % 97) as f32 / 48.0) - 1.0)
        .collect();
    let taps = SweepTaps::new(&grid, [rows, cols], &device);
    let loss = |f: &[f32], device: &Device| -> Tensor<1> {
        let taps = SweepTaps::new(&grid, [rows, cols], device);
        let feature = Tensor::<4>::from_data(
            TensorData::new(f.to_vec(), [1, channels, rows, cols]),
            device,
        );
        let r = Tensor::<5>::from_data(
            TensorData::new(weights_data.clone(), [1, 3, channels, 6, 10]),
            device,
        );
        (taps.warp(feature, 0..3) * r).sum()
    };
    drop(taps);

    let ad = Device::flex().autodiff();
    let feature = Tensor::<4>::from_data(
        TensorData::new(feature_data.clone(), [1, channels, rows, cols]),
        &ad,
    )
    .require_grad();
    let taps = SweepTaps::new(&grid, [rows, cols], &ad);
    let r = Tensor::<5>::from_data(
        TensorData::new(weights_data.clone(), [1, 3, channels, 6, 10]),
        &ad,
    );
    let grads = (taps.warp(feature.clone(), 0..3) * r).sum().backward();
    let analytic = to_vec(feature.grad(&grads).unwrap());

    let eps = 1e-2f32;
    let mut checked_nonzero = 0;
    for i in 0..feature_data.len() {
        let mut plus = feature_data.clone();
        plus[i] += eps;
        let mut minus = feature_data.clone();
        minus[i] -= eps;
        let fd = (to_vec(loss(&plus, &device))[0] - to_vec(loss(&minus, &device))[0]) / (2.0 * eps);
        assert!(
            (fd - analytic[i]).abs() < 2e-3 * (1.0 + fd.abs()),
            "element {i}: fd {fd} vs {}",
            analytic[i]
        );
        if analytic[i].abs() > 1e-3 {
            checked_nonzero += 1;
        }
    }
    assert!(
        checked_nonzero > 20,
        "too few features receive gradient: {checked_nonzero}"
    );
}
