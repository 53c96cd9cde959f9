use std::io::Read;
use std::path::Path;

use omnimvs_camera::nalgebra::Vector3;
use omnimvs_camera::{Camera, Rig};
use rayon::prelude::*;

use crate::{EquirectGrid, InvDepthHypotheses, SweepError};

/// The pixel coordinate the reference writes for an entry that has no valid
/// sample (outside the FOV, or a negative coordinate), before normalising.
pub const INVALID_PIXEL: f64 = -1e5;

/// Grid pixels projected together when a table is built.
const RUN_PIXELS: usize = 256;

/// Which of the `N` hypotheses get a sphere in the table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SphereSet {
    /// Every hypothesis `n = 0 .. N-1` (the classical method).
    All,
    /// `n = 0, 2, ..., N-2`: the network's sweep and the `.hwd` file layout.
    EveryOther,
}

impl SphereSet {
    /// The hypothesis index of each sphere.
    pub fn indices(self, count: usize) -> Vec<usize> {
        match self {
            Self::All => (0..count).collect(),
            Self::EveryOther => (0..count / 2).map(|k| 2 * k).collect(),
        }
    }
}

/// The reference file name of a table: `lt_(h,w,N).hwd`.
pub fn hwd_file_name(height: usize, width: usize, ndepth: usize) -> String {
    format!("lt_({height},{width},{ndepth}).hwd")
}

/// Sampling positions of every sphere in every camera.
///
/// `data` has the reference layout `[camera, sphere, row, col, 2]` (C order,
/// f32): the position in the source fisheye image normalised for
/// `grid_sample(align_corners=True)`, `x = col/(width-1)*2-1`,
/// `y = row/(height-1)*2-1`. Entries with no valid sample hold
/// [`INVALID_PIXEL`] normalised the same way (far outside `[-1, 1]`).
#[derive(Debug, Clone, PartialEq)]
pub struct LookupTable {
    pub grid: EquirectGrid,
    pub hypotheses: InvDepthHypotheses,
    /// Hypothesis index `n` of each sphere of the table.
    pub sphere_indices: Vec<usize>,
    /// Source image size `(width, height)` of each camera.
    pub camera_sizes: Vec<(u32, u32)>,
    pub data: Vec<f32>,
}

/// The source image size `(width, height)` of every camera of `rig`.
fn camera_sizes(rig: &Rig) -> Vec<(u32, u32)> {
    rig.cameras
        .iter()
        .map(|c| (c.model.width(), c.model.height()))
        .collect()
}

fn normalise(px: f64, size: u32) -> f32 {
    (px / (f64::from(size) - 1.0) * 2.0 - 1.0) as f32
}

/// The table entry of a point `p_cam` in the frame of `camera`, whose image is
/// `size = (width, height)`: its fisheye pixel normalised for
/// `grid_sample(align_corners=True)` as `[x, y]`, with [`INVALID_PIXEL`] for a
/// coordinate that is negative or has no projection. Only the direction of
/// `p_cam` matters. The network's per-pixel sampler projects on its own and normalises
/// through [`normalized_pixel`], so that its positions equal the table's on the spheres they
/// share.
pub fn normalized_position(camera: &Camera, size: (u32, u32), p_cam: &Vector3<f64>) -> [f32; 2] {
    normalized_pixel(camera.model.project(p_cam).map(|px| (px.col, px.row)), size)
}

/// The table entry of a fisheye pixel `(col, row)` of an image of `size = (width, height)`,
/// or of no pixel (`None`: no projection): the normalisation and the invalid marker of
/// [`normalized_position`], for projections computed elsewhere.
pub fn normalized_pixel(pixel: Option<(f64, f64)>, size: (u32, u32)) -> [f32; 2] {
    let (mut col, mut row) = pixel.unwrap_or((-1.0, -1.0));
    if col < 0.0 {
        col = INVALID_PIXEL;
    }
    if row < 0.0 {
        row = INVALID_PIXEL;
    }
    [normalise(col, size.0), normalise(row, size.1)]
}

impl LookupTable {
    /// A table of `rig`'s cameras on `grid` and `hypotheses` from its `data`.
    fn new(
        grid: &EquirectGrid,
        hypotheses: &InvDepthHypotheses,
        sphere_indices: Vec<usize>,
        rig: &Rig,
        data: Vec<f32>,
    ) -> Self {
        Self {
            grid: *grid,
            hypotheses: *hypotheses,
            sphere_indices,
            camera_sizes: camera_sizes(rig),
            data,
        }
    }

    /// Builds the table for `rig`, in parallel over (camera, sphere) planes.
    ///
    /// # Errors
    /// [`SweepError::Hypotheses`] when `spheres` is `EveryOther` and `N` is
    /// odd (the `.hwd` layout needs `N/2` spheres).
    pub fn build(
        rig: &Rig,
        grid: &EquirectGrid,
        hypotheses: &InvDepthHypotheses,
        spheres: SphereSet,
    ) -> Result<Self, SweepError> {
        if spheres == SphereSet::EveryOther && !hypotheses.count.is_multiple_of(2) {
            return Err(SweepError::Hypotheses(format!(
                "ndepth {}: expected an even number (the network sweeps every other sphere)",
                hypotheses.count
            )));
        }
        let sphere_indices = spheres.indices(hypotheses.count);
        let plane = grid.len() * 2;
        let num_spheres = sphere_indices.len();
        let mut data = vec![0f32; rig.len() * num_spheres * plane];
        crate::hugepages::advise_huge_pages(&mut data);
        // Rays and per-camera rotated rays are shared by every sphere.
        let rays = grid.rays();
        let cams_from_rig: Vec<_> = rig
            .cameras
            .iter()
            .map(|c| c.rig_from_cam.inverse())
            .collect();
        let rays_in_cam: Vec<Vec<Vector3<f64>>> = cams_from_rig
            .iter()
            .map(|t| rays.iter().map(|r| t.rotation * r).collect())
            .collect();
        data.par_chunks_mut(plane).enumerate().for_each(|(k, out)| {
            let cam_idx = k / num_spheres;
            let sphere = k % num_spheres;
            let camera = &rig.cameras[cam_idx];
            let size = (camera.model.width(), camera.model.height());
            let depth_m = 1.0 / hypotheses.inv_depth(sphere_indices[sphere] as f64);
            let t_cam = cams_from_rig[cam_idx].translation.vector;
            // The plane in runs of pixels, projected together (the same positions as
            // `normalized_position` one by one, to the bit).
            let mut points = Vec::with_capacity(RUN_PIXELS);
            let mut pixels = vec![None; RUN_PIXELS];
            for (rays, dst) in rays_in_cam[cam_idx]
                .chunks(RUN_PIXELS)
                .zip(out.chunks_mut(2 * RUN_PIXELS))
            {
                points.clear();
                points.extend(rays.iter().map(|ray_cam| ray_cam * depth_m + t_cam));
                let pixels = &mut pixels[..rays.len()];
                camera.model.project_many(&points, pixels);
                for (px, dst) in pixels.iter().zip(dst.chunks_exact_mut(2)) {
                    dst.copy_from_slice(&normalized_pixel(px.map(|px| (px.col, px.row)), size));
                }
            }
        });
        Ok(Self::new(grid, hypotheses, sphere_indices, rig, data))
    }

    /// Number of cameras.
    pub fn num_cameras(&self) -> usize {
        self.camera_sizes.len()
    }

    /// Number of spheres in the table.
    pub fn num_spheres(&self) -> usize {
        self.sphere_indices.len()
    }

    /// The `[sphere, row, col, 2]` slice of one camera.
    pub fn camera(&self, cam: usize) -> &[f32] {
        let n = self.num_spheres() * self.grid.len() * 2;
        &self.data[cam * n..(cam + 1) * n]
    }

    /// The `[row, col, 2]` plane of one camera and sphere.
    pub fn plane(&self, cam: usize, sphere: usize) -> &[f32] {
        let n = self.grid.len() * 2;
        &self.camera(cam)[sphere * n..(sphere + 1) * n]
    }

    /// The sampling position of an entry as a fractional source pixel
    /// `(col, row)`.
    pub fn pixel(&self, cam: usize, sphere: usize, row: usize, col: usize) -> (f64, f64) {
        let p = self.plane(cam, sphere);
        let i = (row * self.grid.width + col) * 2;
        let (w, h) = self.camera_sizes[cam];
        (
            (f64::from(p[i]) + 1.0) / 2.0 * (f64::from(w) - 1.0),
            (f64::from(p[i + 1]) + 1.0) / 2.0 * (f64::from(h) - 1.0),
        )
    }

    /// Size in bytes of the `.hwd` file.
    pub fn byte_len(&self) -> usize {
        self.data.len() * 4
    }

    /// Writes the table in the reference `.hwd` layout (raw little-endian
    /// f32), atomically.
    ///
    /// # Errors
    /// [`SweepError::Io`] naming the file.
    pub fn write_hwd(&self, path: &Path) -> Result<(), SweepError> {
        omnimvs_core::fs::write_atomic_with(path, |w| {
            let mut buf = Vec::with_capacity(1 << 16);
            for chunk in self.data.chunks(1 << 14) {
                buf.clear();
                for v in chunk {
                    buf.extend_from_slice(&v.to_le_bytes());
                }
                w.write_all(&buf)?;
            }
            Ok(())
        })
        .map_err(|source| SweepError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads a `.hwd` file written for `rig`, `grid`, `hypotheses` and
    /// `spheres` (the file itself carries no header: the caller states what it
    /// must contain, and the size is checked against that).
    ///
    /// # Errors
    /// [`SweepError::Io`] or [`SweepError::HwdSize`] naming the file.
    pub fn read_hwd(
        path: &Path,
        rig: &Rig,
        grid: &EquirectGrid,
        hypotheses: &InvDepthHypotheses,
        spheres: SphereSet,
    ) -> Result<Self, SweepError> {
        let io = |source| SweepError::Io {
            path: path.to_path_buf(),
            source,
        };
        let sphere_indices = spheres.indices(hypotheses.count);
        let count = rig.len() * sphere_indices.len() * grid.len() * 2;
        let expected = count as u64 * 4;
        let mut file = std::fs::File::open(path).map_err(io)?;
        let found = file.metadata().map_err(io)?.len();
        if found != expected {
            return Err(SweepError::HwdSize {
                path: path.to_path_buf(),
                found,
                expected,
                cameras: rig.len(),
                spheres: sphere_indices.len(),
                height: grid.height,
                width: grid.width,
            });
        }
        let mut bytes = Vec::with_capacity(expected as usize);
        file.read_to_end(&mut bytes).map_err(io)?;
        let data = bytes
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        Ok(Self::new(grid, hypotheses, sphere_indices, rig, data))
    }
}
