//! `omnimvs`: 360-degree depth from a rig of ultra-wide fisheye cameras.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

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
/// `../shared/data/omnimvs-samples/itbt_sample`, or a folder in the released
/// datasets' layout (`ocam1.txt`.. and `poses.txt`, see `--pose-unit`). Dataset folders are only
/// read, never written. Lookup tables are cached in `$OMNIMVS_CACHE_DIR`
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
}

#[derive(Debug, Subcommand)]
enum Command {
    Bench(cmd::bench::Args),
    Demo(cmd::demo::Args),
    Infer(cmd::infer::Args),
    Info(cmd::info::Args),
    Lut(cmd::lut::Args),
    Pano(cmd::pano::Args),
    Parity(cmd::parity::Args),
    Sgm(cmd::sgm::Args),
    Synth(cmd::synth::Args),
    Train(Box<cmd::train::Args>),
    Eval(cmd::eval::Args),
}

/// The commands that do not open their dataset through [`dataset::DatasetOpener`], so a
/// stated pose unit would be silently ignored there: `train` (its datasets are opened by the
/// trainer), `demo` and `synth` (they write their own `config.yaml`), `bench`.
fn ignores_pose_unit(command: &Command) -> Option<&'static str> {
    match command {
        Command::Train(_) => Some("train"),
        Command::Demo(_) => Some("demo"),
        Command::Synth(_) => Some("synth"),
        Command::Bench(_) => Some("bench"),
        _ => None,
    }
}

fn main() -> ExitCode {
    malloc::keep_freed_memory();
    let cli = Cli::parse();
    if let Some(unit) = cli.pose_unit
        && let Some(name) = ignores_pose_unit(&cli.command)
    {
        eprintln!(
            "error: --pose-unit {}: `omnimvs {name}` does not take it (info, lut, pano, parity, sgm, infer and eval do); a released-layout folder is read in centimetres there",
            clap::ValueEnum::to_possible_value(&unit)
                .map(|v| v.get_name().to_string())
                .unwrap_or_default()
        );
        return ExitCode::from(2);
    }
    let datasets = dataset::DatasetOpener::new(cli.pose_unit);
    let result = match cli.command {
        Command::Bench(a) => cmd::bench::run(&a),
        Command::Demo(a) => cmd::demo::run(&a),
        Command::Infer(a) => cmd::infer::run(&a, &datasets),
        Command::Info(a) => cmd::info::run(&a, &datasets),
        Command::Lut(a) => cmd::lut::run(&a, &datasets),
        Command::Pano(a) => cmd::pano::run(&a, &datasets),
        Command::Parity(a) => cmd::parity::run(&a, &datasets),
        Command::Sgm(a) => cmd::sgm::run(&a, &datasets),
        Command::Synth(a) => cmd::synth::run(&a),
        Command::Train(a) => cmd::train::run(&a),
        Command::Eval(a) => cmd::eval::run(&a, &datasets),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", out::error_chain(&e));
            ExitCode::FAILURE
        }
    }
}
