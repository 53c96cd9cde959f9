//! Heavy checks at the paper preset (CH 32, N 192, 160x640, four 768x800 inputs); ignored by
//! default: `cargo test --release -p omnimvs-net --test paper -- --ignored`.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers

use burn::tensor::Device;
use omnimvs_net::NetConfig;
use omnimvs_net::bench::bench_forward;

/// The memory budget for paper-preset inference on the CPU.
const BUDGET_BYTES: u64 = 4 << 30;

#[test]
#[ignore = "paper preset: minutes of CPU and about 2 GB of memory"]
fn paper_preset_inference_fits_in_4_gb() {
    let report = bench_forward(&NetConfig::paper(), 0, true, &Device::flex()).unwrap();
    let peak = report
        .peak_rss_bytes
        .expect("peak RSS is read from /proc on Linux");
    eprintln!("paper preset peak RSS: {} MiB", peak >> 20);
    assert!(
        peak < BUDGET_BYTES,
        "peak RSS {} MiB over the 4 GiB budget",
        peak >> 20
    );
}
