#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)]
//! `--speed fast|balanced|accurate` of `sgm` and `infer` are the settings they name: the same
//! files as the explicit options, byte for byte; `eval --speed` scores them; given beside those
//! options they are refused.

mod support;

use std::path::Path;

use support::{omnimvs, run_ok, synth_dataset, text};

fn same_file(a: &Path, b: &Path) {
    assert_eq!(
        std::fs::read(a).unwrap(),
        std::fs::read(b).unwrap(),
        "{} and {}",
        a.display(),
        b.display()
    );
}

#[test]
fn speed_presets_are_the_settings_they_name() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = synth_dataset(dir.path(), "things", "1", "96x100", 5);
    let data_s = data.to_str().unwrap();
    let out = |name: &str| dir.path().join(name);
    let run = |cmd: &str, name: &str, extra: &[&str]| {
        let o = out(name);
        let mut args = vec![cmd, data_s, "--frames", "1", "--out", o.to_str().unwrap()];
        args.extend_from_slice(extra);
        run_ok(&args, &cache);
    };
    run("sgm", "sgm-fast", &["--speed", "fast"]);
    run("sgm", "sgm-32", &["--ndepth", "32"]);
    same_file(&out("sgm-fast/00001.tiff"), &out("sgm-32/00001.tiff"));
    run("infer", "net-balanced", &["--speed", "balanced"]);
    run("infer", "net-off", &["--pick", "off"]);
    same_file(&out("net-balanced/00001.tiff"), &out("net-off/00001.tiff"));
    run("infer", "net-fast", &["--speed", "fast"]);
    run(
        "infer",
        "net-half",
        &["--pick", "off", "--input-size", "384x400"],
    );
    same_file(&out("net-fast/00001.tiff"), &out("net-half/00001.tiff"));

    // eval scores a preset's rows: ZNCC+SGM over its 32 spheres, in the evaluation's N.
    let eval = out("eval");
    run_ok(
        &[
            "eval",
            "--data",
            data_s,
            "--frames",
            "1",
            "--method",
            "sgm",
            "--speed",
            "fast",
            "--out",
            eval.to_str().unwrap(),
        ],
        &cache,
    );
    let report = support::read_json(&eval.join("eval.json"));
    assert_eq!(report["methods"][0]["native"]["ndepth"], 32, "{report}");
    assert_eq!(report["ndepth"], 192, "{report}");

    for args in [
        vec![
            "sgm", data_s, "--out", "x", "--speed", "fast", "--ndepth", "64",
        ],
        vec![
            "infer", data_s, "--frames", "1", "--out", "x", "--speed", "fast", "--pick", "off",
        ],
        vec!["sgm", data_s, "--out", "x", "--speed", "quick"],
    ] {
        let o = omnimvs(&args, &cache);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(text(&o.stderr).contains("--speed"), "{}", text(&o.stderr));
    }
}
