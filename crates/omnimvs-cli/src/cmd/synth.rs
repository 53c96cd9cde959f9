//! `omnimvs synth`: render a synthetic omnidirectional stereo dataset.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use omnimvs_data::FrameRange;
use omnimvs_synth::rig::{load_rig, resize_rig};
use omnimvs_synth::{DatasetWriter, FrameEvent, SceneKind, Shard};

use crate::args::{Frames, Size};

/// Render a synthetic dataset (OmniThings / OmniHouse style) for a rig:
/// OUT/config.yaml, OUT/camN/%05d.png (8-bit gray fisheyes),
/// OUT/omnidepth_gt_640/%05d.tiff (f32 inverse depth, 1/m, 320x640, +-90
/// degrees, 0 = sky), OUT/scene/%05d.json (the scene) and OUT/synth.json.
/// Frames already complete in OUT are skipped, so an interrupted run resumes.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scene kind: `things` (random objects in a room or under a sky) or
    /// `house` (furnished rooms).
    #[arg(long)]
    pub kind: String,
    /// The rig: `sunny` (the published rig) or a reference config.yaml
    /// (its `config.omnimvs_sweep_min_depth` is the minimum depth).
    #[arg(long, default_value = "sunny")]
    pub rig: String,
    /// Frames, A..B (inclusive) or a single frame.
    #[arg(long)]
    pub frames: Frames,
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

pub fn run(args: &Args) -> Result<()> {
    let kind: SceneKind = args.kind.parse()?;
    let mut source = load_rig(&args.rig).with_context(|| format!("--rig {}", args.rig))?;
    if let Some(size) = args.size {
        let (h, w) = (u32::try_from(size.height)?, u32::try_from(size.width)?);
        source.rig = resize_rig(&source.rig, h, w)?;
    }
    let range = FrameRange {
        start: *args.frames.0.start(),
        step: 1,
        end: *args.frames.0.end(),
    };
    let shard = match &args.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    let frames = shard.frames(&range);
    let meshes: Vec<String> = args
        .meshes
        .iter()
        .map(|p| p.to_string_lossy().into_owned())
        .collect();
    let writer = DatasetWriter::create(
        &args.out, &source, kind, args.seed, args.spp, &meshes, &range,
    )?;

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
            args.out.display()
        )
    })?;
    let secs = t0.elapsed().as_secs_f64();
    println!(
        "{}: {rendered} frame(s) rendered in {secs:.1} s ({:.2} s/frame), {skipped} already complete; shard {}/{} of frames {}..{}",
        args.out.display(),
        secs / rendered.max(1) as f64,
        shard.index,
        shard.count,
        range.start,
        range.end
    );
    Ok(())
}
