//! Writing datasets: the reference layout, byte-identical re-runs, resume,
//! shards, and clear errors that lose no finished frame.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)] // helpers of tests

use std::path::Path;

use omnimvs_synth::{DatasetWriter, FrameEvent, SceneKind, SceneSpec, Shard, SynthError, Tracer};

#[path = "support/datasets.rs"]
mod datasets;
use datasets::{files, small_rig};

fn writer(out: &Path, kind: SceneKind, seed: u64) -> Result<DatasetWriter, SynthError> {
    DatasetWriter::create(
        out,
        &small_rig(),
        kind,
        seed,
        1,
        &[],
        &"1..3".parse::<omnimvs_data::FrameRange>().unwrap(),
    )
}

#[test]
fn same_seed_gives_byte_identical_datasets_in_the_reference_layout() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    for dir in [a.path(), b.path()] {
        for kind in [SceneKind::Things, SceneKind::House] {
            let out = dir.join(kind.name());
            writer(&out, kind, 5).unwrap().run(&[1, 2], |_| {}).unwrap();
        }
    }
    let (fa, fb) = (files(a.path()), files(b.path()));
    // Per dataset: config.yaml, synth.json, 4 masks, then per frame 4 images, the ground
    // truth and the scene.
    assert_eq!(
        fa.len(),
        2 * (2 + 4 + 2 * 6),
        "{:?}",
        fa.keys().collect::<Vec<_>>()
    );
    assert!(fa.keys().all(|k| !k.contains(".tmp")));
    assert_eq!(fa, fb);
    assert!(fa.contains_key("things/cam4/00002.png"));
    assert!(fa.contains_key("house/omnidepth_gt_640/00001.tiff"));
    assert!(fa.contains_key("house/mask4.png"));
    assert_ne!(fa["things/cam1/00001.png"], fa["things/cam1/00002.png"]);

    // The foundation's reader opens it: images, ground truth, rig.
    let ds = omnimvs_data::Dataset::open(&a.path().join("things")).unwrap();
    let frame = ds.read_frame(2).unwrap();
    assert_eq!((frame[0].width, frame[0].height), (50, 48));
    let gt = ds.read_gt(2).unwrap().unwrap();
    assert_eq!((gt.width, gt.height), (640, 320));
    assert!(
        gt.data
            .iter()
            .all(|v| v.is_finite() && *v >= 0.0 && *v <= 1.0 / 1.65 + 1e-4)
    );

    // scene.json renders the same ground truth again.
    let text = std::fs::read_to_string(a.path().join("things/scene/00002.json")).unwrap();
    let scene: SceneSpec = serde_json::from_str(&text).unwrap();
    let tracer = Tracer::new(&scene, &[]).unwrap();
    let grid = omnimvs_sweep::EquirectGrid::new(320, 640, 90.0).unwrap();
    assert_eq!(omnimvs_synth::render_inverse_depth(&tracer, &grid), gt.data);
}

#[test]
fn rerun_resumes_and_shards_cover_the_range() {
    let dir = tempfile::tempdir().unwrap();
    let w = writer(dir.path(), SceneKind::Things, 1).unwrap();
    w.run(
        &Shard::parse("1/2")
            .unwrap()
            .frames(&"1..3".parse::<omnimvs_data::FrameRange>().unwrap()),
        |_| {},
    )
    .unwrap();
    let before = files(dir.path());
    std::fs::remove_file(dir.path().join("cam2/00003.png")).unwrap();
    let mut events = Vec::new();
    let w = writer(dir.path(), SceneKind::Things, 1).unwrap();
    w.run(&[1, 2, 3], |e| events.push(e)).unwrap();
    assert_eq!(
        events,
        vec![
            FrameEvent::Skipped(1),
            FrameEvent::Rendered(2),
            FrameEvent::Rendered(3)
        ]
    );
    let after = files(dir.path());
    for (k, v) in &before {
        assert_eq!(&after[k], v, "{k} changed on resume");
    }
}

#[test]
fn a_dataset_filled_in_several_runs_announces_every_frame() {
    // Validation frames first, then the rest: config.yaml must cover both runs, or readers
    // (which list the frames of the announced range) lose the first run's frames.
    let dir = tempfile::tempdir().unwrap();
    let create = |frames: &str| {
        DatasetWriter::create(
            dir.path(),
            &small_rig(),
            SceneKind::House,
            4,
            1,
            &[],
            &frames.parse::<omnimvs_data::FrameRange>().unwrap(),
        )
        .unwrap()
    };
    create("5..6").run(&[5, 6], |_| {}).unwrap();
    create("1..2").run(&[1, 2], |_| {}).unwrap();
    let ds = omnimvs_data::Dataset::open(dir.path()).unwrap();
    assert_eq!(ds.frames_found(), vec![1, 2, 5, 6]);
}

#[test]
fn bad_input_gives_clear_errors_and_keeps_finished_frames() {
    let dir = tempfile::tempdir().unwrap();
    // Unknown kind.
    let err = "room".parse::<SceneKind>().unwrap_err().to_string();
    assert!(err.contains("unknown kind \"room\""), "{err}");
    // Unreadable rig.
    let err = omnimvs_synth::rig::load_rig("/no/such/rig.yaml")
        .unwrap_err()
        .to_string();
    assert!(err.contains("/no/such/rig.yaml"), "{err}");
    // Reversed range.
    assert!(
        "9..3"
            .parse::<omnimvs_data::FrameRange>()
            .unwrap_err()
            .to_string()
            .contains("reversed")
    );
    // Output folder that cannot be created (a file is in the way).
    let blocker = dir.path().join("file");
    std::fs::write(&blocker, b"x").unwrap();
    let err = writer(&blocker.join("out"), SceneKind::Things, 1)
        .err()
        .unwrap()
        .to_string();
    assert!(
        err.contains("file/out") && err.contains("cannot create"),
        "{err}"
    );
    // Other settings in an existing dataset.
    let out = dir.path().join("ds");
    let w = writer(&out, SceneKind::Things, 1).unwrap();
    w.run(&[1], |_| {}).unwrap();
    let err = writer(&out, SceneKind::Things, 2)
        .err()
        .unwrap()
        .to_string();
    assert!(err.contains("seed 1 there, 2 now"), "{err}");
    // A write failing mid-frame (here: a folder where the ground truth
    // goes) names the file; frame 1 stays whole and no temporary is left.
    let frame1 = files(&out);
    std::fs::create_dir_all(out.join("omnidepth_gt_640/00002.tiff")).unwrap();
    let err = w.run(&[1, 2], |_| {}).unwrap_err().to_string();
    assert!(err.contains("00002.tiff"), "{err}");
    let now = files(&out);
    for (k, v) in &frame1 {
        assert_eq!(&now[k], v);
    }
    assert!(now.keys().all(|k| !k.contains(".tmp")));
    assert!(!w.is_complete(2));
}
