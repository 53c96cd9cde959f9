//! `omnimvs rig`: show a rig file, convert it to another calibration format.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use omnimvs_camera::{FrameChoice, Pixel, Rig, RigFormat, read_rig_file, write_rig_file};

/// Show a rig's calibration, or convert it to another calibration format.
///
/// The formats: a reference config.yaml, a Basalt calibration.json, a Kalibr camchain.yaml,
/// the released datasets' ocamN.txt + poses.txt.
#[derive(Debug, clap::Subcommand)]
pub enum Command {
    Show(ShowArgs),
    Convert(ConvertArgs),
}

/// Print a rig file's cameras (model, image size, FOV, position, optical axis), its frame and
/// the baselines between its cameras.
#[derive(Debug, clap::Args)]
pub struct ShowArgs {
    /// The rig file, or a folder holding one.
    pub rig: PathBuf,
}

/// Write a rig in another calibration format.
///
/// The format of OUT comes from its name unless --to states it: `*.json` Basalt,
/// `*camchain*.yaml` Kalibr, any other `*.yaml` a config.yaml (its cameras: section), a folder
/// the released layout (ocamN.txt and poses.txt, centimetres). A format that has no such
/// camera model is refused before anything is written (Basalt and Kalibr have no OCamCalib
/// model; the released layout has only OCamCalib). Kalibr's poses are relative to cam0, so a
/// rig written to camchain.yaml is expressed in its first camera's frame. With the global
/// `--rig-frame fitted` the rig is written in the frame fitted to its cameras (a Kalibr rig
/// centred for the sweep, say).
#[derive(Debug, clap::Args)]
pub struct ConvertArgs {
    /// The rig file, or a folder holding one.
    pub input: PathBuf,
    /// The file (or, for ocam-txt, the folder) to write.
    pub output: PathBuf,
    /// The output format (default: from OUTPUT's name).
    #[arg(long, value_enum)]
    pub to: Option<FormatArg>,
}

/// `--to` values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum FormatArg {
    /// The reference config.yaml (`cameras:`).
    Config,
    /// Basalt's calibration.json.
    Basalt,
    /// Kalibr's camchain.yaml.
    Kalibr,
    /// The released datasets' ocamN.txt + poses.txt (a folder).
    OcamTxt,
}

impl From<FormatArg> for RigFormat {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Config => Self::ConfigYaml,
            FormatArg::Basalt => Self::Basalt,
            FormatArg::Kalibr => Self::Kalibr,
            FormatArg::OcamTxt => Self::OcamTxt,
        }
    }
}

pub fn run(command: &Command, frame: FrameChoice) -> Result<()> {
    match command {
        Command::Show(args) => {
            let (rig, format, file) = read_rig_file(&args.rig)?;
            let rig = in_frame(rig, frame)?;
            outln!("rig file     {} ({})", file.display(), format.name());
            match frame {
                FrameChoice::Calibration => outln!("frame        {}", format.rig_frame()),
                FrameChoice::Fitted => outln!(
                    "frame        fitted to the cameras (origin at their mean, y normal to their plane), from {}",
                    format.rig_frame()
                ),
            }
            print_rig(&rig);
            Ok(())
        }
        Command::Convert(args) => convert(args, frame),
    }
}

/// The rig in `frame` (`--rig-frame`).
fn in_frame(rig: Rig, frame: FrameChoice) -> Result<Rig> {
    Ok(rig.in_frame(frame).context("--rig-frame fitted")?.0)
}

fn convert(args: &ConvertArgs, frame: FrameChoice) -> Result<()> {
    let (rig, from, file) = read_rig_file(&args.input)?;
    let rig = in_frame(rig, frame)?;
    let to = match args.to {
        Some(f) => RigFormat::from(f),
        None => format_of_name(&args.output)?,
    };
    if to == RigFormat::OcamTxt {
        std::fs::create_dir_all(&args.output)
            .with_context(|| format!("creating {}", args.output.display()))?;
    }
    write_rig_file(&rig, to, &args.output)
        .with_context(|| format!("writing {} as {}", args.output.display(), to.name()))?;
    outln!(
        "wrote {} ({}, {} cameras) from {} ({})",
        args.output.display(),
        to.name(),
        rig.len(),
        file.display(),
        from.name()
    );
    if to == RigFormat::Kalibr && from != RigFormat::Kalibr {
        outln!("note: Kalibr's poses are relative to cam0: the written rig is in cam0's frame");
    }
    Ok(())
}

/// The format a file name asks for.
fn format_of_name(path: &Path) -> Result<RigFormat> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    Ok(match ext.as_str() {
        "json" => RigFormat::Basalt,
        "yaml" | "yml" if name.contains("camchain") => RigFormat::Kalibr,
        "yaml" | "yml" => RigFormat::ConfigYaml,
        "" => RigFormat::OcamTxt,
        _ => bail!(
            "{}: cannot tell the format from the name (.json: Basalt, *camchain*.yaml: Kalibr, .yaml: config.yaml, a folder: ocam-txt); give --to",
            path.display()
        ),
    })
}

/// Prints every camera of `rig` (model, size, FOV, centre, optical axis, image folder) and the
/// baselines.
pub fn print_rig(rig: &Rig) {
    outln!("cameras      {}", rig.len());
    for (i, cam) in rig.cameras.iter().enumerate() {
        let m = &cam.model;
        let c = cam.center_in_rig();
        let center_px = Pixel::new(f64::from(m.width()) / 2.0, f64::from(m.height()) / 2.0);
        let axis = cam.ray_in_rig(center_px).unwrap_or_default();
        let resolution = m
            .angular_resolution()
            .map_or(String::new(), |r| format!(", {r:.0} px/rad"));
        outln!(
            "  camera {} (id {}, {}): {}x{} px, FOV {:.1} deg{resolution}, centre ({:+.3}, {:+.3}, {:+.3}) m, axis ({:+.2}, {:+.2}, {:+.2}), dir {}",
            i + 1,
            cam.id,
            m.name(),
            m.width(),
            m.height(),
            m.max_fov_deg(),
            c.x,
            c.y,
            c.z,
            axis.x,
            axis.y,
            axis.z,
            cam.img_dir
        );
    }
    outln!("baselines");
    for &(i, j, b) in &rig.baselines_m() {
        outln!("  camera {}-{}: {b:.3} m", i + 1, j + 1);
    }
}
