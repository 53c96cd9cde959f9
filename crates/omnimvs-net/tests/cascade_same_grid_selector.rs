//! The half stage's learnt choice among the coarse answers around each pixel when the coarse
//! stage shares its grid (`same_grid_selector`): the setting is checked and written
//! only when on, the candidates are the 3 x 3 neighbourhood on the same grid with the pixel's
//! own answer first in the prior, a network saved without the selector grows into it starting
//! near its own answers, the selector learns, and a saved one reloads as it was. Uses the
//! published rig of `sunny_single` from `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use burn::optim::GradientsParams;
use burn::tensor::Device;
use burn::tensor::activation::softmax;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::cascade::model::{
    UPSAMPLE_TAPS, neighbourhood_candidates, same_grid_prior, upsampling_candidates,
};
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig, NetError, weights};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{max_difference, micro_config, micro_image_tensors as images};

/// The micro cascade with its coarse stage on the half grid, the cue and learnt upsampling.
fn half_grid_config() -> NetConfig {
    let mut config = micro_config();
    config.cascade.coarse_scale = 2;
    config.cascade.convex_upsampling = true;
    config.cascade.convex_upsampling_full = false;
    config.cascade.zncc_cue = true;
    config.cascade.coarse_stride4 = true;
    config
}

fn invalid_field(config: &NetConfig) -> &'static str {
    match config.validate() {
        Err(NetError::InvalidConfig { field, .. }) => field,
        other => panic!("expected an invalid configuration, got {other:?}"),
    }
}

#[test]
fn the_setting_is_checked_and_written_only_when_on() {
    let off = half_grid_config();
    assert!(!off.cascade.same_grid_selector);
    assert!(!off.cascade.half_grid_selector());
    let json = serde_json::to_string(&off).unwrap();
    assert!(!json.contains("same_grid_selector"), "{json}");

    let mut on = off.clone();
    on.cascade.same_grid_selector = true;
    on.validate().unwrap();
    assert!(on.cascade.half_grid_selector());
    let json = serde_json::to_string(&on).unwrap();
    assert!(json.contains("\"same_grid_selector\":true"), "{json}");
    assert_eq!(serde_json::from_str::<NetConfig>(&json).unwrap(), on);

    let mut quarter = on.clone();
    quarter.cascade.coarse_scale = 4;
    assert_eq!(invalid_field(&quarter), "cascade.same_grid_selector");
    let mut plain = on;
    plain.cascade.convex_upsampling = false;
    assert_eq!(invalid_field(&plain), "cascade.same_grid_selector");
}

#[test]
fn candidates_are_the_neighbourhood_on_the_same_grid_and_the_prior_keeps_the_pixel() {
    let [rows, width] = [3, 5];
    let map: Vec<f32> = (0..rows * width).map(|i| i as f32 * 1.5 + 0.25).collect();
    let cols = 1..4;
    let n = rows * cols.len();
    let got = neighbourhood_candidates(&map, [rows, width], 1, &cols);
    assert_eq!(got.len(), UPSAMPLE_TAPS * n);
    for r in 0..rows {
        for (i, c) in cols.clone().enumerate() {
            for dr in -1i64..=1 {
                for dc in -1i64..=1 {
                    // Rows clamp at the top and bottom, columns wrap.
                    let rr = (r as i64 + dr).clamp(0, rows as i64 - 1) as usize;
                    let cc = (c as i64 + dc).rem_euclid(width as i64) as usize;
                    let tap = ((dr + 1) * 3 + dc + 1) as usize;
                    assert_eq!(
                        got[tap * n + r * cols.len() + i],
                        map[rr * width + cc],
                        "pixel ({r}, {c}), neighbour ({dr}, {dc})"
                    );
                }
            }
            assert_eq!(got[4 * n + r * cols.len() + i], map[r * width + c]);
        }
    }
    // Factor 2 is the learnt upsampling's candidates.
    let cols = 0..2 * width;
    assert_eq!(
        neighbourhood_candidates(&map, [rows, width], 2, &cols),
        upsampling_candidates(&map, [rows, width], &cols)
    );

    // The prior's softmax keeps about 95 % on the pixel's own answer everywhere.
    let device = Device::flex();
    let prior = same_grid_prior(rows, &(0..width), &device);
    assert_eq!(prior.dims(), [1, UPSAMPLE_TAPS, rows, width]);
    let weights = read_values(softmax(prior, 1), "weights").unwrap();
    let n = rows * width;
    for p in 0..n {
        let own = weights[4 * n + p];
        assert!((0.94..0.96).contains(&own), "pixel {p}: {own}");
    }
}

#[test]
fn a_network_grows_into_the_selector_near_its_answer_and_the_selector_learns() {
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    let config = half_grid_config();
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    assert!(net.up_mid.is_none());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("own.safetensors");
    weights::save_module(&net, &config, &path).unwrap();

    let mut chosen = config.clone();
    chosen.cascade.same_grid_selector = true;
    let grown = weights::load_cascade_grown(&path, &chosen, &device).unwrap();
    assert_eq!(grown.config, chosen);
    assert!(grown.up_mid.is_some() && grown.up_fine.is_none());
    // Every other weight is the file's.
    let a = read_values(net.mid.convs[0].conv.weight.val(), "a").unwrap();
    let b = read_values(grown.mid.convs[0].conv.weight.val(), "b").unwrap();
    assert_eq!(max_difference(&a, &b), 0.0);

    let geometry = CascadeGeometry::new(&ds.rig, &chosen, &hyps, &device).unwrap();
    let out = grown.forward(&images(&chosen, &device), &geometry).unwrap();
    let coarse = read_values(out.stages[0].index.clone(), "coarse").unwrap();
    let up = out.upsampled[0].clone().expect("the half grid's centres");
    assert_eq!(up.dims(), [1, 8, 32]);
    let up = read_values(up, "centres").unwrap();
    // Each centre lies within its neighbourhood's range, and near its own answer: the
    // neighbours keep about 5 % of the weight.
    let candidates = neighbourhood_candidates(&coarse, [8, 32], 1, &(0..32));
    let n = coarse.len();
    for p in 0..n {
        let values: Vec<f32> = (0..UPSAMPLE_TAPS).map(|t| candidates[t * n + p]).collect();
        let lo = values.iter().copied().fold(f32::MAX, f32::min);
        let hi = values.iter().copied().fold(f32::MIN, f32::max);
        assert!(lo - 1e-3 <= up[p] && up[p] <= hi + 1e-3, "pixel {p}");
        assert!(
            (up[p] - coarse[p]).abs() <= 0.06 * (hi - lo) + 1e-3,
            "pixel {p}: {} from {}",
            up[p],
            coarse[p]
        );
    }
    // The half stage centres on the chosen answers.
    let hyp = read_values(out.stages[1].hypotheses.clone(), "hypotheses").unwrap();
    let k = chosen.cascade.stage_hypotheses[0];
    for (p, &c) in up.iter().enumerate() {
        let (lo, hi) = (0..k)
            .map(|j| hyp[j * n + p])
            .fold((f32::MAX, f32::MIN), |(a, b), v| (a.min(v), b.max(v)));
        assert!(lo <= c + 1e-3 && c - 1e-3 <= hi, "pixel {p}");
    }

    // The selector's last convolution gets a gradient from the loss on its centres.
    let device = Device::flex().autodiff();
    let grown = weights::load_cascade_grown(&path, &chosen, &device).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &chosen, &hyps, &device).unwrap();
    let out = grown.forward(&images(&chosen, &device), &geometry).unwrap();
    let loss = out.upsampled[0]
        .clone()
        .unwrap()
        .sub_scalar(10.0)
        .abs()
        .mean();
    let grads = GradientsParams::from_grads(loss.backward(), &grown);
    let selector = grown.up_mid.as_ref().unwrap();
    let grad = grads.get::<4>(selector.out.weight.id).expect("a gradient");
    let norm: f32 = read_values(grad, "grad")
        .unwrap()
        .iter()
        .map(|g| g.abs())
        .sum();
    assert!(norm > 0.0 && norm.is_finite(), "{norm}");

    // Saved with the selector, the network reloads as it was, and not without it.
    let grown = weights::load_cascade_grown(&path, &chosen, &Device::flex()).unwrap();
    let saved = dir.path().join("chosen.safetensors");
    weights::save_module(&grown, &chosen, &saved).unwrap();
    let again = weights::load_cascade_grown(&saved, &chosen, &Device::flex()).unwrap();
    let a = read_values(grown.up_mid.unwrap().hidden.conv.weight.val(), "a").unwrap();
    let b = read_values(again.up_mid.unwrap().hidden.conv.weight.val(), "b").unwrap();
    assert_eq!(max_difference(&a, &b), 0.0);
    assert!(weights::load_cascade_grown(&saved, &config, &Device::flex()).is_err());
}
