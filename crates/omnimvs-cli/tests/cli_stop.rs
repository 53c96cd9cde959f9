#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! Ctrl-C during `omnimvs sgm` ends the run after the frames in flight: every frame on disk is
//! complete and listed in `sgm.json`, the frames not reached are not written, the exit status
//! is non-zero and the message says so. A finished run sums up its frames per second and each
//! stage's time.

mod support;

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use support::{read_json, run_ok, synth_dataset, text};

#[test]
fn ctrl_c_stops_after_the_frames_in_flight_with_every_written_frame_complete() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1..24", "96x100", 11);
    let out = dir.path().join("sgm");
    let child = Command::new(env!("CARGO_BIN_EXE_omnimvs"))
        .args([
            "sgm",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--size",
            "64x256",
            "--ndepth",
            "64",
        ])
        .env("OMNIMVS_CACHE_DIR", &cache)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Ctrl-C once the first frame is on disk.
    let started = Instant::now();
    while !out.join("00001.tiff").exists() {
        assert!(
            started.elapsed() < Duration::from_secs(600),
            "no frame written"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let o = child.wait_with_output().unwrap();
    let err = text(&o.stderr);
    assert!(!o.status.success(), "{err}");
    assert!(err.contains("stopped by Ctrl-C"), "{err}");
    let record = read_json(&out.join("sgm.json"));
    let listed: Vec<u64> = record["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["frame"].as_u64().unwrap())
        .collect();
    assert!(!listed.is_empty() && listed.len() < 24, "{listed:?}");
    for f in 1..=24u64 {
        let tiff = out.join(format!("{f:05}.tiff"));
        if listed.contains(&f) {
            let map = omnimvs_data::gt::read_inv_depth(&tiff).unwrap();
            assert_eq!((map.width, map.height), (256, 64), "frame {f}");
        } else {
            assert!(!tiff.exists(), "frame {f} written but not listed");
        }
    }
    // Not a temporary file left behind.
    for entry in std::fs::read_dir(&out).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!name.contains(".tmp"), "{name}");
    }

    // A run that finishes sums itself up.
    let whole = run_ok(
        &[
            "sgm",
            data.to_str().unwrap(),
            "--frames",
            "1..2",
            "--out",
            dir.path().join("two").to_str().unwrap(),
            "--size",
            "64x256",
            "--ndepth",
            "64",
        ],
        &cache,
    );
    assert!(
        whole.contains("2 frame(s) in") && whole.contains("frames/s"),
        "{whole}"
    );
}
