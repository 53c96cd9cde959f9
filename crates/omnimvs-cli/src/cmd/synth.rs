//! `omnimvs synth`: render a synthetic omnidirectional stereo dataset.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_data::FrameRange;
use omnimvs_synth::rig::RigSource;
use omnimvs_synth::{DatasetWriter, Difficulty, FrameEvent, Shard, SynthOptions};

use crate::args::{Kind, RigArg, Size};

/// Render a synthetic dataset (OmniThings / OmniHouse style) with exact ground truth.
///
/// Render a synthetic dataset (OmniThings / OmniHouse style) for a rig:
/// OUT/config.yaml, OUT/camN/%05d.png (8-bit gray fisheyes),
/// OUT/omnidepth_gt_640/%05d.tiff (f32 inverse depth, 1/m, 320x640, +-90
/// degrees, 0 = sky), OUT/scene/%05d.json (the scene) and OUT/synth.json.
/// Frames already complete in OUT are skipped, so an interrupted run resumes.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// `--kind` and `--difficulty` (grouped so that callers building these
    /// arguments in code, like `demo`, write `kind: Kind::Things.into()` and get
    /// the `standard` difficulty).
    #[command(flatten)]
    pub kind: SceneArgs,
    /// The rig: `sunny` (the published rig) or a rig file: a reference config.yaml (its
    /// `config.omnimvs_sweep_min_depth` is the minimum depth), a Basalt calibration.json or a
    /// Kalibr camchain.yaml (minimum depth 0.55 m), or `random:SEED`: a rig drawn from the seed
    /// (2-8 cameras on a ring 0.05-0.6 m apart, one lens model of ds, eucm, ucm and kb4 seeing
    /// 180-250 degrees, 480-1216 px, tilts up to 15 degrees, and in half the rigs a small
    /// calibration error in the written config.yaml); `--min-depth` replaces the minimum depth,
    /// `--rig-frame fitted` re-expresses the rig in the frame fitted to its cameras.
    #[arg(long, default_value = "sunny", value_parser = RigArg::parse)]
    pub rig: RigArg,
    /// Frames, A..B (inclusive) or a single frame.
    #[arg(long)]
    pub frames: FrameRange,
    /// Output folder.
    #[arg(long)]
    pub out: PathBuf,
    /// Dataset seed: the same seed and frame give byte-identical files.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Image size HxW of every camera (default: the rig's own); the rig's
    /// intrinsics are rescaled to it.
    #[arg(long)]
    pub size: Option<Size>,
    /// Samples per pixel (anti-aliasing).
    #[arg(long, default_value_t = 1)]
    pub spp: u32,
    /// Render only part i of n of the frames (i from 1), e.g. 2/4, to split a
    /// dataset across machines writing to the same layout.
    #[arg(long)]
    pub shard: Option<String>,
    /// A user mesh (.obj or .ply) that `things` scenes may place; repeatable.
    #[arg(long = "mesh")]
    pub meshes: Vec<PathBuf>,
}

/// What scenes a dataset holds: their kind and how hard they are.
#[derive(Debug, Clone, clap::Args)]
pub struct SceneArgs {
    /// Scene kind: `things` (random objects in a room or under a sky) or
    /// `house` (furnished rooms).
    #[arg(long, value_enum)]
    pub kind: Kind,
    /// `standard`: rich textures, mostly convex shapes, even light, ideal
    /// cameras (the datasets made before this option). `hard`: flat,
    /// repetitive and dark textures, thin and concave shapes, several
    /// falling-off lights, and per-camera gain, gamma, vignetting, blur and
    /// noise on the images (ground truth unchanged). Recorded in synth.json.
    #[arg(long, value_enum, default_value_t = DifficultyArg::Standard)]
    pub difficulty: DifficultyArg,
}

impl From<Kind> for SceneArgs {
    /// A kind at the `standard` difficulty.
    fn from(kind: Kind) -> Self {
        Self {
            kind,
            difficulty: DifficultyArg::Standard,
        }
    }
}

/// `--difficulty` (the library's [`Difficulty`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DifficultyArg {
    Standard,
    Hard,
}

impl From<DifficultyArg> for Difficulty {
    fn from(d: DifficultyArg) -> Self {
        match d {
            DifficultyArg::Standard => Self::Standard,
            DifficultyArg::Hard => Self::Hard,
        }
    }
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    let options = datasets.options();
    let mut source = args
        .rig
        .load(options.min_depth_m, options.frame)
        .with_context(|| format!("--rig {}", args.rig))?;
    if let Some(size) = args.size {
        let (h, w) = (u32::try_from(size.height)?, u32::try_from(size.width)?);
        source = source.resized(h, w).context("--size")?;
    }
    let range = args.frames;
    let shard = match &args.shard {
        Some(s) => Shard::parse(s).context("--shard")?,
        None => Shard::ALL,
    };
    let meshes: Vec<String> = args
        .meshes
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let options = SynthOptions {
        spp: args.spp,
        meshes,
        difficulty: args.kind.difficulty.into(),
        ..SynthOptions::new(args.kind.kind.into(), args.seed)
    };
    render(&args.out, &source, &options, range, shard)
}

/// Renders `shard` of the frames `range` of the dataset `out` (created, or resumed where it
/// stopped) with a progress bar, then prints what it did.
///
/// # Errors
/// A folder that holds another dataset, a rig the renderer cannot take, a file that cannot
/// be written.
pub fn render(
    out: &Path,
    source: &RigSource,
    options: &SynthOptions,
    range: FrameRange,
    shard: Shard,
) -> Result<()> {
    let frames = shard.frames(&range);
    let writer = DatasetWriter::create_with(out, source, options, &range)?;

    let bar = ProgressBar::new(frames.len() as u64);
    bar.set_style(ProgressStyle::with_template(
        "{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} frames, {per_sec}, ETA {eta}",
    )?);
    let (mut rendered, mut skipped) = (0usize, 0usize);
    let t0 = Instant::now();
    let result = writer.run(&frames, |e| {
        match e {
            FrameEvent::Rendered(_) => rendered += 1,
            FrameEvent::Skipped(_) => skipped += 1,
        }
        bar.inc(1);
    });
    bar.finish_and_clear();
    result.with_context(|| {
        format!(
            "after {rendered} new frame(s) (all finished frames are kept; run again to resume) in {}",
            out.display()
        )
    })?;
    let secs = t0.elapsed().as_secs_f64();
    outln!(
        "{}: {rendered} frame(s) rendered in {secs:.1} s ({:.2} s/frame), {skipped} already complete; shard {}/{} of frames {}..{}",
        out.display(),
        secs / rendered.max(1) as f64,
        shard.index,
        shard.count,
        range.start,
        range.end
    );
    Ok(())
}
