//! Bilinear warping with `grid_sample(align_corners=True, padding=zeros)`
//! semantics: a sample position `(col, row)` in pixels blends the four
//! neighbouring pixels, and neighbours outside the image contribute zero.

use rayon::prelude::*;

use omnimvs_core::interp::BilinearTap;

use crate::{LookupTable, SweepError};

/// Warps a `channels x height x width` map of camera `cam` onto every sphere
/// of `lut`, writing `[sphere, channel, grid_h, grid_w]` into `out`.
///
/// The map may have any resolution (a feature map at half the image size,
/// say): the table's normalised coordinates are scaled to it.
///
/// # Errors
/// [`SweepError::Mismatch`] when `src` or `out` has the wrong length or `cam`
/// is out of range.
pub fn warp_camera_onto_spheres(
    lut: &LookupTable,
    cam: usize,
    src: &[f32],
    channels: usize,
    width: usize,
    height: usize,
    out: &mut [f32],
) -> Result<(), SweepError> {
    if cam >= lut.num_cameras() {
        return Err(SweepError::mismatch(
            "camera index",
            format!("< {}", lut.num_cameras()),
            cam,
        ));
    }
    if src.len() != channels * width * height {
        return Err(SweepError::mismatch(
            "source map length",
            format!(
                "{channels} x {height} x {width} = {}",
                channels * width * height
            ),
            src.len(),
        ));
    }
    let grid_len = lut.grid.len();
    let want = lut.num_spheres() * channels * grid_len;
    if out.len() != want {
        return Err(SweepError::mismatch("warp output length", want, out.len()));
    }
    let plane_len = width * height;
    out.par_chunks_mut(channels * grid_len)
        .enumerate()
        .for_each(|(sphere, dst)| {
            let lut_plane = lut.plane(cam, sphere);
            for (i, xy) in lut_plane.chunks_exact(2).enumerate() {
                let tap = BilinearTap::from_normalized(xy[0], xy[1], width, height);
                for c in 0..channels {
                    dst[c * grid_len + i] = tap.apply(&src[c * plane_len..(c + 1) * plane_len]);
                }
            }
        });
    Ok(())
}
