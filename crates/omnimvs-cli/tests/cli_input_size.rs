//! `omnimvs infer --input-size`: a reference checkpoint runs at the cameras' native image size
//! by default (as the reference runs it), our models at the size they were trained at, and
//! either can be told, also as the size of the angular resolution the model was trained at;
//! `infer.json` records what was used.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sample() -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/omnimvs-samples/sunny_single");
    assert!(
        path.join("config.yaml").is_file(),
        "this test needs the real sample {} (../shared beside the repository)",
        path.display()
    );
    path
}

fn checkpoint() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../omnimvs-net/tests/fixtures/parity/parity.pt")
}

fn infer(out: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "infer".to_string(),
        sample().display().to_string(),
        "--frames".into(),
        "1".into(),
        "--out".into(),
        out.display().to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    Command::new(env!("CARGO_BIN_EXE_omnimvs"))
        .args(&args)
        .env("OMNIMVS_CACHE_DIR", out.parent().unwrap().join("cache"))
        .output()
        .unwrap()
}

fn used_size(out: &Path) -> Vec<usize> {
    let text = std::fs::read_to_string(out.join("infer.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json["input_size"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap() as usize)
        .collect()
}

#[test]
fn reference_checkpoints_run_at_native_size_and_every_size_can_be_asked() {
    let dir = tempfile::tempdir().unwrap();
    let pt = checkpoint().display().to_string();
    let cases: [(&str, &[&str], [usize; 2]); 5] = [
        // A reference checkpoint: the cameras' own 768x800, as the reference runs it.
        (
            "pt-default",
            &["--weights", &pt, "--preset", "tiny"],
            [768, 800],
        ),
        (
            "pt-model",
            &[
                "--weights",
                &pt,
                "--preset",
                "tiny",
                "--input-size",
                "model",
            ],
            [192, 200],
        ),
        (
            "pt-fixed",
            &[
                "--weights",
                &pt,
                "--preset",
                "tiny",
                "--input-size",
                "384x400",
            ],
            [384, 400],
        ),
        // Our bundled model: the size it was trained at.
        ("tiny-default", &["--weights", "tiny"], [192, 200]),
        // The published rig's own cameras: the angular resolution the model was trained at is
        // the one they show at the model's size.
        (
            "tiny-angular",
            &["--weights", "tiny", "--input-size", "angular"],
            [192, 200],
        ),
    ];
    for (name, extra, expected) in cases {
        let out = dir.path().join(name);
        let o = infer(&out, extra);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        assert_eq!(used_size(&out), expected, "{name}");
        assert!(out.join("00001.tiff").is_file(), "{name}");
    }

    let out = dir.path().join("bad");
    let o = infer(&out, &["--input-size", "768"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--input-size") && err.contains("native") && err.contains("HEIGHTxWIDTH"),
        "{err}"
    );
}
