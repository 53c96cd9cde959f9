//! Reads one frame's output: the inverse-depth TIFF that `zncc_sgm`, `bundled_network`,
//! `omnimvs sgm` and `omnimvs infer` write, turned into depth in metres (a TIFF of its own)
//! and into a point cloud (PLY) in the rig's frame.
//!
//! ```text
//! cargo run --release -p omnimvs-examples --example read_outputs -- OUT FRAME
//! ```
//!
//! OUT is an output folder of one of those programs; writes `OUT/%05d_depth_m.tiff` (f32
//! metres: infinity where the inverse depth is 0, i.e. sky; NaN where there is no answer) and
//! `OUT/%05d_points.ply` (x, y, z in metres, coloured by depth).
//!
//! The map is an equirectangular panorama around the rig, row-major, row 0 at the top:
//! column `c` of a `W`-wide map looks at longitude `theta = (c - W/2) / (W/2) * pi + pi/2`,
//! row `r` of an `H`-high one at latitude `phi = (r - (H-1)/2) / ((H-1)/2) * phi_max` with
//! `phi_max = 180 H / W` degrees (square pixels: 45 for 160x640); the ray of a pixel in the
//! rig frame (x right, y down, z forward) is `(-cos phi cos theta, sin phi, cos phi sin theta)`
//! (`EquirectGrid::ray`), and the point is the ray divided by the inverse depth.

use std::path::Path;

use anyhow::{Context, Result};
use omnimvs_data::colormap::Colormap;
use omnimvs_data::gt::{read_tiff_f32, write_f32_tiff};
use omnimvs_eval::output::frame_path;
use omnimvs_eval::ply::{ColoredPoint, write_ply};
use omnimvs_sweep::EquirectGrid;

const USAGE: &str = "usage: read_outputs OUT FRAME

Reads OUT/%05d.tiff (inverse depth, 1/m) of FRAME and writes OUT/%05d_depth_m.tiff (depth in
metres) and OUT/%05d_points.ply (a point cloud in the rig frame).";

/// Points farther than this (1 km) are left out of the cloud.
const FARTHEST_M: f32 = 1000.0;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [out, frame] = args.as_slice() else {
        eprintln!("{USAGE}");
        std::process::exit(2);
    };
    let out = Path::new(out);
    let frame: u32 = frame
        .parse()
        .with_context(|| format!("FRAME: expected a frame number, found {frame:?}"))?;

    // The f32 page of the TIFF: width, height and the values, row-major.
    let path = frame_path(out, frame, ".tiff");
    let inv = read_tiff_f32(&path)?;
    let grid = EquirectGrid::new(inv.height, inv.width, inv.phi_deg())?;
    println!(
        "{}: {}x{} inverse depth (1/m), latitudes +-{} degrees",
        path.display(),
        inv.height,
        inv.width,
        grid.phi_deg
    );

    // Depth in metres: 1 / inverse depth. 0 is "at infinity" (sky); NaN means the method left
    // the pixel without an answer (e.g. `sgm --min-confidence`).
    let depth_m: Vec<f32> = inv
        .data
        .iter()
        .map(|&d| if d == 0.0 { f32::INFINITY } else { 1.0 / d })
        .collect();
    let depth_path = frame_path(out, frame, "_depth_m.tiff");
    write_f32_tiff(&depth_path, inv.width, inv.height, &depth_m)?;

    // A few directions on the horizon (the middle row): ahead (+z), right (+x), behind, left.
    let middle = inv.height / 2;
    for (name, col) in [
        ("ahead", inv.width / 2),
        ("right", 3 * inv.width / 4),
        ("behind", 0),
        ("left", inv.width / 4),
    ] {
        let ray = grid.ray(middle as f64, col as f64);
        println!(
            "  {name:>6} (ray {:+.2} {:+.2} {:+.2}): {:.2} m",
            ray.x,
            ray.y,
            ray.z,
            depth_m[middle * inv.width + col]
        );
    }

    // Sky: the farthest hypothesis is the sphere at infinity (inverse depth 0, or next to it),
    // so depths beyond 1 km are counted apart.
    let mut near: Vec<f32> = depth_m
        .iter()
        .copied()
        .filter(|&d| d < FARTHEST_M)
        .collect();
    near.sort_by(f32::total_cmp);
    if let (Some(nearest), Some(farthest)) = (near.first(), near.last()) {
        println!(
            "  depth: nearest {nearest:.2} m, median {:.2} m, farthest {farthest:.2} m; {} pixels beyond 1 km (sky), {} without an answer",
            near[near.len() / 2],
            depth_m.iter().filter(|&&d| d >= FARTHEST_M).count(),
            depth_m.iter().filter(|d| d.is_nan()).count(),
        );
    }

    // The point cloud: every pixel with a finite depth under 1 km, coloured from near (warm)
    // to far by its inverse depth.
    let max_inv = inv
        .data
        .iter()
        .copied()
        .filter(|d| d.is_finite())
        .fold(0.0, f32::max);
    let mut points = Vec::new();
    for row in 0..inv.height {
        for col in 0..inv.width {
            let depth = depth_m[row * inv.width + col];
            // NaN (no answer) and sky are left out.
            if depth.is_nan() || depth >= FARTHEST_M {
                continue;
            }
            let p = grid.ray(row as f64, col as f64) * f64::from(depth);
            let t = f64::from(1.0 / depth) / f64::from(max_inv.max(f32::EPSILON));
            points.push(ColoredPoint {
                xyz_m: [p.x as f32, p.y as f32, p.z as f32],
                rgb: Colormap::Turbo.color(t),
            });
        }
    }
    let ply_path = frame_path(out, frame, "_points.ply");
    write_ply(&ply_path, &points)?;
    println!(
        "wrote {} and {} ({} points)",
        depth_path.display(),
        ply_path.display(),
        points.len()
    );
    Ok(())
}
