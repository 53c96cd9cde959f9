//! `omnimvs`: 360-degree depth from a rig of ultra-wide fisheye cameras.

use std::process::ExitCode;

use clap::{Parser, Subcommand, ValueEnum};

/// `println!` for the commands' results: a closed stdout (`omnimvs info DATASET | head -5`)
/// ends the program quietly instead of panicking (see [`out`]).
macro_rules! outln {
    () => {
        $crate::out::line(format_args!(""))
    };
    ($($arg:tt)*) => {
        $crate::out::line(format_args!($($arg)*))
    };
}

/// `print!` with the manners of [`outln!`].
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::out::text(format_args!($($arg)*))
    };
}

mod args;
mod bench;
mod cmd;
mod dataset;
mod malloc;
mod out;
mod pipeline;
mod weights;

/// 360-degree depth maps from a rig of ultra-wide (220-degree) fisheye cameras,
/// after OmniMVS (ICCV 2019).
///
/// A DATASET is a folder with a reference-layout `config.yaml` (the rig and
/// the image file pattern) and the camera images, e.g.
/// `../shared/data/omnimvs-samples/itbt_sample`; a folder in the released
/// datasets' layout (`ocam1.txt`.. and `poses.txt`, see `--pose-unit`); or a folder with a
/// Basalt `calibration.json` or a Kalibr `camchain.yaml` and one image folder per camera
/// (`cam0/`.. or `cam1/`..). Dataset folders are only read, never written. Lookup tables are cached in `$OMNIMVS_CACHE_DIR`
/// (default `~/.cache/omnimvs`).
#[derive(Debug, Parser)]
#[command(name = "omnimvs", version = env!("OMNIMVS_VERSION"), propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
    /// Unit of the translations in a released-layout folder's poses.txt (a folder with
    /// ocam1.txt.. and poses.txt instead of config.yaml): cm in the released OmniThings,
    /// OmniHouse and urban sets (the default), mm in SweepNet's real_indoor_sample.
    /// `omnimvs info` shows the baselines it gives, in metres. A config.yaml's poses are
    /// always metres. Taken by info, lut, pano, parity, sgm, infer and eval.
    #[arg(long, global = true, value_enum)]
    pose_unit: Option<dataset::PoseUnit>,
    /// The frame panoramas and point clouds are expressed in: `calibration` (the default: the
    /// calibration file's own frame, the rig frame of config.yaml, Basalt's IMU frame,
    /// Kalibr's cam0) or `fitted` (centred at the cameras' mean, vertical axis normal to the
    /// plane they span: for a calibration frame that is not level with the rig). `omnimvs
    /// info` prints the frame used; infer.json and sgm.json record it.
    #[arg(long, global = true, value_enum)]
    rig_frame: Option<dataset::RigFrameArg>,
    /// The sweep's minimum depth in metres, instead of the dataset's (config.yaml's
    /// omnimvs_sweep_min_depth; 0.55 for a released-layout or calibration-file folder).
    #[arg(long, global = true)]
    min_depth: Option<f64>,
}

#[derive(Debug, Subcommand)]
enum Command {
    Bench(cmd::bench::Args),
    Demo(cmd::demo::Args),
    Infer(cmd::infer::Args),
    Info(cmd::info::Args),
    Lut(cmd::lut::Args),
    Pano(cmd::pano::Args),
    #[command(subcommand)]
    Rig(cmd::rig::Command),
    Parity(cmd::parity::Args),
    Sgm(cmd::sgm::Args),
    Synth(cmd::synth::Args),
    Train(Box<cmd::train::Args>),
    Eval(cmd::eval::Args),
    Finetune(Box<cmd::finetune::Args>),
}

/// The commands that do not open their dataset through [`dataset::DatasetOpener`], so a
/// stated pose unit, rig frame or minimum depth would be silently ignored there: `train` (its
/// datasets are opened by the trainer), `demo` (it writes its own `config.yaml`), `bench`.
/// `synth` takes the rig frame and the minimum depth for its `--rig`, `rig` the rig frame.
fn ignores_dataset_options(
    command: &Command,
    pose_unit_stated: bool,
    min_depth_stated: bool,
) -> Option<&'static str> {
    match command {
        Command::Train(_) => Some("train"),
        Command::Demo(_) => Some("demo"),
        Command::Synth(_) if pose_unit_stated => Some("synth"),
        Command::Finetune(_) if pose_unit_stated => Some("finetune"),
        Command::Bench(_) => Some("bench"),
        Command::Rig(_) if pose_unit_stated || min_depth_stated => Some("rig"),
        _ => None,
    }
}

fn main() -> ExitCode {
    malloc::keep_freed_memory();
    let cli = Cli::parse();
    let value = |v: Option<clap::builder::PossibleValue>| {
        v.map(|v| v.get_name().to_string()).unwrap_or_default()
    };
    let stated = [
        cli.pose_unit
            .map(|u| format!("--pose-unit {}", value(u.to_possible_value()))),
        cli.rig_frame
            .map(|f| format!("--rig-frame {}", value(f.to_possible_value()))),
        cli.min_depth.map(|d| format!("--min-depth {d}")),
    ];
    if let Some(name) = ignores_dataset_options(
        &cli.command,
        cli.pose_unit.is_some(),
        cli.min_depth.is_some(),
    ) && let Some(flag) = stated.into_iter().flatten().next()
    {
        eprintln!(
            "error: {flag}: `omnimvs {name}` does not take it (info, lut, pano, parity, sgm, infer and eval do)"
        );
        return ExitCode::from(2);
    }
    let datasets = dataset::DatasetOpener::new(cli.pose_unit, cli.rig_frame, cli.min_depth);
    let result = match cli.command {
        Command::Bench(a) => cmd::bench::run(&a),
        Command::Demo(a) => cmd::demo::run(&a),
        Command::Infer(a) => cmd::infer::run(&a, &datasets),
        Command::Info(a) => cmd::info::run(&a, &datasets),
        Command::Lut(a) => cmd::lut::run(&a, &datasets),
        Command::Pano(a) => cmd::pano::run(&a, &datasets),
        Command::Rig(a) => cmd::rig::run(&a, datasets.options().frame),
        Command::Parity(a) => cmd::parity::run(&a, &datasets),
        Command::Sgm(a) => cmd::sgm::run(&a, &datasets),
        Command::Synth(a) => cmd::synth::run(&a, &datasets),
        Command::Train(a) => cmd::train::run(&a),
        Command::Eval(a) => cmd::eval::run(&a, &datasets),
        Command::Finetune(a) => cmd::finetune::run(&a, &datasets),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", out::error_chain(&e));
            ExitCode::FAILURE
        }
    }
}
