//! The gray equirectangular panorama seen through every camera at a given
//! inverse depth (the reference panorama of the paper's figures).

use omnimvs_camera::nalgebra::Point3;
use omnimvs_camera::{Camera, Rig, ValidityMask};
use rayon::prelude::*;

use omnimvs_core::GrayImage;

use crate::{EquirectGrid, SweepError};

/// Inverse depth (1/m) at which each panorama pixel is looked up.
#[derive(Debug, Clone, Copy)]
pub enum InvDepthSource<'a> {
    /// The same inverse depth everywhere (1/m); 0 = at infinity.
    Constant(f64),
    /// One inverse depth per grid pixel (row-major, 1/m); 0 = at infinity.
    Map(&'a [f32]),
}

impl InvDepthSource<'_> {
    fn at(&self, i: usize) -> f64 {
        match self {
            Self::Constant(d) => *d,
            Self::Map(m) => f64::from(m[i]),
        }
    }
}

/// A composed panorama.
#[derive(Debug, Clone, PartialEq)]
pub struct Panorama {
    /// Mean over the cameras that see each pixel (0 where none does).
    pub image: GrayImage,
    /// How many cameras see each pixel.
    pub count: Vec<u8>,
}

/// One camera's view of the panorama: its sample at every grid pixel and
/// whether it sees that pixel (inside the FOV, the image and the mask).
///
/// # Errors
/// [`SweepError::Mismatch`] when the image or mask size differs from the
/// camera's, or an inverse-depth map has the wrong length.
pub fn warp_camera_to_panorama(
    camera: &Camera,
    grid: &EquirectGrid,
    image: &GrayImage,
    mask: Option<&ValidityMask>,
    inv_depth: InvDepthSource<'_>,
) -> Result<(Vec<f32>, Vec<bool>), SweepError> {
    let (w, h) = (
        camera.model.width() as usize,
        camera.model.height() as usize,
    );
    if image.width != w || image.height != h {
        return Err(SweepError::mismatch(
            format!("camera {} image size", camera.id),
            format!("{w}x{h}"),
            format!("{}x{}", image.width, image.height),
        ));
    }
    if let Some(m) = mask
        && (m.width as usize != w || m.height as usize != h)
    {
        return Err(SweepError::mismatch(
            format!("camera {} mask size", camera.id),
            format!("{w}x{h}"),
            format!("{}x{}", m.width, m.height),
        ));
    }
    if let InvDepthSource::Map(m) = inv_depth
        && m.len() != grid.len()
    {
        return Err(SweepError::mismatch(
            "inverse-depth map length",
            format!("{} x {} = {}", grid.height, grid.width, grid.len()),
            m.len(),
        ));
    }
    let cam_from_rig = camera.rig_from_cam.inverse();
    let mut values = vec![0f32; grid.len()];
    let mut seen = vec![false; grid.len()];
    values
        .par_chunks_mut(grid.width)
        .zip(seen.par_chunks_mut(grid.width))
        .enumerate()
        .for_each(|(row, (vals, seens))| {
            for col in 0..grid.width {
                let ray = grid.ray(row as f64, col as f64);
                let d = inv_depth.at(row * grid.width + col);
                let p_cam = if d > 1e-12 {
                    cam_from_rig.transform_point(&Point3::from(ray / d)).coords
                } else {
                    // At infinity only the direction matters.
                    cam_from_rig.rotation * ray
                };
                let Some(px) = camera.model.project(&p_cam) else {
                    continue;
                };
                if !camera.model.contains(px) {
                    continue;
                }
                if let Some(m) = mask
                    && !m.is_valid(px.col.round() as i64, px.row.round() as i64)
                {
                    continue;
                }
                vals[col] = image.sample(px.col, px.row);
                seens[col] = true;
            }
        });
    Ok((values, seen))
}

/// Composes the panorama of `rig` on `grid`: each pixel is the mean of the
/// cameras that see the point at `inv_depth` along its ray.
///
/// # Errors
/// [`SweepError::Mismatch`] when the number of images or masks differs from
/// the number of cameras, or a size differs (see [`warp_camera_to_panorama`]).
pub fn compose_panorama(
    rig: &Rig,
    grid: &EquirectGrid,
    images: &[GrayImage],
    masks: Option<&[ValidityMask]>,
    inv_depth: InvDepthSource<'_>,
) -> Result<Panorama, SweepError> {
    if images.len() != rig.len() {
        return Err(SweepError::mismatch(
            "number of images",
            rig.len(),
            images.len(),
        ));
    }
    if let Some(m) = masks
        && m.len() != rig.len()
    {
        return Err(SweepError::mismatch("number of masks", rig.len(), m.len()));
    }
    let mut sum = vec![0f32; grid.len()];
    let mut count = vec![0u8; grid.len()];
    for (i, camera) in rig.cameras.iter().enumerate() {
        let mask = masks.map(|m| &m[i]);
        let (vals, seen) = warp_camera_to_panorama(camera, grid, &images[i], mask, inv_depth)?;
        for k in 0..grid.len() {
            if seen[k] {
                sum[k] += vals[k];
                count[k] = count[k].saturating_add(1);
            }
        }
    }
    for (s, &c) in sum.iter_mut().zip(&count) {
        if c > 0 {
            *s /= f32::from(c);
        }
    }
    Ok(Panorama {
        image: GrayImage {
            width: grid.width,
            height: grid.height,
            data: sum,
        },
        count,
    })
}
