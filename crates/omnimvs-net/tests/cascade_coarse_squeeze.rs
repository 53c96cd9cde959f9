//! The coarse stage's evidence squeezed through a 1x1 convolution before its first 3x3 one
//! (`coarse_squeeze`): the setting is checked and written only when set; a trained
//! network factorised by a truncated SVD of that layer answers as before at the layer's full
//! rank and comes nearer as the rank grows; the loader grows a saved network into it, the
//! squeeze learns, grows further (the aggregated cue's inputs land on the squeeze with zero
//! weights) and reloads as it was. Uses the published rig of `sunny_single` from
//! `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::sync::{Mutex, MutexGuard, PoisonError};

use burn::module::Param;
use burn::optim::GradientsParams;
use burn::tensor::Device;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig, NetError, weights};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{max_difference, micro_config, micro_image_tensors as images};

/// The micro cascade with the photometric cue: 8 spheres of 6 evidence channels (48 inputs)
/// into a first convolution of 4 outputs, so the layer's matrix is 36 x 48, of rank 36.
fn config() -> NetConfig {
    let mut config = micro_config();
    config.cascade.zncc_cue = true;
    config
}

const FULL_RANK: usize = 36;

/// Each test's random draws (the networks' initialisations) from its own `seed`, so that a
/// test always sees the same networks: the tests of this file run one at a time under the
/// returned guard, since the backend's generator is shared by the threads that run them.
fn seeded(device: &Device, seed: u64) -> MutexGuard<'static, ()> {
    static DRAWS: Mutex<()> = Mutex::new(());
    let guard = DRAWS.lock().unwrap_or_else(PoisonError::into_inner);
    device.seed(seed);
    guard
}

/// The network's coarse index and final index maps on `sunny_single`.
fn answers(net: &CascadeNet, config: &NetConfig) -> (Vec<f32>, Vec<f32>) {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(config.num_invdepth).unwrap();
    let device = Device::flex();
    let geometry = CascadeGeometry::new(&ds.rig, config, &hyps, &device).unwrap();
    let out = net.forward(&images(config, &device), &geometry).unwrap();
    let [coarse, _, fine] = out.stages;
    (
        read_values(coarse.index, "coarse").unwrap(),
        read_values(fine.index, "fine").unwrap(),
    )
}

#[test]
fn the_setting_is_checked_and_written_only_when_set() {
    let off = config();
    assert_eq!(off.cascade.coarse_squeeze, 0);
    assert!(
        !serde_json::to_string(&off)
            .unwrap()
            .contains("coarse_squeeze")
    );
    let mut on = off.clone();
    on.cascade.coarse_squeeze = 16;
    on.validate().unwrap();
    let json = serde_json::to_string(&on).unwrap();
    assert!(json.contains("\"coarse_squeeze\":16"), "{json}");
    assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), on);
    // No wider than the 48 channels it squeezes.
    on.cascade.coarse_squeeze = 49;
    match on.validate() {
        Err(NetError::InvalidConfig { field, message }) => {
            assert_eq!(field, "cascade.coarse_squeeze");
            assert!(message.contains("48"), "{message}");
        }
        other => panic!("expected an invalid configuration, got {other:?}"),
    }
}

#[test]
fn the_factorisation_answers_as_before_at_full_rank_and_nearer_as_the_rank_grows() {
    let config = config();
    let device = Device::flex();
    let _draws = seeded(&device, 37);
    // A random micro network's first layer (4 outputs) is now and then dead on these images
    // (every output at or below 0 before its ReLU, about one network in ten), and then no
    // factorisation of it can change the answer: take one whose answer depends on that layer.
    let net = (0..20)
        .map(|_| CascadeNet::new(&config, &device).unwrap())
        .find(|net| {
            let mut dead = net.clone();
            let w = dead.coarse.c0[0].conv.weight.val();
            dead.coarse.c0[0].conv.weight = Param::from_tensor(w.zeros_like());
            max_difference(&answers(net, &config).0, &answers(&dead, &config).0) > 1e-4
        })
        .expect("a network whose first coarse layer is live");
    let (coarse, fine) = answers(&net, &config);
    let w = read_values(net.coarse.c0[0].conv.weight.val(), "w").unwrap(); // [4, 48, 3, 3]
    let energy: f32 = w.iter().map(|v| v * v).sum();
    let mut previous = f32::MAX;
    for k in [4, 12, 24, FULL_RANK] {
        let squeezed = net.clone().with_coarse_squeeze(k).unwrap();
        assert_eq!(squeezed.config.cascade.coarse_squeeze, k);
        let squeeze = squeezed.coarse.squeeze.as_ref().expect("a squeeze");
        assert_eq!(squeeze.weight.val().dims(), [k, 48, 1, 1]);
        assert_eq!(squeezed.coarse.c0[0].conv.weight.val().dims(), [4, k, 3, 3]);
        // The squeeze's rows are orthonormal (V^T of the SVD).
        let b = read_values(squeeze.weight.val(), "squeeze").unwrap();
        for i in 0..k {
            for j in 0..k {
                let dot: f32 = (0..48).map(|c| b[i * 48 + c] * b[j * 48 + c]).sum();
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((dot - expected).abs() < 1e-4, "rows {i}, {j}: {dot}");
            }
        }
        // Every other weight is the network's own.
        let a = read_values(net.coarse.c0[1].conv.weight.val(), "a").unwrap();
        let s = read_values(squeezed.coarse.c0[1].conv.weight.val(), "b").unwrap();
        assert_eq!(max_difference(&a, &s), 0.0);
        // The layer it stands for, A B, is W's best approximation of rank k: its error
        // shrinks as k grows (Eckart-Young) and vanishes at full rank.
        let a = read_values(squeezed.coarse.c0[0].conv.weight.val(), "a").unwrap();
        let mut error = 0f32;
        for o in 0..4 {
            for i in 0..48 {
                for t in 0..9 {
                    let ab: f32 = (0..k).map(|j| a[(o * k + j) * 9 + t] * b[j * 48 + i]).sum();
                    error += (ab - w[(o * 48 + i) * 9 + t]).powi(2);
                }
            }
        }
        assert!(
            error <= previous * (1.0 + 1e-4),
            "rank {k}: {error} after {previous}"
        );
        previous = error;
        // The best rank-k layer keeps the k largest of 36 singular values, so at least k/36 of
        // the energy: a factorisation by any other k of them would leave more out (at full
        // rank, rounding only: below).
        let bound = energy * (1.0 - k as f32 / FULL_RANK as f32).max(1e-8);
        assert!(
            error <= bound * (1.0 + 1e-4),
            "rank {k}: error {error} above {bound}"
        );
        let (c, f) = answers(&squeezed, &squeezed.config);
        let diff = max_difference(&coarse, &c);
        if k == FULL_RANK {
            assert!(error < 1e-8 * energy, "full rank: layer error {error}");
            assert!(diff < 1e-3, "full rank: coarse index off by {diff}");
            assert!(
                max_difference(&fine, &f) < 1e-2,
                "full rank: final index moved"
            );
        } else {
            assert!(error > 1e-6 * energy, "rank {k} of 36 is the whole layer");
            assert!(
                diff > 1e-4,
                "rank {k} of 36 left the answer unchanged ({diff})"
            );
        }
    }
    // Once squeezed, the network keeps its squeeze: the same width is a no-op, another not.
    let squeezed = net.with_coarse_squeeze(12).unwrap();
    let same = squeezed.clone().with_coarse_squeeze(12).unwrap();
    assert_eq!(same.config, squeezed.config);
    assert!(squeezed.with_coarse_squeeze(24).is_err());
}

#[test]
fn the_loader_grows_a_network_into_it_which_learns_grows_further_and_reloads() {
    let config = config();
    let device = Device::flex();
    let _draws = seeded(&device, 38);
    let net = CascadeNet::new(&config, &device).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plain.safetensors");
    weights::save_module(&net, &config, &path).unwrap();

    let mut squeezed = config.clone();
    squeezed.cascade.coarse_squeeze = FULL_RANK;
    let grown = weights::load_cascade_grown(&path, &squeezed, &device).unwrap();
    assert_eq!(grown.config, squeezed);
    let direct = net.clone().with_coarse_squeeze(FULL_RANK).unwrap();
    let a = read_values(grown.coarse.c0[0].conv.weight.val(), "a").unwrap();
    let b = read_values(direct.coarse.c0[0].conv.weight.val(), "b").unwrap();
    assert_eq!(max_difference(&a, &b), 0.0);
    let (coarse, _) = answers(&net, &config);
    let (c, _) = answers(&grown, &squeezed);
    assert!(max_difference(&coarse, &c) < 1e-3);

    // The squeeze gets a gradient.
    let autodiff = Device::flex().autodiff();
    let trained = weights::load_cascade_grown(&path, &squeezed, &autodiff).unwrap();
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(squeezed.num_invdepth).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &squeezed, &hyps, &autodiff).unwrap();
    let out = trained
        .forward(&images(&squeezed, &autodiff), &geometry)
        .unwrap();
    let loss = out.stages[0].index.clone().sub_scalar(10.0).abs().mean();
    let grads = GradientsParams::from_grads(loss.backward(), &trained);
    let squeeze = trained.coarse.squeeze.as_ref().unwrap();
    let grad = grads.get::<4>(squeeze.weight.id).expect("a gradient");
    let norm: f32 = read_values(grad, "grad")
        .unwrap()
        .iter()
        .map(|g| g.abs())
        .sum();
    assert!(norm > 0.0 && norm.is_finite(), "{norm}");

    // Saved squeezed, it reloads as it was; the aggregated cue grows into the squeeze's
    // inputs with zero weights (the same answers); it cannot be squeezed again or unsqueezed.
    let saved = dir.path().join("squeezed.safetensors");
    weights::save_module(&grown, &squeezed, &saved).unwrap();
    let again = weights::load_cascade_grown(&saved, &squeezed, &device).unwrap();
    let (c2, f2) = answers(&again, &squeezed);
    let (c1, f1) = answers(&grown, &squeezed);
    assert_eq!(max_difference(&c1, &c2), 0.0);
    assert_eq!(max_difference(&f1, &f2), 0.0);
    let mut with_sgm = squeezed.clone();
    with_sgm.cascade.coarse_cue_sgm = true;
    let wider = weights::load_cascade_grown(&saved, &with_sgm, &device).unwrap();
    assert_eq!(
        wider.coarse.squeeze.as_ref().unwrap().weight.val().dims(),
        [FULL_RANK, 56, 1, 1]
    );
    let (c3, _) = answers(&wider, &with_sgm);
    assert!(max_difference(&c1, &c3) < 1e-4);
    let mut other = squeezed.clone();
    other.cascade.coarse_squeeze = 8;
    assert!(weights::load_cascade_grown(&saved, &other, &device).is_err());
    assert!(weights::load_cascade_grown(&saved, &config, &device).is_err());
}
