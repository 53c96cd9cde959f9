//! Writes a trained cascade with its coarse evidence squeezed through `CHANNELS` channels
//! before the first 3x3 convolution ([`omnimvs_net::cascade::CascadeNet::with_coarse_squeeze`]:
//! a truncated SVD of that layer), every other weight copied as it is, and prints the share
//! of the layer's weight energy (sum of squared singular values) the rank keeps. A starting
//! point for training (`omnimvs train --init OUT ...`), or for timing and scoring the
//! factorisation before any training.
//!
//! ```text
//! cargo run --release -p omnimvs-net --example coarse_squeeze -- IN.safetensors OUT.safetensors CHANNELS
//! ```
//! (the configuration JSON is read beside IN and written beside OUT).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use burn::tensor::Device;
use omnimvs_net::tensor::read_values;
use omnimvs_net::weights;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 3 {
        eprintln!("usage: coarse_squeeze IN.safetensors OUT.safetensors CHANNELS");
        return ExitCode::from(2);
    }
    let result = args[2]
        .parse::<usize>()
        .map_err(|_| format!("CHANNELS: expected a whole number, got {:?}", args[2]))
        .and_then(|k| run(&PathBuf::from(&args[0]), &PathBuf::from(&args[1]), k));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(input: &Path, output: &Path, channels: usize) -> Result<(), String> {
    let before = weights::load_cascade(input, &Device::flex()).map_err(|e| e.to_string())?;
    let net = before
        .clone()
        .with_coarse_squeeze(channels)
        .map_err(|e| e.to_string())?;
    let config = net.config.clone();
    // The energy kept: |A B|^2 / |W|^2 with W the original layer, A B its factorisation
    // (the factorisation is orthogonal, so this is the kept singular values' share).
    let energy = |v: Vec<f32>| v.iter().map(|&x| f64::from(x) * f64::from(x)).sum::<f64>();
    let w =
        read_values(before.coarse.c0[0].conv.weight.val(), "weights").map_err(|e| e.to_string())?;
    let a =
        read_values(net.coarse.c0[0].conv.weight.val(), "weights").map_err(|e| e.to_string())?;
    weights::save_module(&net, &config, output).map_err(|e| e.to_string())?;
    println!(
        "wrote {} (coarse evidence squeezed to {channels} channels; the layer keeps {:.2} % of its weight energy)",
        output.display(),
        100.0 * energy(a) / energy(w)
    );
    Ok(())
}
