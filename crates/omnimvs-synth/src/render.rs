//! Rendering: fisheye images through the exact camera model, and the
//! ground-truth inverse depth on an equirectangular grid. Both run in
//! parallel over image rows (rayon); nothing is allocated per ray.

use glam::Vec3A;
use nalgebra::Vector3;
use omnimvs_camera::{Camera, Pixel, Rig};
use omnimvs_core::GrayImage;
use omnimvs_data::gt::InvDepthMap;
use omnimvs_sweep::EquirectGrid;
use rayon::prelude::*;

use crate::Tracer;

/// Sub-pixel sample offsets (pixels, in `[-0.5, 0.5)`) for `spp` samples:
/// the pixel centre first, then Roberts' R2 low-discrepancy sequence. The
/// same pattern serves every pixel, so a rendering is deterministic.
pub fn sample_offsets(spp: u32) -> Vec<(f64, f64)> {
    const A1: f64 = 0.754_877_666_246_692_7; // 1 / plastic number
    const A2: f64 = 0.569_840_290_998_053_3; // 1 / plastic number^2
    (0..spp.max(1))
        .map(|i| {
            let i = f64::from(i);
            ((0.5 + i * A1).fract() - 0.5, (0.5 + i * A2).fract() - 0.5)
        })
        .collect()
}

/// Renders one camera's 8-bit gray image (row-major, `height x width`).
/// Every sample casts the ray of the exact camera model (`unproject`) from
/// the camera centre; samples outside the field of view are black, so
/// pixels outside it are 0.
pub fn render_fisheye(tracer: &Tracer, camera: &Camera, spp: u32) -> Vec<u8> {
    let (w, h) = (
        camera.model.width() as usize,
        camera.model.height() as usize,
    );
    let mut out = vec![0u8; w * h];
    render_fisheye_into(tracer, camera, spp, &mut out);
    out
}

/// As [`render_fisheye`], into a caller-allocated `height x width` buffer.
///
/// # Panics
/// Debug builds assert the buffer size.
pub fn render_fisheye_into(tracer: &Tracer, camera: &Camera, spp: u32, out: &mut [u8]) {
    let w = camera.model.width() as usize;
    debug_assert_eq!(out.len(), w * camera.model.height() as usize);
    let offsets = sample_offsets(spp);
    let inv_n = 1.0 / offsets.len() as f32;
    let rot = camera.rig_from_cam.rotation.to_rotation_matrix();
    let origin = to_vec3a(&camera.center_in_rig().coords);
    out.par_chunks_mut(w).enumerate().for_each(|(row, line)| {
        for (col, px) in line.iter_mut().enumerate() {
            let mut sum = 0.0f32;
            for &(dc, dr) in &offsets {
                let pixel = Pixel::new(col as f64 + dc, row as f64 + dr);
                if let Some(ray_cam) = camera.model.unproject(pixel) {
                    let d = to_vec3a(&(rot * ray_cam)).normalize();
                    sum += tracer.radiance(origin, d);
                }
            }
            *px = (sum * inv_n * 255.0 + 0.5).clamp(0.0, 255.0) as u8;
        }
    });
}

/// The images of every camera of `rig` as the sweep reads them (gray levels
/// 0..255 as f32): one frame in memory, without a dataset on disk.
pub fn render_gray_frame(tracer: &Tracer, rig: &Rig, spp: u32) -> Vec<GrayImage> {
    rig.cameras
        .iter()
        .map(|camera| GrayImage {
            width: camera.model.width() as usize,
            height: camera.model.height() as usize,
            data: render_fisheye(tracer, camera, spp)
                .into_iter()
                .map(f32::from)
                .collect(),
        })
        .collect()
}

/// [`render_inverse_depth`] as an [`InvDepthMap`] of `grid`'s size.
pub fn render_inverse_depth_map(tracer: &Tracer, grid: &EquirectGrid) -> InvDepthMap {
    InvDepthMap {
        width: grid.width,
        height: grid.height,
        data: render_inverse_depth(tracer, grid),
    }
}

/// Ground-truth inverse depth (1/m, from the rig origin; 0 for the sky) on
/// an equirectangular grid (`FORMATS.md` convention), row-major.
pub fn render_inverse_depth(tracer: &Tracer, grid: &EquirectGrid) -> Vec<f32> {
    let mut out = vec![0f32; grid.len()];
    out.par_chunks_mut(grid.width.max(1))
        .enumerate()
        .for_each(|(row, line)| {
            for (col, v) in line.iter_mut().enumerate() {
                let d = to_vec3a(&grid.ray(row as f64, col as f64).normalize());
                *v = tracer.inverse_depth(d);
            }
        });
    out
}

fn to_vec3a(v: &Vector3<f64>) -> Vec3A {
    Vec3A::new(v.x as f32, v.y as f32, v.z as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_sample_is_the_pixel_centre_and_all_stay_inside() {
        let o = sample_offsets(16);
        assert_eq!(o[0], (0.0, 0.0));
        assert!(
            o.iter()
                .all(|&(a, b)| (-0.5..0.5).contains(&a) && (-0.5..0.5).contains(&b))
        );
        assert_eq!(sample_offsets(0).len(), 1);
    }
}
