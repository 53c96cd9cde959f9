//! Writes a trained cascade with its coarse stage moved to another grid and spheres
//! ([`omnimvs_net::cascade::CascadeNet::with_coarse_grid`]): the coarse stage's first and
//! scoring convolutions resampled along the spheres, every other weight copied as it is. A
//! starting point for training (`omnimvs train --init OUT ...`), or for timing and studying
//! what the move costs before any training.
//!
//! ```text
//! cargo run --release -p omnimvs-net --example coarse_grid -- IN.safetensors OUT.safetensors SCALE SPHERES [CUE_DEPTHS]
//! ```
//! (the configuration JSON is read beside IN and written beside OUT; with `SCALE` 2 the coarse
//! cue is matched on the coarse grid itself, `coarse_cue_oversample` 1).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use burn::tensor::Device;
use omnimvs_net::weights;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: coarse_grid IN.safetensors OUT.safetensors SCALE SPHERES [CUE_DEPTHS]";
    if !(4..=5).contains(&args.len()) {
        eprintln!("{usage}");
        return ExitCode::from(2);
    }
    let number = |i: usize, what: &str| -> Result<usize, String> {
        args[i]
            .parse()
            .map_err(|_| format!("{what}: expected a whole number, got {:?}", args[i]))
    };
    let parsed = (|| -> Result<(usize, usize, Option<usize>), String> {
        let depths = if args.len() == 5 {
            Some(number(4, "CUE_DEPTHS")?)
        } else {
            None
        };
        Ok((number(2, "SCALE")?, number(3, "SPHERES")?, depths))
    })();
    let result = parsed.and_then(|(scale, spheres, depths)| {
        run(
            &PathBuf::from(&args[0]),
            &PathBuf::from(&args[1]),
            scale,
            spheres,
            depths,
        )
    });
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(
    input: &Path,
    output: &Path,
    scale: usize,
    spheres: usize,
    depths: Option<usize>,
) -> Result<(), String> {
    let mut config =
        weights::read_config(&weights::config_path(input)).map_err(|e| e.to_string())?;
    config.cascade.coarse_scale = scale;
    config.cascade.coarse_spheres = spheres;
    if scale == 2 {
        config.cascade.coarse_cue_oversample = 1;
    }
    if let Some(depths) = depths {
        config.cascade.coarse_cue_depths = depths;
    }
    let device = Device::flex();
    let net = weights::load_cascade_grown(input, &config, &device).map_err(|e| e.to_string())?;
    weights::save_module(&net, &config, output).map_err(|e| e.to_string())?;
    let [coarse, _, _] = config.cascade_sizes();
    println!(
        "wrote {} (coarse stage {}x{} over {spheres} spheres)",
        output.display(),
        coarse[0],
        coarse[1]
    );
    Ok(())
}
