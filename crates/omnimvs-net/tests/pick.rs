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
use omnimvs_net::pick::{self, PickRefiner, Tensors};

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

#[test]
fn unet_scores_and_pick_match_pytorch() {
    let net = PickRefiner::load(&fixture("pick_tiny.safetensors")).unwrap();
    assert_eq!(net.cameras(), 1);
    let io = tensors("io.safetensors");
    let (shape, input) = &io["input"];
    assert_eq!(shape, &[11, 16, 64]);
    let logits = net.scores(input, [16, 64]).unwrap();
    let diff = max_difference(&logits, &io["logits"].1);
    assert!(diff < 1e-4, "logits differ from torch by {diff}");
    let answer = pick::combine(&io["logits"].1, &io["index"].1, [16, 64]);
    let diff = max_difference(&answer, &io["answer"].1);
    assert!(diff < 1e-3, "answer differs from torch by {diff}");
    // The pick stays within the candidates: between the 9 x 9 minimum and maximum.
    let cands = pick::candidates(&io["index"].1, [16, 64]);
    let plane = 16 * 64;
    for p in 0..plane {
        let (lo, hi) = (cands[5 * plane + p], cands[6 * plane + p]);
        assert!(
            answer[p] >= lo - 1e-3 && answer[p] <= hi + 1e-3,
            "pixel {p}"
        );
    }
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

#[test]
fn inputs_match_the_training_script_on_a_real_frame() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/itbt_sample");
    let ds = Dataset::open(&root).unwrap();
    let images = ds.read_frame(1).unwrap();
    let hypotheses = ds.hypotheses(192).unwrap();
    let grid = omnimvs_sweep::EquirectGrid::new(160, 640, 45.0).unwrap();
    let (v, spread) = synthetic_answer(160, 640);
    // A pick for the rig's four cameras (its weights play no part in the inputs).
    let net = PickRefiner::bundled().unwrap();
    let inputs = net
        .inputs(
            &v,
            &spread,
            &PixelSampler::new(&ds.rig, &grid, &hypotheses).unwrap(),
            &images,
        )
        .unwrap();
    let expected = tensors("inputs.safetensors");
    let pixels: Vec<usize> = expected["pixels"].1.iter().map(|&p| p as usize).collect();
    let (shape, values) = &expected["inputs"];
    assert_eq!(shape, &[pick::input_channels(4), pixels.len()]);
    let plane = 160 * 640;
    let (mut worst, mut sees_differ, mut seen) = (0f32, 0usize, 0usize);
    for ch in 0..shape[0] {
        for (i, &p) in pixels.iter().enumerate() {
            let (ours, theirs) = (inputs[ch * plane + p], values[ch * pixels.len() + i]);
            let sees_channel = ch >= 5 && (ch - 5) % 2 == 1;
            if sees_channel {
                seen += usize::from(theirs > 0.5);
                sees_differ += usize::from((ours > 0.5) != (theirs > 0.5));
            } else if ch < 5
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
    let err = PickRefiner::load(Path::new("/nonexistent/pick.safetensors")).unwrap_err();
    assert!(matches!(err, NetError::Io { .. }), "{err}");
}
