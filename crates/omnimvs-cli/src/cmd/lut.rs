//! `omnimvs lut`: write the lookup table in the reference `.hwd` layout.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use omnimvs_sweep::{LookupTable, SphereSet};

use crate::args::SweepArgs;

/// Build the spherical-sweep lookup table of a dataset's rig (the reference `.hwd` file).
///
/// The file is the reference `lt_(h,w,N).hwd`: raw little-endian f32 of shape
/// [cameras, N/2, h, w, 2], sampling positions normalised for
/// grid_sample(align_corners=True); invalid entries far outside [-1, 1].
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder, or a rig file alone (config.yaml, Basalt calibration.json, Kalibr
    /// camchain.yaml): the table needs no images.
    pub dataset: PathBuf,
    /// Output grid and hypotheses.
    #[command(flatten)]
    pub sweep: SweepArgs,
    /// Write all N spheres instead of every other one (not the reference layout).
    #[arg(long)]
    pub all_spheres: bool,
    /// Output file (conventionally named lt_(h,w,N).hwd).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    // The table needs the rig alone: a calibration file without images will do.
    let ds = datasets.open_rig_only(&args.dataset)?;
    if args.sweep.ndepth < 2 || (!args.all_spheres && !args.sweep.ndepth.is_multiple_of(2)) {
        bail!(
            "--ndepth {}: expected an even number of at least 2 (the file holds every other sphere)",
            args.sweep.ndepth
        );
    }
    let spec = args.sweep.spec(&ds)?;
    let (grid, hyps) = (spec.grid, spec.hypotheses);
    let set = if args.all_spheres {
        SphereSet::All
    } else {
        SphereSet::EveryOther
    };
    let t0 = Instant::now();
    let lut = LookupTable::build(&ds.rig, &grid, &hyps, set)?;
    let build_s = t0.elapsed().as_secs_f64();
    lut.write_hwd(&args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let invalid = lut
        .data
        .chunks_exact(2)
        .filter(|p| p[0] < -2.0 || p[1] < -2.0)
        .count();
    outln!(
        "wrote {} ({} cameras x {} spheres x {}x{} x 2 f32, {:.1} MB) in {:.2} s build; {:.1}% of entries invalid",
        args.out.display(),
        lut.num_cameras(),
        lut.num_spheres(),
        grid.height,
        grid.width,
        lut.byte_len() as f64 / 1e6,
        build_s,
        100.0 * invalid as f64 / (lut.data.len() / 2) as f64
    );
    Ok(())
}
