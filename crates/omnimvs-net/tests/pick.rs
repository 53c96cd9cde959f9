#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The learnt pick after the cascade (`omnimvs_net::pick`) against the PyTorch scripts that
//! trained it: the U-Net's scores and the picked answer on a random input
//! (`tests/fixtures/pick/`, made by `scripts/pick_parity/make_pick_fixture.py`), and the
//! inputs computed from the real `itbt_sample` frame 1 as `scripts/pick/pick_inputs.py`
//! computes them.

use std::path::{Path, PathBuf};

use omnimvs_data::Dataset;
use omnimvs_net::cascade::PixelSampler;
use omnimvs_net::error::NetError;
use omnimvs_net::pick::{self, CoarseModes, PickLayout, PickRefiner, Tensors};

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
    let answer = layout.combine(
        &io["logits"].1,
        &io["index"].1,
        &CoarseModes::none(),
        [h, w],
    );
    let diff = max_difference(&answer, &io["answer"].1);
    assert!(diff < 1e-3, "answer differs from torch by {diff}");
    let cands = layout.candidate_maps(&io["index"].1, &CoarseModes::none(), [h, w]);
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
        coarse_modes: 0,
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
            &CoarseModes::none(),
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
    assert!(
        err.to_string().contains("not a whole safetensors file"),
        "{err}"
    );
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

#[test]
fn coarse_modes_are_ordered_by_mass_and_fill_the_output_grid() {
    // One coarse row of two pixels over six spheres 10 index units apart.
    let (k, plane) = (6, 2);
    let hyp: Vec<f32> = (0..k)
        .flat_map(|i| [10.0 * i as f32; 2])
        .collect::<Vec<_>>();
    let by_pixel = [
        [0.1, 0.5, 0.1, 0.0, 0.3, 0.0], // two modes: spheres 1 (mass 0.7) and 4 (0.3)
        [0.0, 0.0, 0.0, 0.0, 0.2, 0.8], // one: the last sphere, mass 1
    ];
    let mut prob = vec![0f32; k * plane];
    for (p, row) in by_pixel.iter().enumerate() {
        for (i, &v) in row.iter().enumerate() {
            prob[i * plane + p] = v;
        }
    }
    let modes = CoarseModes::from_distribution(&prob, &hyp, [k, 1, 2], 3, [2, 4]).unwrap();
    assert_eq!(modes.count, 3);
    let close = |a: f32, b: f32| (a - b).abs() < 1e-4;
    // Each coarse pixel covers 2 x 2 output pixels.
    for r in 0..2 {
        for c in 0..4 {
            let at = |j: usize| {
                (
                    modes.index[j * 8 + r * 4 + c],
                    modes.mass[j * 8 + r * 4 + c],
                )
            };
            let expected = if c < 2 {
                [(10.0, 0.7), (40.0, 0.3), (10.0, 0.0)]
            } else {
                [(48.0, 1.0), (48.0, 0.0), (48.0, 0.0)]
            };
            for (j, (index, mass)) in expected.into_iter().enumerate() {
                let (i, m) = at(j);
                assert!(
                    close(i, index) && close(m, mass),
                    "({r}, {c}) mode {j}: {i} {m}"
                );
            }
        }
    }
    assert!(CoarseModes::from_distribution(&prob[1..], &hyp, [k, 1, 2], 3, [2, 4]).is_err());
    assert!(CoarseModes::from_distribution(&prob, &hyp, [k, 1, 2], 3, [0, 4]).is_err());
}

/// The real `itbt_sample` frame 1, its rig's sampler on the output grid, and the fixture's
/// synthetic answer and spread on it.
fn real_frame() -> (
    Vec<omnimvs_core::GrayImage>,
    PixelSampler,
    Vec<f32>,
    Vec<f32>,
) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/itbt_sample");
    let ds = Dataset::open(&root).unwrap();
    let grid = omnimvs_sweep::EquirectGrid::new(160, 640, 45.0).unwrap();
    let sampler = PixelSampler::new(&ds.rig, &grid, &ds.hypotheses(192).unwrap()).unwrap();
    let (v, spread) = synthetic_answer(160, 640);
    (ds.read_frame(1).unwrap(), sampler, v, spread)
}

/// Two modes for the answer `v`: `v` itself (mass 0.7) and 15 index units farther (0.2).
fn two_modes(v: &[f32]) -> CoarseModes {
    let mut index = v.to_vec();
    index.extend(v.iter().map(|&x| (x + 15.0).min(191.0)));
    let mut mass = vec![0.7f32; v.len()];
    mass.extend(vec![0.2f32; v.len()]);
    CoarseModes {
        count: 2,
        index,
        mass,
    }
}

#[test]
fn the_coarse_modes_inputs_read_the_cameras_at_each_mode() {
    let (images, sampler, v, spread) = real_frame();
    let layout = PickLayout {
        coarse_modes: 2,
        ..layout3()
    };
    assert_eq!(layout.mode_channels(), 10);
    assert_eq!(layout.candidates(), 13);
    assert_eq!(layout.input_channels(4), layout3().input_channels(4) + 10);
    let modes = two_modes(&v);
    let inputs = layout
        .inputs(&v, &spread, &modes, &sampler, &images)
        .unwrap();
    let plane = v.len();
    let channel = |c: usize| &inputs[c * plane..(c + 1) * plane];
    let first = layout.input_channels(4) - layout.mode_channels();
    // pick-3's ZNCC at the answer (checked against the training script above), window 5.
    let zncc_first = layout.answer_channels() + 2 * 4 * layout.depths();
    assert_eq!(pick::MODE_ZNCC, layout.zncc);
    let (zncc_v, pairs_v) = (channel(zncc_first), channel(zncc_first + 1));
    // Mode 0 is the answer itself: offset 0, its mass, and the ZNCC at the answer.
    assert!(channel(first).iter().all(|&x| x == 0.0));
    assert!(channel(first + 1).iter().all(|&x| x == 0.7));
    assert_eq!(channel(first + 2), zncc_v);
    assert_eq!(channel(first + 3), pairs_v);
    // Mode 1: its offset and mass, and other ZNCC where pairs count.
    let offsets = channel(first + 4).iter().zip(&modes.index[plane..]).zip(&v);
    for ((&offset, &mode), &answer) in offsets {
        assert!((offset - (mode - answer) / 32.0).abs() < 1e-6);
    }
    assert!(channel(first + 5).iter().all(|&x| x == 0.2));
    let differ = (0..plane)
        .filter(|&p| pairs_v[p] > 0.0 && (channel(first + 6)[p] - zncc_v[p]).abs() > 0.05)
        .count();
    assert!(
        differ * 4 > plane,
        "mode 1's ZNCC differs from the answer's at {differ} pixels"
    );
    assert!(channel(first + 6).iter().all(|z| (-1.0..=1.0).contains(z)));
    // Then the ZNCC at the answer.
    assert_eq!(channel(first + 8), zncc_v);
    assert_eq!(channel(first + 9), pairs_v);
    // Too few modes are refused.
    let one = CoarseModes {
        count: 1,
        index: v.clone(),
        mass: vec![1.0; plane],
    };
    let err = layout
        .inputs(&v, &spread, &one, &sampler, &images)
        .unwrap_err();
    assert!(err.to_string().contains("coarse modes"), "{err}");
}

/// A pick's safetensors (the training script's names) of width 1 for `layout` and four
/// cameras that puts all the weight on candidate `trusted`: zero weights, the head's biases 30
/// there and -30 elsewhere.
fn pick_file(layout: &PickLayout, trusted: usize) -> Vec<u8> {
    let w = 1;
    let mut bias = vec![-30.0; layout.candidates()];
    bias[trusted] = 30.0;
    let c = layout.input_channels(4);
    let layers = [
        ("e0.0.0", c, w),
        ("e0.1.0", w, w),
        ("e1.0.0", w, 2 * w),
        ("e1.1.0", 2 * w, 2 * w),
        ("e2.0.0", 2 * w, 3 * w),
        ("e2.1.0", 3 * w, 3 * w),
        ("e3.0.0", 3 * w, 4 * w),
        ("e3.1.0", 4 * w, 4 * w),
        ("d2.0", 7 * w, 3 * w),
        ("d1.0", 5 * w, 2 * w),
        ("d0.0", 3 * w, w),
        ("head", w, layout.candidates()),
    ];
    let mut header = serde_json::Map::new();
    let list = |v: &[usize]| {
        v.iter()
            .map(ToString::to_string)
            .collect::<Vec<_>>()
            .join(",")
    };
    header.insert(
        "__metadata__".into(),
        serde_json::json!({
            "candidate_radii": list(&layout.candidate_radii),
            "depth_radii": list(&layout.depth_radii),
            "zncc": layout.zncc.to_string(),
            "coarse_modes": layout.coarse_modes.to_string(),
        }),
    );
    let mut data: Vec<f32> = Vec::new();
    for (name, c_in, c_out) in layers {
        let biases = if name == "head" {
            bias.clone()
        } else {
            vec![0.0; c_out]
        };
        for (suffix, shape, values) in [
            (
                "weight",
                vec![c_out, c_in, 3, 3],
                vec![0f32; c_out * c_in * 9],
            ),
            ("bias", vec![c_out], biases),
        ] {
            let start = 4 * data.len();
            data.extend(values);
            header.insert(
                format!("{name}.{suffix}"),
                serde_json::json!({"dtype": "F32", "shape": shape, "data_offsets": [start, 4 * data.len()]}),
            );
        }
    }
    let header = serde_json::to_vec(&serde_json::Value::Object(header)).unwrap();
    let mut out = (header.len() as u64).to_le_bytes().to_vec();
    out.extend(header);
    out.extend(data.iter().flat_map(|v| v.to_le_bytes()));
    out
}

#[test]
fn a_pick_that_trusts_the_second_mode_answers_with_its_depth() {
    let (images, sampler, v, spread) = real_frame();
    let layout = PickLayout {
        coarse_modes: 2,
        ..PickLayout::default()
    };
    // Candidates: v, six extremes, then the two modes; all the weight on the second mode.
    let bytes = pick_file(&layout, 8);
    let pick = PickRefiner::from_bytes(&bytes, Path::new("modes.safetensors")).unwrap();
    assert_eq!((pick.cameras(), pick.layout()), (4, &layout));
    let modes = two_modes(&v);
    let answer = pick.refine(&v, &spread, &modes, &sampler, &images).unwrap();
    let diff = max_difference(&answer, &modes.index[v.len()..]);
    assert!(
        diff < 1e-3,
        "the answer differs from the second mode by {diff}"
    );
    // Without the modes it reads, it refuses to run.
    let err = pick
        .refine(&v, &spread, &CoarseModes::none(), &sampler, &images)
        .unwrap_err();
    assert!(err.to_string().contains("coarse modes"), "{err}");
    // A count of modes out of range in the metadata is refused, its key named.
    let text = String::from_utf8_lossy(&bytes).into_owned();
    assert!(text.contains("\"coarse_modes\":\"2\""));
    let bad = good_with(&bytes, "\"coarse_modes\":\"2\"", "\"coarse_modes\":\"9\"");
    let err = PickRefiner::from_bytes(&bad, Path::new("modes.safetensors")).unwrap_err();
    assert!(err.to_string().contains("coarse_modes"), "{err}");
}

#[test]
fn a_chain_of_picks_runs_each_on_the_answer_of_the_one_before() {
    let (images, sampler, v, spread) = real_frame();
    let with_modes = PickLayout {
        coarse_modes: 2,
        ..PickLayout::default()
    };
    // The first answers with the second mode (v + 15); the second with the maximum over the
    // 3 x 3 answers around (its candidate 2) of that.
    let first = PickRefiner::from_bytes(&pick_file(&with_modes, 8), Path::new("first.safetensors"))
        .unwrap();
    let plain = PickLayout::default();
    let second =
        PickRefiner::from_bytes(&pick_file(&plain, 2), Path::new("second.safetensors")).unwrap();
    let chain = first.clone().followed_by(second.clone()).unwrap();
    assert_eq!((chain.passes(), chain.coarse_modes()), (2, 2));
    // The second of the chain reads no modes, but the chain does.
    assert_eq!(
        second
            .clone()
            .followed_by(first.clone())
            .unwrap()
            .coarse_modes(),
        2
    );
    let modes = two_modes(&v);
    let answer = chain
        .refine(&v, &spread, &modes, &sampler, &images)
        .unwrap();
    let after_first = &modes.index[v.len()..];
    let expected = &plain.candidate_maps(after_first, &CoarseModes::none(), [160, 640])
        [2 * v.len()..3 * v.len()];
    let diff = max_difference(&answer, expected);
    assert!(diff < 1e-3, "the chain's answer differs by {diff}");
    // A pick for one camera cannot follow a pick for four.
    let one_camera = PickRefiner::load(&fixture("pick_tiny.safetensors")).unwrap();
    let err = chain.followed_by(one_camera).unwrap_err();
    assert!(err.to_string().contains("cameras"), "{err}");
    // The bundled pick is one; the bundled chain, two.
    assert_eq!(PickRefiner::bundled().unwrap().passes(), 1);
    assert_eq!(PickRefiner::bundled_chain().unwrap().passes(), 2);
    // The third pick kept beside its run (pick-9, `models/extra/`) follows them, with pick-6's layout.
    let pick9 = PickRefiner::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../models/extra/pick9.safetensors"),
    )
    .unwrap();
    assert_eq!(pick9.layout(), PickRefiner::bundled().unwrap().layout());
    let three = PickRefiner::bundled_chain()
        .unwrap()
        .followed_by(pick9)
        .unwrap();
    assert_eq!(three.passes(), 3);
}
