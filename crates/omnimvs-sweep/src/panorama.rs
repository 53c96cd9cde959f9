//! The equirectangular panorama seen through every camera at a given inverse depth (the
//! reference panorama of the paper's figures): gray, or colour composed plane by plane with
//! the same weights.

use omnimvs_camera::nalgebra::Point3;
use omnimvs_camera::{Camera, Rig, ValidityMask};
use rayon::prelude::*;

use omnimvs_core::{ColourPlanes, GrayImage};

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

/// A composed gray panorama.
#[derive(Debug, Clone, PartialEq)]
pub struct Panorama {
    /// Mean over the cameras that see each pixel (0 where none does).
    pub image: GrayImage,
    /// How many cameras see each pixel.
    pub count: Vec<u8>,
}

/// A composed colour panorama: each plane composed as [`Panorama::image`] is.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourPanorama {
    /// Mean over the cameras that see each pixel, per channel (0 where none does).
    pub image: ColourPlanes,
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
    let ([values], seen) = warp_planes(camera, grid, [image], mask, inv_depth)?;
    Ok((values, seen))
}

/// [`warp_camera_to_panorama`] of `C` planes of one image at once: each pixel is projected
/// once and every plane sampled there.
fn warp_planes<const C: usize>(
    camera: &Camera,
    grid: &EquirectGrid,
    planes: [&GrayImage; C],
    mask: Option<&ValidityMask>,
    inv_depth: InvDepthSource<'_>,
) -> Result<([Vec<f32>; C], Vec<bool>), SweepError> {
    let (w, h) = (
        camera.model.width() as usize,
        camera.model.height() as usize,
    );
    for image in planes {
        if image.width != w || image.height != h {
            return Err(SweepError::mismatch(
                format!("camera {} image size", camera.id),
                format!("{w}x{h}"),
                format!("{}x{}", image.width, image.height),
            ));
        }
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
    // Per row: the samples of every plane (`C` runs of `width`) and what the camera sees.
    let rows: Vec<(Vec<f32>, Vec<bool>)> = (0..grid.height)
        .into_par_iter()
        .map(|row| {
            let mut vals = vec![0f32; C * grid.width];
            let mut seens = vec![false; grid.width];
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
                for (k, image) in planes.iter().enumerate() {
                    vals[k * grid.width + col] = image.sample(px.col, px.row);
                }
                seens[col] = true;
            }
            (vals, seens)
        })
        .collect();
    let mut values: [Vec<f32>; C] = std::array::from_fn(|_| Vec::with_capacity(grid.len()));
    let mut seen = Vec::with_capacity(grid.len());
    for (vals, seens) in rows {
        for (k, plane) in values.iter_mut().enumerate() {
            plane.extend_from_slice(&vals[k * grid.width..(k + 1) * grid.width]);
        }
        seen.extend(seens);
    }
    Ok((values, seen))
}

/// Composes `C` planes over the cameras: each pixel of each plane is the mean of the cameras
/// that see the point at `inv_depth` along its ray; returns the planes and the counts.
fn compose_planes<const C: usize>(
    rig: &Rig,
    grid: &EquirectGrid,
    planes: &[[&GrayImage; C]],
    masks: Option<&[ValidityMask]>,
    inv_depth: InvDepthSource<'_>,
) -> Result<([GrayImage; C], Vec<u8>), SweepError> {
    if planes.len() != rig.len() {
        return Err(SweepError::mismatch(
            "number of images",
            rig.len(),
            planes.len(),
        ));
    }
    if let Some(m) = masks
        && m.len() != rig.len()
    {
        return Err(SweepError::mismatch("number of masks", rig.len(), m.len()));
    }
    let mut sums: [Vec<f32>; C] = std::array::from_fn(|_| vec![0f32; grid.len()]);
    let mut count = vec![0u8; grid.len()];
    for (i, camera) in rig.cameras.iter().enumerate() {
        let mask = masks.map(|m| &m[i]);
        let (vals, seen) = warp_planes(camera, grid, planes[i], mask, inv_depth)?;
        for k in 0..grid.len() {
            if seen[k] {
                for (sum, val) in sums.iter_mut().zip(&vals) {
                    sum[k] += val[k];
                }
                count[k] = count[k].saturating_add(1);
            }
        }
    }
    let planes = sums.map(|mut sum| {
        for (s, &c) in sum.iter_mut().zip(&count) {
            if c > 0 {
                *s /= f32::from(c);
            }
        }
        GrayImage {
            width: grid.width,
            height: grid.height,
            data: sum,
        }
    });
    Ok((planes, count))
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
    let planes: Vec<[&GrayImage; 1]> = images.iter().map(|image| [image]).collect();
    let ([image], count) = compose_planes(rig, grid, &planes, masks, inv_depth)?;
    Ok(Panorama { image, count })
}

/// [`compose_panorama`] of colour images: each channel composed with the same cameras and
/// weights as the gray panorama (a gray camera enters as [`ColourPlanes::from_gray`]).
///
/// # Errors
/// As [`compose_panorama`].
pub fn compose_colour_panorama(
    rig: &Rig,
    grid: &EquirectGrid,
    images: &[ColourPlanes],
    masks: Option<&[ValidityMask]>,
    inv_depth: InvDepthSource<'_>,
) -> Result<ColourPanorama, SweepError> {
    let planes: Vec<[&GrayImage; 3]> = images
        .iter()
        .map(|image| {
            let [r, g, b] = &image.planes;
            [r, g, b]
        })
        .collect();
    let (planes, count) = compose_planes(rig, grid, &planes, masks, inv_depth)?;
    Ok(ColourPanorama {
        image: ColourPlanes { planes },
        count,
    })
}
