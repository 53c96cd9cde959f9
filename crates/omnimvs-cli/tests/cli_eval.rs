//! `omnimvs eval` end to end on a small generated dataset: every method at its own grid,
//! scored at one evaluation grid, in two tables (the reference's protocol, then with sky).

#![allow(clippy::unwrap_used, clippy::expect_used)] // helpers of tests

use std::path::Path;
use std::process::{Command, Output};

fn omnimvs(args: &[&str], cache: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_omnimvs"))
        .args(args)
        .env("OMNIMVS_CACHE_DIR", cache)
        .output()
        .unwrap()
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn eval_prints_both_protocols_at_one_grid() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let data = dir.path().join("things");
    let data_s = data.to_str().unwrap();
    let o = omnimvs(
        &[
            "synth", "--kind", "things", "--frames", "1..2", "--out", data_s, "--size", "96x100",
            "--seed", "5",
        ],
        &cache,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));

    // A small evaluation grid keeps SGM fast; the default bundled network, the cascade,
    // answers at 160x640, N = 192, and is resampled to it.
    let out = dir.path().join("eval");
    let o = omnimvs(
        &[
            "eval",
            "--data",
            data_s,
            "--method",
            "net,sgm",
            "--frames",
            "1..2",
            "--size",
            "40x160",
            "--ndepth",
            "48",
            "--out",
            out.to_str().unwrap(),
        ],
        &cache,
    );
    let stdout = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let reference = stdout.find("Protocol `reference`").expect(&stdout);
    let with_sky = stdout.find("Protocol `with-sky`").expect(&stdout);
    assert!(
        reference < with_sky,
        "the reference's table first: {stdout}"
    );
    assert!(
        stdout.contains("evaluation grid 40x160 (+-45 deg), N = 48"),
        "{stdout}"
    );
    for table in [&stdout[reference..with_sky], &stdout[with_sky..]] {
        assert!(table.contains("| method | >1 (%) |"), "{table}");
        assert!(
            table.contains("| net, native 160x640, N = 192 | "),
            "{table}"
        );
        assert!(
            table.contains("| ZNCC+SGM, native 40x160, N = 48 | "),
            "{table}"
        );
    }
    let md = std::fs::read_to_string(out.join("eval.md")).unwrap();
    assert!(md.contains("Protocol `reference`") && md.contains("Protocol `with-sky`"));

    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("eval.json")).unwrap()).unwrap();
    assert_eq!(report["height"], 40, "{report}");
    assert_eq!(
        (report["width"].as_u64(), report["ndepth"].as_u64()),
        (Some(160), Some(48))
    );
    assert_eq!(report["protocol"], "reference");
    let net = &report["methods"][0];
    assert_eq!(net["method"], "net");
    assert_eq!(
        (
            net["native"]["height"].as_u64(),
            net["native"]["width"].as_u64()
        ),
        (Some(160), Some(640))
    );
    assert_eq!(
        (net["native"]["ndepth"].as_u64(), &net["resampled"]),
        (Some(192), &true.into())
    );
    let sgm = &report["methods"][1];
    assert_eq!(
        (sgm["native"]["height"].as_u64(), &sgm["resampled"]),
        (Some(40), &false.into())
    );
    // Both methods are scored on the same pixels; scoring sky adds pixels, never removes any.
    let pixels = |m: &serde_json::Value, key: &str| m[key]["valid_pixels"].as_u64().unwrap();
    assert_eq!(pixels(net, "metrics"), pixels(sgm, "metrics"));
    assert!(pixels(net, "metrics_with_sky") >= pixels(net, "metrics"));
    assert!(pixels(net, "metrics") > 0 && pixels(net, "metrics") <= 2 * 40 * 160);
    for m in [net, sgm] {
        let mae = m["metrics"]["mae"].as_f64().unwrap();
        assert!(mae.is_finite() && mae > 0.0 && mae < 100.0, "{m}");
        assert_eq!(m["per_frame"].as_array().unwrap().len(), 2);
    }

    // Without --size/--ndepth, the paper's grid.
    let out = dir.path().join("eval-default");
    let out_s = out.to_str().unwrap();
    let o = omnimvs(
        &[
            "eval", "--data", data_s, "--method", "net", "--frames", "1", "--out", out_s,
        ],
        &cache,
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("eval.json")).unwrap()).unwrap();
    assert_eq!(
        (
            report["height"].as_u64(),
            report["width"].as_u64(),
            report["ndepth"].as_u64()
        ),
        (Some(160), Some(640), Some(192)),
        "{report}"
    );
}
