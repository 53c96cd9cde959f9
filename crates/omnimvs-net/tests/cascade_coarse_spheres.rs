//! A trained cascade's coarse stage resampled to other spheres (`coarse_spheres`): its first
//! convolution keeps its output for evidence linear over inverse depth and its scores are
//! interpolated at the new spheres, and saved weights are resampled when loaded. Uses the
//! published rig of `sunny_single` from `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, weights};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{max_difference, micro_config, micro_image_tensors as images};

/// A tensor of `dims` with values from a fixed pseudo-random sequence (`seed`).
fn noise(dims: [usize; 4], seed: u32, device: &Device) -> Tensor<4> {
    let n: usize = dims.iter().product();
    let values: Vec<f32> = (0..n)
        .map(|i| ((i as f32 * 0.618 + seed as f32 * 1.37).sin() * 43758.547).fract() - 0.5)
        .collect();
    Tensor::from_data(TensorData::new(values, dims), device)
}

#[test]
fn resampled_spheres_keep_linear_evidence_and_interpolate_the_scores() {
    let config = micro_config(); // N = 32, 8 spheres, groups 4 at stride 8
    let device = Device::flex();
    let old = CascadeNet::new(&config, &device).unwrap();
    let (k_old, k_new, n) = (8usize, 5usize, 32usize);
    let moved = old.clone().with_coarse_spheres(k_new).unwrap();
    assert_eq!(moved.config.cascade.coarse_spheres, k_new);
    let channels = config.cascade.groups[2] + 1;
    assert_eq!(moved.coarse.c0[0].conv.weight.dims()[1], channels * k_new);
    assert_eq!(moved.coarse.out.conv.weight.dims()[0], k_new);
    // Everything else is kept.
    let same = |a: Tensor<4>, b: Tensor<4>| {
        max_difference(&read_values(a, "a").unwrap(), &read_values(b, "b").unwrap())
    };
    assert_eq!(
        same(
            old.coarse.c1[0].conv.weight.val(),
            moved.coarse.c1[0].conv.weight.val()
        ),
        0.0
    );

    // Evidence linear in the sphere's inverse-depth index, per channel and pixel.
    let (h, w) = (4, 8);
    let position = |k: usize, i: usize| i as f32 * (n - 1) as f32 / (k - 1) as f32;
    let slope = noise([1, channels, h, w], 1, &device);
    let offset = noise([1, channels, h, w], 2, &device);
    let volume = |k: usize| {
        let planes: Vec<Tensor<4>> = (0..channels)
            .flat_map(|c| {
                let (s, o) = (
                    slope.clone().narrow(1, c, 1),
                    offset.clone().narrow(1, c, 1),
                );
                (0..k).map(move |i| s.clone().mul_scalar(position(k, i) / 31.0) + o.clone())
            })
            .collect();
        Tensor::cat(planes, 1) // [1, channels x k, h, w], the sphere fastest
    };
    let before = old.coarse.c0[0].forward(volume(k_old), None);
    let after = moved.coarse.c0[0].forward(volume(k_new), None);
    let diff = same(before, after);
    assert!(diff < 1e-4, "first convolution moved by {diff}");

    // The new scores are the old ones interpolated at the new spheres' inverse depths.
    let hidden = noise([1, config.cascade.coarse_channels[0], h, w], 3, &device);
    let old_scores = read_values(old.coarse.out.forward(hidden.clone(), None), "old").unwrap();
    let new_scores = read_values(moved.coarse.out.forward(hidden, None), "new").unwrap();
    let plane = h * w;
    for j in 0..k_new {
        let u = position(k_new, j) * (k_old - 1) as f32 / (n - 1) as f32;
        let (i0, f) = (u.floor() as usize, u - u.floor());
        let i1 = (i0 + 1).min(k_old - 1);
        for p in 0..plane {
            let want = old_scores[i0 * plane + p] * (1.0 - f) + old_scores[i1 * plane + p] * f;
            let got = new_scores[j * plane + p];
            assert!(
                (got - want).abs() < 1e-4,
                "sphere {j} pixel {p}: {got} vs {want}"
            );
        }
    }

    // Resampling to the same spheres changes nothing.
    let kept = old.clone().with_coarse_spheres(k_old).unwrap();
    assert_eq!(
        same(
            old.coarse.c0[0].conv.weight.val(),
            kept.coarse.c0[0].conv.weight.val()
        ),
        0.0
    );
    // An invalid count is refused.
    assert!(old.with_coarse_spheres(1).is_err());
}

#[test]
fn saved_weights_are_resampled_to_other_spheres_when_loaded() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let mut config = micro_config();
    config.cascade.convex_upsampling = true;
    config.cascade.zncc_cue = true;
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("eight.safetensors");
    weights::save_module(&net, &config, &path).unwrap();

    let mut moved_config = config.clone();
    moved_config.cascade.coarse_spheres = 6;
    let moved = weights::load_cascade_grown(&path, &moved_config, &device).unwrap();
    assert_eq!(moved.config, moved_config);
    // Groups, visibility and cue per sphere.
    let inputs = (config.cascade.groups[2] + 2) * 6;
    assert_eq!(moved.coarse.c0[0].conv.weight.dims()[1], inputs);
    let geometry = CascadeGeometry::new(&ds.rig, &moved_config, &hyps, &device).unwrap();
    let out = moved
        .forward(&images(&moved_config, &device), &geometry)
        .unwrap();
    assert_eq!(out.stages[0].prob.dims()[1], 6);
    // The refinement stages' weights are the file's.
    let a = read_values(net.fine.convs[0].conv.weight.val(), "a").unwrap();
    let b = read_values(moved.fine.convs[0].conv.weight.val(), "b").unwrap();
    assert_eq!(max_difference(&a, &b), 0.0);
    let moved_path = dir.path().join("six.safetensors");
    weights::save_module(&moved, &moved_config, &moved_path).unwrap();
    let again = weights::load_cascade_grown(&moved_path, &moved_config, &device).unwrap();
    assert_eq!(again.config, moved_config);
}
