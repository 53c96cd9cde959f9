//! `omnimvs pano`: the panorama of a frame at a given depth, in colour when its images are.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use omnimvs_data::gt::read_inv_depth;
use omnimvs_data::image_io::{write_colour_png, write_gray_png};
use omnimvs_sweep::{EquirectGrid, InvDepthSource, compose_colour_panorama, compose_panorama};

use crate::args::Size;

/// Compose the equirectangular panorama of one frame at a depth or an inverse-depth map.
///
/// Compose the equirectangular panorama of one frame: every pixel is the mean
/// of the cameras that see the point at the given depth along its ray. Use a
/// constant depth (--depth) or an inverse-depth map (--invdepth, e.g. a
/// result TIFF of `omnimvs sgm`/`infer`, or ground truth). The PNG is in colour (RGB,
/// each channel composed the same way) when the frame's images are, a gray camera of a
/// mixed rig counting as R = G = B; gray otherwise.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Dataset folder (or its config.yaml).
    pub dataset: PathBuf,
    /// Frame index.
    #[arg(long)]
    pub frame: u32,
    /// Constant depth in metres (0 or inf = at infinity).
    #[arg(
        long,
        conflicts_with = "invdepth",
        required_unless_present = "invdepth"
    )]
    pub depth: Option<f64>,
    /// Inverse-depth map (1/m): .tiff (f32), 16-bit .png, or raw f32 640 wide.
    /// The panorama takes its size; latitudes +-180*h/w degrees unless --phi-deg.
    #[arg(long)]
    pub invdepth: Option<PathBuf>,
    /// Panorama size for --depth, HEIGHTxWIDTH.
    #[arg(long, default_value = "500x1000")]
    pub size: Size,
    /// Latitude range, +-degrees (default: 90 with --depth, from the map's shape with --invdepth).
    #[arg(long)]
    pub phi_deg: Option<f64>,
    /// Output PNG (RGB for colour images, gray for gray ones).
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(args: &Args, datasets: &crate::dataset::DatasetOpener) -> Result<()> {
    let ds = datasets.open(&args.dataset)?;
    let (images, colour) = ds.read_frame_and_colour(args.frame)?;
    let masks = ds.masks()?;
    let map;
    let (grid, source) = match (&args.invdepth, args.depth) {
        (Some(path), _) => {
            map = read_inv_depth(path)?;
            let phi = args.phi_deg.unwrap_or_else(|| map.phi_deg());
            let grid = EquirectGrid::new(map.height, map.width, phi)
                .with_context(|| format!("grid of {}", path.display()))?;
            (grid, InvDepthSource::Map(&map.data))
        }
        (None, Some(depth_m)) => {
            if depth_m.is_nan() || depth_m < 0.0 {
                bail!("--depth {depth_m}: expected a non-negative depth in metres");
            }
            let inv = if depth_m == 0.0 || depth_m.is_infinite() {
                0.0
            } else {
                1.0 / depth_m
            };
            let grid = EquirectGrid::new(
                args.size.height,
                args.size.width,
                args.phi_deg.unwrap_or(90.0),
            )?;
            (grid, InvDepthSource::Constant(inv))
        }
        (None, None) => bail!("give --depth or --invdepth"),
    };
    let writing = || format!("writing {}", args.out.display());
    let (count, kind) = match colour {
        Some(colour) => {
            let pano = compose_colour_panorama(&ds.rig, &grid, &colour, Some(&masks), source)?;
            write_colour_png(&args.out, &pano.image).with_context(writing)?;
            (pano.count, "colour")
        }
        None => {
            let pano = compose_panorama(&ds.rig, &grid, &images, Some(&masks), source)?;
            write_gray_png(&args.out, &pano.image).with_context(writing)?;
            (pano.count, "gray")
        }
    };
    let seen = count.iter().filter(|&&c| c > 0).count();
    let multi = count.iter().filter(|&&c| c > 1).count();
    outln!(
        "wrote {} ({kind}, {}x{}, +-{} deg): {:.1}% of pixels seen, {:.1}% by two or more cameras",
        args.out.display(),
        grid.height,
        grid.width,
        grid.phi_deg,
        100.0 * seen as f64 / grid.len() as f64,
        100.0 * multi as f64 / grid.len() as f64
    );
    Ok(())
}
