//! A synthetic lookup table that needs no rig: for benchmarks (`omnimvs bench`) and tests of
//! the network and the trainer.

use std::f32::consts::PI;

use crate::config::NetConfig;
use crate::taps::SweepGrid;

/// Half field of view of the synthetic fisheyes, degrees (220 degree lenses).
pub const HALF_FOV_DEG: f32 = 110.0;

/// A synthetic lookup table: camera `i` looks horizontally along azimuth `i * 360 / cams`
/// with an equidistant 220 degree fisheye; the spheres shift the samples slightly like a
/// baseline would. Samples outside the field of view are invalid (far outside the image).
pub fn synthetic_grids(config: &NetConfig) -> Vec<SweepGrid> {
    let (h, w, n) = (config.out_height, config.out_width, config.num_spheres());
    let phi_max = (config.phi_deg as f32).to_radians();
    (0..config.num_cameras)
        .map(|cam| {
            let yaw = 2.0 * PI * cam as f32 / config.num_cameras as f32;
            let mut coords = Vec::with_capacity(n * h * w * 2);
            for s in 0..n {
                let shift = 0.02 * s as f32 / n as f32;
                for row in 0..h {
                    let phi =
                        (row as f32 - (h as f32 - 1.0) / 2.0) / ((h as f32 - 1.0) / 2.0) * phi_max;
                    for col in 0..w {
                        let theta = (col as f32 - w as f32 / 2.0) / (w as f32 / 2.0) * PI - yaw;
                        // Ray in the camera frame: z forward, x right, y down.
                        let (x, y, z) =
                            (phi.cos() * theta.sin(), phi.sin(), phi.cos() * theta.cos());
                        let angle = z.clamp(-1.0, 1.0).acos();
                        if angle.to_degrees() > HALF_FOV_DEG {
                            coords.extend([-1e5f32, -1e5]);
                            continue;
                        }
                        let r = angle / HALF_FOV_DEG.to_radians() + shift;
                        let norm = (x * x + y * y).sqrt().max(f32::EPSILON);
                        coords.extend([r * x / norm, r * y / norm]);
                    }
                }
            }
            SweepGrid {
                num_spheres: n,
                height: h,
                width: w,
                coords,
            }
        })
        .collect()
}
