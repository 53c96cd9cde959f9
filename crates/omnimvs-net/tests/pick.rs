#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The learnt pick after the cascade (`omnimvs_net::pick`) against the PyTorch scripts that
//! trained it: the U-Net's scores and the picked answer on a random input
//! (`tests/fixtures/pick/`, made by `scripts/pick_parity/make_pick_fixture.py`), and the
//! inputs computed from the real `itbt_sample` frame 1 as `models/training/pick-1/pick_inputs.py`
//! computes them.

use std::path::{Path, PathBuf};

use omnimvs_data::Dataset;
use omnimvs_net::cascade::PixelSampler;
use omnimvs_net::error::NetError;
use omnimvs_net::pick::{self, PickLayout, PickRefiner, Tensors};

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::max_difference;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/pick")
        .join(name)
}

fn tensors(name: &str) -> Tensors {
    let path = fixture(name);
    pick::read_safetensors(&std::fs::read(&path).unwrap(), &path).unwrap()
}

/// The U-Net's scores and the pick of `weights` against torch's on `io` (`[channels, h, w]`
/// inputs); the pick stays between the widest candidates' minimum and maximum.
fn check_scores_and_pick(weights: &str, io: &str, layout: &PickLayout, [c, h, w]: [usize; 3]) {
    let net = PickRefiner::load(&fixture(weights)).unwrap();
    assert_eq!(net.cameras(), 1);
    assert_eq!(net.layout(), layout);
    let io = tensors(io);
    let (shape, input) = &io["input"];
    assert_eq!(shape, &[c, h, w]);
    assert_eq!(layout.input_channels(1), c);
    let logits = net.scores(input, [h, w]).unwrap();
    let diff = max_difference(&logits, &io["logits"].1);
    // Float rounding, relative to the logits' size (random weights make them large).
    let size = io["logits"].1.iter().fold(1f32, |m, v| m.max(v.abs()));
    assert!(
        diff < 1e-5 * size,
        "logits differ from torch by {diff} (largest {size})"
    );
    let answer = layout.combine(&io["logits"].1, &io["index"].1, [h, w]);
    let diff = max_difference(&answer, &io["answer"].1);
    assert!(diff < 1e-3, "answer differs from torch by {diff}");
    let cands = layout.candidate_maps(&io["index"].1, [h, w]);
    let plane = h * w;
    let widest = layout.candidates() - 2;
    for p in 0..plane {
        let (lo, hi) = (cands[widest * plane + p], cands[(widest + 1) * plane + p]);
        assert!(
            answer[p] >= lo - 1e-3 && answer[p] <= hi + 1e-3,
            "pixel {p}"
        );
    }
}

#[test]
fn unet_scores_and_pick_match_pytorch() {
    check_scores_and_pick(
        "pick_tiny.safetensors",
        "io.safetensors",
        &PickLayout::default(),
        [11, 16, 64],
    );
}

/// pick-3's layout, read from the file's metadata: eleven candidates, depths at the 5 x 5 and
/// 25 x 25 extremes, ZNCC channels.
fn layout3() -> PickLayout {
    PickLayout {
        candidate_radii: vec![1, 2, 4, 7, 12],
        depth_radii: vec![2, 12],
        zncc: 5,
    }
}

#[test]
fn a_wider_layout_from_the_metadata_matches_pytorch() {
    check_scores_and_pick(
        "pick_tiny3.safetensors",
        "io3.safetensors",
        &layout3(),
        [28, 32, 64],
    );
}

/// The fixture's synthetic answer and spread (`synthetic_answer` of the fixture script).
fn synthetic_answer(h: usize, w: usize) -> (Vec<f32>, Vec<f32>) {
    let mut v = Vec::with_capacity(h * w);
    let mut spread = Vec::with_capacity(h * w);
    for r in 0..h {
        for c in 0..w {
            let (rf, cf) = (r as f64, c as f64);
            let step = if c % 160 >= 80 { 50.0 } else { 0.0 };
            v.push((40.0 + 30.0 * (cf / 50.0).sin() + 10.0 * (rf / 17.0).cos() + step) as f32);
            spread.push((0.1 * rf + 0.01 * cf) as f32);
        }
    }
    (v, spread)
}

/// The inputs of `layout` on the real `itbt_sample` frame 1 for the synthetic answer against
/// the training script's (`fixture`).
fn check_inputs_on_a_real_frame(layout: &PickLayout, fixture_name: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/itbt_sample");
    let ds = Dataset::open(&root).unwrap();
    let images = ds.read_frame(1).unwrap();
    let hypotheses = ds.hypotheses(192).unwrap();
    let grid = omnimvs_sweep::EquirectGrid::new(160, 640, 45.0).unwrap();
    let (v, spread) = synthetic_answer(160, 640);
    let inputs = layout
        .inputs(
            &v,
            &spread,
            &PixelSampler::new(&ds.rig, &grid, &hypotheses).unwrap(),
            &images,
        )
        .unwrap();
    let expected = tensors(fixture_name);
    let pixels: Vec<usize> = expected["pixels"].1.iter().map(|&p| p as usize).collect();
    let (shape, values) = &expected["inputs"];
    assert_eq!(shape, &[layout.input_channels(4), pixels.len()]);
    let plane = 160 * 640;
    let (first, zncc_first) = (
        layout.answer_channels(),
        layout.answer_channels() + 2 * 4 * layout.depths(),
    );
    let (mut worst, mut sees_differ, mut seen) = (0f32, 0usize, 0usize);
    let (mut zncc_worst, mut zncc_compared) = (Vec::new(), 0usize);
    for ch in 0..shape[0] {
        for (i, &p) in pixels.iter().enumerate() {
            let (ours, theirs) = (inputs[ch * plane + p], values[ch * pixels.len() + i]);
            if ch >= zncc_first {
                // ZNCC and the pairs that count: a window's visibility may differ at the
                // edge of a field of view; compare where the pairs counted agree.
                let fraction = (ch - zncc_first) % 2 == 1;
                let pairs_channel = if fraction { ch } else { ch + 1 };
                let pairs = |x: &[f32], at: usize, n: usize| x[pairs_channel * n + at];
                if pairs(&inputs, p, plane) == pairs(values, i, pixels.len()) {
                    zncc_compared += 1;
                    zncc_worst.push((ours - theirs).abs());
                }
                continue;
            }
            let sees_channel = ch >= first && (ch - first) % 2 == 1;
            if sees_channel {
                seen += usize::from(theirs > 0.5);
                sees_differ += usize::from((ours > 0.5) != (theirs > 0.5));
            } else if ch < first
                || (values[(ch + 1) * pixels.len() + i] > 0.5 && inputs[(ch + 1) * plane + p] > 0.5)
            {
                worst = worst.max((ours - theirs).abs());
            }
        }
    }
    // Projections agree to about 1e-3 pixel: a sample at the edge of the field of view may
    // fall either side.
    assert!(seen > pixels.len(), "the cameras see the points: {seen}");
    assert!(
        sees_differ * 1000 < seen,
        "{sees_differ} of {seen} visibility flags differ"
    );
    assert!(worst < 0.02, "inputs differ from the script's by {worst}");
    if layout.zncc > 0 {
        let expected_compared = 2 * layout.depths() * pixels.len();
        assert!(
            zncc_compared * 100 > expected_compared * 99,
            "pairs counted agree at {zncc_compared} of {expected_compared}"
        );
        zncc_worst.sort_by(f32::total_cmp);
        // A sample at the very edge of a camera's view can shift one window's sums.
        let p999 = zncc_worst[zncc_worst.len() * 999 / 1000];
        assert!(
            p999 < 0.02,
            "ZNCC differs from the script's by {p999} (99.9th percentile)"
        );
    }
}

#[test]
fn inputs_match_the_training_script_on_a_real_frame() {
    check_inputs_on_a_real_frame(&PickLayout::default(), "inputs.safetensors");
}

#[test]
fn wider_inputs_with_zncc_match_the_training_script_on_a_real_frame() {
    check_inputs_on_a_real_frame(&layout3(), "inputs3.safetensors");
}

#[test]
fn the_bundled_pick_reads_and_bad_files_are_refused() {
    let net = PickRefiner::bundled().unwrap();
    assert_eq!(net.cameras(), 4);
    let path = Path::new("x.safetensors");
    let err = PickRefiner::from_bytes(b"abc", path).unwrap_err();
    assert!(matches!(err, NetError::Weights { .. }), "{err}");
    assert!(err.to_string().contains("x.safetensors"), "{err}");
    // A file of another model: the first tensor it lacks is named.
    let mut bytes = std::fs::read(fixture("io.safetensors")).unwrap();
    let err = PickRefiner::from_bytes(&bytes, path).unwrap_err();
    assert!(err.to_string().contains("e0.0.0.weight"), "{err}");
    // A truncated file.
    bytes.truncate(bytes.len() / 2);
    let err = PickRefiner::from_bytes(&bytes, path).unwrap_err();
    assert!(err.to_string().contains("data_offsets"), "{err}");
    // A layout in the metadata that is not one: the key is named.
    let good = std::fs::read(fixture("pick_tiny3.safetensors")).unwrap();
    let text = String::from_utf8_lossy(&good).into_owned();
    for (from, to, key) in [
        ("\"1,2,4,7,12\"", "\"1,x,4,7,12\"", "candidate_radii"),
        ("\"zncc\": \"5\"", "\"zncc\": \"4\"", "zncc"),
    ] {
        assert!(text.contains(from), "fixture header holds {from}");
        let bad = good_with(&good, from, to);
        let err = PickRefiner::from_bytes(&bad, path).unwrap_err();
        assert!(err.to_string().contains(key), "{err}");
    }
    // Weights whose first layer does not fit the layout in their metadata.
    let bad = good_with(&good, "\"2,12\"", "\"2,11\"");
    assert!(PickRefiner::from_bytes(&bad, path).is_ok());
    let bad = good_with(
        &good,
        "\"depth_radii\": \"2,12\"",
        "\"depth_radii\": \"2\"   ",
    );
    let err = PickRefiner::from_bytes(&bad, path).unwrap_err();
    assert!(err.to_string().contains("e0.0.0.weight"), "{err}");
    let err = PickRefiner::load(Path::new("/nonexistent/pick.safetensors")).unwrap_err();
    assert!(matches!(err, NetError::Io { .. }), "{err}");
}

/// `bytes` with the header text `from` replaced by `to` of the same length.
fn good_with(bytes: &[u8], from: &str, to: &str) -> Vec<u8> {
    assert_eq!(from.len(), to.len());
    let at = bytes
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .unwrap();
    let mut out = bytes.to_vec();
    out[at..at + to.len()].copy_from_slice(to.as_bytes());
    out
}
