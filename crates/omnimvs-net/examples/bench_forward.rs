//! Forward-pass timings per stage and peak memory on the CPU (`flex`) backend.
//!
//! `cargo run --release -p omnimvs-net --example bench_forward -- [tiny|paper] [repeats] [--no-fold]`

use burn::tensor::Device;
use omnimvs_net::NetConfig;
use omnimvs_net::bench::bench_forward;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let preset = args.first().map_or("tiny", String::as_str);
    let repeats = args.get(1).and_then(|r| r.parse().ok()).unwrap_or(3);
    let fold = !args.iter().any(|a| a == "--no-fold");
    let config = NetConfig::preset(preset)?;
    let report = bench_forward(&config, repeats, fold, &Device::flex())?;
    for run in &report.runs {
        println!(
            "run     features {:.3}s sweep {:.3}s fusion {:.3}s cost {:.3}s softargmin {:.3}s total {:.3}s",
            run.features, run.sweep, run.fusion, run.cost, run.softargmin, run.total
        );
    }
    if let Some(m) = report.median() {
        println!(
            "median  features {:.3}s sweep {:.3}s fusion {:.3}s cost {:.3}s softargmin {:.3}s total {:.3}s",
            m.features, m.sweep, m.fusion, m.cost, m.softargmin, m.total
        );
    }
    if let Some(peak) = report.peak_rss_bytes {
        println!("peak RSS {} MiB", peak / (1 << 20));
    }
    println!(
        "preset {preset}, folded batch norm {fold}, valid sweep samples {:.1}%",
        100.0 * report.valid_fraction
    );
    Ok(())
}
