//! Writes a cascade whose learnt upsampling serves both grids as one that keeps it on the
//! half-resolution grid only (`convex_upsampling_full` off): the full-resolution stage then
//! centres on the bilinear upsampling of the half stage, and the full grid's selector, the
//! dearer one, is left out. Every other weight is copied as it is.
//!
//! ```text
//! cargo run --release -p omnimvs-net --example half_grid_selector -- IN.safetensors OUT.safetensors
//! ```
//! (the configuration JSON is read beside IN and written beside OUT).

use std::path::PathBuf;
use std::process::ExitCode;

use burn::tensor::Device;
use omnimvs_net::weights;

fn main() -> ExitCode {
    let args: Vec<PathBuf> = std::env::args_os().skip(1).map(PathBuf::from).collect();
    let [input, output] = args.as_slice() else {
        eprintln!("usage: half_grid_selector IN.safetensors OUT.safetensors");
        return ExitCode::from(2);
    };
    match run(input, output) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(input: &std::path::Path, output: &std::path::Path) -> Result<(), String> {
    let mut config =
        weights::read_config(&weights::config_path(input)).map_err(|e| e.to_string())?;
    if !config.cascade.convex_upsampling || !config.cascade.convex_upsampling_full {
        return Err(format!(
            "{}: `cascade.convex_upsampling` must be on for both grids (the file's network has \
             no full-resolution selector to leave out)",
            weights::config_path(input).display()
        ));
    }
    config.cascade.convex_upsampling_full = false;
    let device = Device::flex();
    let net = weights::load_cascade_grown(input, &config, &device).map_err(|e| e.to_string())?;
    weights::save_module(&net, &config, output).map_err(|e| e.to_string())?;
    println!(
        "wrote {} (the half-resolution selector only)",
        output.display()
    );
    Ok(())
}
