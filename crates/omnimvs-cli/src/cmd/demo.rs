//! `omnimvs demo`: the whole pipeline on a bundled default, in one command.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use omnimvs_camera::fs::write_atomic;
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::gt::read_inv_depth;
use omnimvs_data::image_io::write_png_u8;
use omnimvs_data::metrics::{ProtocolMetrics, eval_metrics};
use omnimvs_data::ply::write_ply;
use omnimvs_data::{Dataset, FrameRange};
use omnimvs_sweep::{EquirectGrid, InvDepthSource, compose_panorama};

use crate::args::{Kind, Method, Preset, RigArg, Size};
use crate::cmd::eval::protocol_tables;
use crate::cmd::{eval, infer, sgm, synth};
use crate::pictures::{error_map, fisheye_strip, gray_to_rgb, label_rows, point_cloud};
use crate::weights::Weights;
use omnimvs_net::BundledModel;

/// Run the whole pipeline on a rendered scene (no data needed) and print its metrics.
///
/// Run the pipeline end to end on a default that needs nothing but this
/// repository: render a few frames of a synthetic `things` scene with exact
/// ground truth for the published 4-camera rig, estimate 360-degree depth with
/// the classical method (ZNCC + SGM) and with the bundled network; print the
/// paper's metrics tables (the reference's protocol, and with sky scored); write pictures (inputs, panorama, ground truth,
/// estimates, error maps) and a PLY point cloud. If the reference samples are beside the repository
/// (../shared/data/omnimvs-samples), the real itbt_sample frame 1 is
/// processed as well.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Output folder (created; existing demo files are replaced).
    #[arg(long, default_value = "demo-out")]
    pub out: PathBuf,
    /// Number of synthetic frames.
    #[arg(long, default_value_t = 2)]
    pub frames: u32,
    /// Seed of the synthetic scenes.
    #[arg(long, default_value_t = 2026)]
    pub seed: u64,
    /// Output grid, HEIGHTxWIDTH.
    #[arg(long, default_value = "160x640")]
    pub size: Size,
    /// Number of inverse-depth hypotheses for the classical method.
    #[arg(long, default_value_t = 192)]
    pub ndepth: usize,
    /// Folder of the reference samples (skipped when absent).
    #[arg(long, default_value = "../shared/data/omnimvs-samples")]
    pub samples: PathBuf,
}

pub fn run(args: &Args) -> Result<()> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let t0 = Instant::now();
    let data_dir = args.out.join("things");
    outln!(
        "[1/5] rendering {} synthetic `things` frames (published rig, 4 x 768x800) into {}",
        args.frames,
        data_dir.display()
    );
    synth::run(&synth::Args {
        kind: Kind::Things.into(),
        rig: RigArg::Published,
        frames: FrameRange::inclusive(1, args.frames),
        out: data_dir.clone(),
        seed: args.seed,
        size: None,
        spp: 1,
        shard: None,
        meshes: Vec::new(),
    })?;

    outln!(
        "[2/5] classical method (ZNCC + SGM), {}x{}, N = {}",
        args.size.height,
        args.size.width,
        args.ndepth
    );
    let sgm_dir = args.out.join("sgm");
    sgm::run(&sgm_args(
        &data_dir,
        &sgm_dir,
        args,
        Some(FrameRange::inclusive(1, args.frames)),
    ))?;

    outln!("[3/5] metrics and pictures of the classical method at full size");
    let ds = Dataset::open(&data_dir)?;
    let grid = EquirectGrid::new(args.size.height, args.size.width, 45.0)?;
    let hyps = ds.hypotheses(args.ndepth)?;
    let masks = ds.masks()?;
    let mut frame_metrics_sgm = Vec::new();
    for frame in 1..=args.frames {
        let images = ds.read_frame(frame)?;
        let index = read_inv_depth(&sgm_dir.join(format!("{frame:05}_index.tiff")))?;
        let inv = read_inv_depth(&sgm_dir.join(format!("{frame:05}.tiff")))?;
        let truth = ds
            .eval_truth(frame, &grid, &hyps)?
            .context("the synthetic frame has no ground truth")?;
        frame_metrics_sgm.push(eval_metrics(&index.data, &truth, args.ndepth)?);
        let gt = &truth.gt;
        let pano = compose_panorama(
            &ds.rig,
            &grid,
            &images,
            Some(&masks),
            InvDepthSource::Map(&inv.data),
        )?;
        let gt_inv: Vec<f32> = gt
            .index
            .iter()
            .map(|&n| hyps.inv_depth(f64::from(n)) as f32)
            .collect();
        let max_inv = hyps.max_inv_depth();
        let rows: Vec<(String, Vec<u8>)> = vec![
            ("inputs".into(), fisheye_strip(&images, grid.width)),
            (
                "panorama at the estimated depth".into(),
                gray_to_rgb(&pano.image),
            ),
            (
                "ground truth".into(),
                colorize(&gt_inv, 0.0, max_inv, Colormap::Turbo, Some(&gt.valid)),
            ),
            (
                "ZNCC+SGM".into(),
                colorize(&inv.data, 0.0, max_inv, Colormap::Turbo, None),
            ),
            (
                "ZNCC+SGM error".into(),
                error_map(&index.data, gt, args.ndepth),
            ),
        ];
        let (px, height) = label_rows(&rows, grid.width);
        let path = args.out.join(format!("things_{frame:05}.png"));
        write_png_u8(&path, grid.width, height, 3, &px)?;
        write_ply(
            &args.out.join(format!("things_{frame:05}_sgm.ply")),
            &point_cloud(&grid, &inv.data, &pano.image.data),
        )?;
        outln!("  wrote {} and its point cloud", path.display());
    }
    let rows: Vec<(String, ProtocolMetrics)> = ProtocolMetrics::mean(&frame_metrics_sgm)
        .map(|mean| ("ZNCC+SGM".to_string(), mean))
        .into_iter()
        .collect();
    let table = protocol_tables(&rows);
    let md = args.out.join("metrics.md");
    write_atomic(&md, table.as_bytes()).with_context(|| format!("writing {}", md.display()))?;

    // Every bundled network, the default first: `tiny` answers at 32x128, the cascade at the
    // full 160x640.
    let networks: Vec<Weights> = std::iter::once(BundledModel::DEFAULT)
        .chain(
            BundledModel::ALL
                .into_iter()
                .filter(|m| *m != BundledModel::DEFAULT),
        )
        .map(Weights::Bundled)
        .collect();
    outln!(
        "[4/5] bundled networks ({}) against the classical method, all scored at {}x{}, N = {} \
         (a coarser output upsampled)",
        networks
            .iter()
            .map(Weights::stem)
            .collect::<Vec<_>>()
            .join(", "),
        args.size.height,
        args.size.width,
        args.ndepth
    );
    let eval_dir = args.out.join("eval");
    eval::run(&eval::Args {
        data: data_dir.clone(),
        method: vec![Method::Net, Method::Sgm],
        weights: networks.clone(),
        frames: FrameRange::inclusive(1, args.frames),
        preset: Preset::Tiny,
        size: args.size,
        ndepth: args.ndepth,
        phi_deg: 45.0,
        out: Some(eval_dir.clone()),
        pictures: true,
        backend: omnimvs_net::Backend::Cpu,
    })?;
    let net_table = std::fs::read_to_string(eval_dir.join("eval.md")).ok();
    for weights in &networks {
        let out = args.out.join(format!("net_{}", weights.stem()));
        infer::run(&infer_args(&data_dir, &out, args.frames, weights))?;
    }

    let itbt = args.samples.join("itbt_sample");
    if itbt.join("config.yaml").is_file() {
        outln!("[5/5] real data: itbt_sample frame 1");
        let out = args.out.join("itbt_sgm");
        sgm::run(&sgm_args(
            &itbt,
            &out,
            args,
            Some(FrameRange::inclusive(1, 1)),
        ))?;
        outln!("  ZNCC+SGM: {}", out.join("00001_invdepth.png").display());
        for weights in &networks {
            let out = args.out.join(format!("itbt_net_{}", weights.stem()));
            infer::run(&infer_args(&itbt, &out, 1, weights))?;
            outln!(
                "  network `{}`: {}",
                weights.stem(),
                out.join("00001_vis.png").display()
            );
        }
    } else {
        outln!(
            "[5/5] {} not found: skipping the real sample",
            itbt.display()
        );
    }
    outln!(
        "\nClassical method at {}x{}, N = {}, on {} synthetic frames (error in % of N; lower is better):\n\n{}",
        args.size.height,
        args.size.width,
        args.ndepth,
        args.frames,
        table.trim_end()
    );
    if let Some(t) = net_table {
        outln!(
            "\nNetwork and classical method at the same grid:\n\n{}",
            t.trim_end()
        );
    }
    outln!(
        "\ndone in {:.1} s: pictures, point clouds and metrics in {}",
        t0.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}

fn infer_args(dataset: &Path, out: &Path, frames: u32, weights: &Weights) -> infer::Args {
    infer::Args {
        dataset: dataset.to_path_buf(),
        weights: weights.clone(),
        preset: Preset::Tiny,
        frames: FrameRange::inclusive(1, frames),
        out: out.to_path_buf(),
        backend: omnimvs_net::Backend::Cpu,
        ply: true,
        order: None,
        input_size: None,
    }
}

fn sgm_args(dataset: &Path, out: &Path, args: &Args, frames: Option<FrameRange>) -> sgm::Args {
    sgm::Args {
        dataset: dataset.to_path_buf(),
        frames,
        out: out.to_path_buf(),
        size: args.size,
        phi_deg: 45.0,
        ndepth: args.ndepth,
        p1: omnimvs_stereo::DEFAULT_P1,
        p2: omnimvs_stereo::DEFAULT_P2,
        four_paths: false,
        every_other: false,
    }
}
