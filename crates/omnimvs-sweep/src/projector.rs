//! Fast projection of sweep-sphere points into a fisheye camera.
//!
//! The foundation's [`omnimvs_sweep::LookupTable`] stores a sampling position
//! for every camera, sphere and grid pixel; with all 192 spheres at 160x640
//! that is 629 MB of f32 for four cameras, more than this method's whole
//! memory budget. The positions are instead recomputed on the fly, which is
//! cheap: for grid ray `r` and inverse depth `d`, the point on the sphere in
//! the camera frame is proportional to `R r + d t` (`cam_from_rig = (R, t)`),
//! and the OCamCalib projection of a direction depends on its angle from the
//! optical axis through one smooth function, tabulated once per camera in
//! the half-angle variable `s = tan(alpha / 2)` (no `atan2`, no polynomial).
//! The result matches [`omnimvs_camera::OcamModel::project`] (and hence the
//! lookup table) to about 1e-3 pixel; see the tests.
//!
//! A lens with tangential distortion (Kalibr's `omni` + `radtan`, a pinhole with
//! `radtan`) has no such radial function: its projector calls the camera model's exact
//! projection for every point instead, slower but the same everywhere else.

use omnimvs_camera::nalgebra::Vector3;
use omnimvs_camera::{Camera, CameraModel};

use crate::{EquirectGrid, SweepError};

/// Entries of the tabulated radial function.
const TABLE_LEN: usize = 4096;

/// Projects points of the sweep spheres of one grid into one camera.
#[derive(Debug, Clone)]
pub struct SphereProjector {
    /// `R r` for every grid pixel (row-major), split by axis: x, y, z.
    rays: [Vec<f32>; 3],
    /// `t` of `cam_from_rig`, metres.
    t: [f32; 3],
    /// `g(s) = rho(alpha) (1 + s^2) / (2 s)` at `s = k * ds`.
    table: Vec<f32>,
    inv_ds: f32,
    /// `tan(max_fov / 4)`: the largest valid `s`.
    s_max: f32,
    /// Affine `c, d, e` and centre `(row, col)` of the camera's radial projection.
    c: f32,
    d: f32,
    e: f32,
    center_row: f32,
    center_col: f32,
    /// The camera's own projection, for a lens that is not radial (then `table` is empty).
    exact: Option<Box<CameraModel>>,
}

impl SphereProjector {
    /// Prepares the projection of `grid`'s rays into `camera`: tabulated for a radial lens,
    /// through the camera model's exact projection for one with tangential distortion.
    ///
    /// # Errors
    /// [`SweepError::Camera`] for a field of view of 360 degrees or more
    /// (no half-angle table).
    pub fn new(
        camera: &Camera,
        camera_number: usize,
        grid: &EquirectGrid,
    ) -> Result<Self, SweepError> {
        let half_fov = camera.model.max_fov_deg().to_radians() / 2.0;
        if !(half_fov > 0.0 && half_fov < std::f64::consts::PI) {
            return Err(SweepError::Camera {
                camera: camera_number,
                reason: format!(
                    "max_fov {} deg: expected a field of view in (0, 360) degrees",
                    camera.model.max_fov_deg()
                ),
            });
        }
        let Some(radial) = camera.model.radial_projection() else {
            return Ok(Self::exact(camera, grid, half_fov));
        };
        let half_fov = radial.half_fov_rad;
        let s_max = (half_fov / 2.0).tan();
        // The table spans a little more than the FOV so that interpolation
        // at s_max stays inside it.
        let ds = s_max * 1.001 / (TABLE_LEN - 2) as f64;
        let table = (0..TABLE_LEN)
            .map(|k| {
                // g(0) is the limit s -> 0; sample just off zero instead.
                let s = (k as f64 * ds).max(ds * 1e-3);
                let alpha = 2.0 * s.atan();
                let rho = radial.radius_px(alpha);
                (rho * (1.0 + s * s) / (2.0 * s)) as f32
            })
            .collect();
        let t = camera.rig_from_cam.inverse().translation.vector;
        Ok(Self {
            rays: Self::camera_rays(camera, grid),
            t: [t.x as f32, t.y as f32, t.z as f32],
            table,
            inv_ds: (1.0 / ds) as f32,
            s_max: s_max as f32,
            c: radial.c as f32,
            d: radial.d as f32,
            e: radial.e as f32,
            center_row: radial.center.row as f32,
            center_col: radial.center.col as f32,
            exact: None,
        })
    }

    /// The grid's rays rotated into the camera frame, split by axis.
    fn camera_rays(camera: &Camera, grid: &EquirectGrid) -> [Vec<f32>; 3] {
        let rot = camera.rig_from_cam.inverse().rotation.to_rotation_matrix();
        let mut rays = [
            Vec::with_capacity(grid.len()),
            Vec::with_capacity(grid.len()),
            Vec::with_capacity(grid.len()),
        ];
        for row in 0..grid.height {
            for col in 0..grid.width {
                let r = rot * grid.ray(row as f64, col as f64);
                for axis in 0..3 {
                    rays[axis].push(r[axis] as f32);
                }
            }
        }
        rays
    }

    /// A projector through `camera`'s exact projection, for a lens that is not radial;
    /// `half_fov` (radians, in `(0, pi)`) bounds what it sees, for [`Self::visible_runs`].
    fn exact(camera: &Camera, grid: &EquirectGrid, half_fov: f64) -> Self {
        let t = camera.rig_from_cam.inverse().translation.vector;
        Self {
            rays: Self::camera_rays(camera, grid),
            t: [t.x as f32, t.y as f32, t.z as f32],
            table: Vec::new(),
            inv_ds: 0.0,
            s_max: (half_fov / 2.0).tan() as f32,
            c: 0.0,
            d: 0.0,
            e: 0.0,
            center_row: 0.0,
            center_col: 0.0,
            exact: Some(Box::new(camera.model.clone())),
        }
    }

    /// The exact projection of grid pixel `i` on the sphere of inverse depth `inv_depth`.
    fn project_exact(&self, model: &CameraModel, i: usize, inv_depth: f32) -> Option<(f32, f32)> {
        let p_cam = Vector3::from_fn(|axis, _| {
            f64::from(self.rays[axis][i]) + f64::from(inv_depth) * f64::from(self.t[axis])
        });
        model
            .project(&p_cam)
            .map(|px| (px.col as f32, px.row as f32))
    }

    /// The fisheye pixel `(col, row)` where grid pixel `i` (row-major) sees
    /// the sphere of inverse depth `inv_depth` (1/m); `None` outside the
    /// field of view.
    #[inline]
    pub fn project(&self, i: usize, inv_depth: f32) -> Option<(f32, f32)> {
        if let Some(model) = &self.exact {
            return self.project_exact(model, i, inv_depth);
        }
        let x = self.rays[0][i] + inv_depth * self.t[0];
        let y = self.rays[1][i] + inv_depth * self.t[1];
        let z = self.rays[2][i] + inv_depth * self.t[2];
        let n2 = x * x + y * y;
        let norm = (n2 + z * z).sqrt();
        let den = norm + z;
        if den <= 1e-12 * norm.max(1e-30) {
            return None; // straight behind the camera
        }
        let s = n2.sqrt() / den;
        if s.is_nan() || s > self.s_max {
            return None;
        }
        let pos = s * self.inv_ds;
        let k = pos as usize; // s >= 0, and s <= s_max keeps k < TABLE_LEN - 1
        let frac = pos - k as f32;
        let g0 = self.table[k];
        let g1 = self.table[k + 1];
        let scale = (g0 + frac * (g1 - g0)) / norm;
        // OCamCalib: x_ocam = Y rho / n (rows), y_ocam = X rho / n (columns).
        let xo = y * scale;
        let yo = x * scale;
        let row = self.c * xo + self.d * yo + self.center_row;
        let col = self.e * xo + yo + self.center_col;
        Some((col, row))
    }

    /// [`Self::project`] for the grid pixels `start..start + cols.len()`,
    /// written as fisheye columns and rows; a point outside the field of
    /// view gets column `-1` (rejected by every sampler). `table_pos` is
    /// scratch of the same length. The square roots and divisions run in a
    /// branch-free loop that vectorises; only the table look-up is scalar.
    ///
    /// On x86-64 with AVX2 and FMA (checked at run time) the branch-free part
    /// runs eight lanes at a time; no fused multiply-add is used, so the
    /// results are the same to the bit (see the tests).
    pub fn project_run(
        &self,
        start: usize,
        inv_depth: f32,
        cols: &mut [f32],
        rows: &mut [f32],
        table_pos: &mut [f32],
    ) {
        let n = cols.len();
        if let Some(model) = &self.exact {
            for (k, (col, row)) in cols.iter_mut().zip(rows.iter_mut()).enumerate() {
                (*col, *row) = self
                    .project_exact(model, start + k, inv_depth)
                    .unwrap_or((-1.0, 0.0));
            }
            return;
        }
        let (table_pos, rows) = (&mut table_pos[..n], &mut rows[..n]);
        #[cfg(target_arch = "x86_64")]
        let done = match pulp::x86::V3::try_new() {
            Some(simd) => self.directions_v3(simd, start, inv_depth, cols, rows, table_pos),
            None => 0,
        };
        #[cfg(not(target_arch = "x86_64"))]
        let done = 0;
        self.directions(
            start + done,
            inv_depth,
            &mut cols[done..],
            &mut rows[done..],
            &mut table_pos[done..],
        );
        self.finish(cols, rows, table_pos);
    }

    /// The branch-free part of [`Self::project_run`]: per grid pixel the
    /// direction's table position (`-1` outside the field of view) and the
    /// affine image of its unit vector, `(e y + x) / |p|` and `(c y + d x) / |p|`.
    fn directions(
        &self,
        start: usize,
        inv_depth: f32,
        cols: &mut [f32],
        rows: &mut [f32],
        table_pos: &mut [f32],
    ) {
        let n = cols.len();
        let (rx, ry, rz) = (
            &self.rays[0][start..start + n],
            &self.rays[1][start..start + n],
            &self.rays[2][start..start + n],
        );
        let [tx, ty, tz] = self.t;
        let last = (TABLE_LEN - 2) as f32;
        let (c, d, e) = (self.c, self.d, self.e);
        let table_pos = &mut table_pos[..n];
        let rows = &mut rows[..n];
        for i in 0..n {
            let x = rx[i] + inv_depth * tx;
            let y = ry[i] + inv_depth * ty;
            let z = rz[i] + inv_depth * tz;
            let n2 = x * x + y * y;
            let norm = (n2 + z * z).sqrt();
            let s = n2.sqrt() / (norm + z);
            let inv_norm = 1.0 / norm;
            // NaN (0/0) and points behind (den ~ 0, s huge) fail this test.
            let valid = s <= self.s_max;
            table_pos[i] = if valid {
                (s * self.inv_ds).min(last)
            } else {
                -1.0
            };
            // OCamCalib: x_ocam = Y rho / n (rows), y_ocam = X rho / n (cols);
            // rho / n = g(s) / norm.
            cols[i] = (e * y + x) * inv_norm;
            rows[i] = (c * y + d * x) * inv_norm;
        }
    }

    /// [`Self::directions`] eight lanes at a time with AVX2, the same
    /// operations in the same order; returns how many leading pixels it did
    /// (a multiple of 8), the rest is left to the plain loop.
    #[cfg(target_arch = "x86_64")]
    fn directions_v3(
        &self,
        simd: pulp::x86::V3,
        start: usize,
        inv_depth: f32,
        cols: &mut [f32],
        rows: &mut [f32],
        table_pos: &mut [f32],
    ) -> usize {
        struct Op<'a> {
            p: &'a SphereProjector,
            simd: pulp::x86::V3,
            start: usize,
            inv_depth: f32,
            cols: &'a mut [f32],
            rows: &'a mut [f32],
            table_pos: &'a mut [f32],
        }
        impl pulp::NullaryFnOnce for Op<'_> {
            type Output = usize;
            #[inline(always)]
            fn call(self) -> usize {
                use pulp::{as_arrays, as_arrays_mut, bytemuck::cast, f32x8};
                let (p, simd) = (self.p, self.simd);
                let n = self.cols.len();
                let (rx, _) = as_arrays::<8, f32>(&p.rays[0][self.start..self.start + n]);
                let (ry, _) = as_arrays::<8, f32>(&p.rays[1][self.start..self.start + n]);
                let (rz, _) = as_arrays::<8, f32>(&p.rays[2][self.start..self.start + n]);
                let (cols, _) = as_arrays_mut::<8, f32>(self.cols);
                let (rows, _) = as_arrays_mut::<8, f32>(&mut self.rows[..n]);
                let (tpos, _) = as_arrays_mut::<8, f32>(&mut self.table_pos[..n]);
                let [tx, ty, tz] = p.t;
                let d = self.inv_depth;
                let (dtx, dty, dtz) = (
                    simd.splat_f32x8(d * tx),
                    simd.splat_f32x8(d * ty),
                    simd.splat_f32x8(d * tz),
                );
                let (c, dd, e) = (
                    simd.splat_f32x8(p.c),
                    simd.splat_f32x8(p.d),
                    simd.splat_f32x8(p.e),
                );
                let one = simd.splat_f32x8(1.0);
                let s_max = simd.splat_f32x8(p.s_max);
                let inv_ds = simd.splat_f32x8(p.inv_ds);
                let last = simd.splat_f32x8((TABLE_LEN - 2) as f32);
                let minus_one = simd.splat_f32x8(-1.0);
                let done = cols.len();
                for i in 0..done {
                    let x = simd.add_f32x8(cast::<[f32; 8], f32x8>(rx[i]), dtx);
                    let y = simd.add_f32x8(cast::<[f32; 8], f32x8>(ry[i]), dty);
                    let z = simd.add_f32x8(cast::<[f32; 8], f32x8>(rz[i]), dtz);
                    let n2 = simd.add_f32x8(simd.mul_f32x8(x, x), simd.mul_f32x8(y, y));
                    let norm = simd.sqrt_f32x8(simd.add_f32x8(n2, simd.mul_f32x8(z, z)));
                    let s = simd.div_f32x8(simd.sqrt_f32x8(n2), simd.add_f32x8(norm, z));
                    let inv_norm = simd.div_f32x8(one, norm);
                    let valid = simd.cmp_le_f32x8(s, s_max);
                    let pos = simd.min_f32x8(simd.mul_f32x8(s, inv_ds), last);
                    tpos[i] = cast(simd.select_f32x8(valid, pos, minus_one));
                    let col = simd.add_f32x8(simd.mul_f32x8(e, y), x);
                    let row = simd.add_f32x8(simd.mul_f32x8(c, y), simd.mul_f32x8(dd, x));
                    cols[i] = cast(simd.mul_f32x8(col, inv_norm));
                    rows[i] = cast(simd.mul_f32x8(row, inv_norm));
                }
                done * 8
            }
        }
        simd.vectorize(Op {
            p: self,
            simd,
            start,
            inv_depth,
            cols,
            rows,
            table_pos,
        })
    }

    /// The table look-up of [`Self::project_run`]: scales the affine unit
    /// vectors by `g(s)` and adds the centre; column `-1` outside the FOV.
    fn finish(&self, cols: &mut [f32], rows: &mut [f32], table_pos: &[f32]) {
        for ((col, row), &pos) in cols.iter_mut().zip(rows.iter_mut()).zip(table_pos.iter()) {
            if pos < 0.0 {
                *col = -1.0;
                continue;
            }
            let k = pos as usize;
            let frac = pos - k as f32;
            let g0 = self.table[k];
            let g = g0 + frac * (self.table[k + 1] - g0);
            *col = *col * g + self.center_col;
            *row = *row * g + self.center_row;
        }
    }

    /// The runs `start..end` of columns of grid row `row` (`width` columns) where some sphere
    /// of inverse depth in `[near, far]` (1/m) can be inside the field of view; the other
    /// columns see none of them, and [`Self::project`] gives `None` there for every such
    /// sphere. Every column when the field of view is 180 degrees or less.
    ///
    /// Why two spheres decide: the point of pixel `i` on the sphere of inverse depth `d` is
    /// proportional to `R r + d t`, a segment as `d` runs over `[near, far]`; beyond 180
    /// degrees the directions the camera cannot see form a convex cone, which holds the
    /// whole segment if it holds both ends. A margin of 1e-3 in `tan(alpha / 2)` keeps
    /// rounding on the side of looking.
    pub fn visible_runs(
        &self,
        row: usize,
        width: usize,
        near: f32,
        far: f32,
    ) -> Vec<(usize, usize)> {
        if self.s_max <= 1.0 {
            return vec![(0, width)];
        }
        let limit = self.s_max * (1.0 + 1e-3);
        // NaN (0 / 0) and points straight behind (s huge) count as outside.
        let inside = |i: usize, d: f32| {
            let x = self.rays[0][i] + d * self.t[0];
            let y = self.rays[1][i] + d * self.t[1];
            let z = self.rays[2][i] + d * self.t[2];
            let n2 = x * x + y * y;
            let s = n2.sqrt() / ((n2 + z * z).sqrt() + z);
            s <= limit
        };
        let mut runs = Vec::new();
        let mut open: Option<usize> = None;
        for col in 0..width {
            let i = row * width + col;
            let seen = inside(i, near) || inside(i, far);
            match (seen, open) {
                (true, None) => open = Some(col),
                (false, Some(start)) => {
                    runs.push((start, col));
                    open = None;
                }
                _ => {}
            }
        }
        if let Some(start) = open {
            runs.push((start, width));
        }
        runs
    }

    /// Number of grid pixels.
    pub fn len(&self) -> usize {
        self.rays[0].len()
    }

    /// Whether the grid has no pixel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{InvDepthHypotheses, LookupTable, SphereSet};
    use omnimvs_camera::{Camera, Rig};

    /// The published rig (the generator's preset, the same cameras as the public
    /// `sunny/config.yaml`).
    fn preset_rig() -> Rig {
        let text = include_str!("../../omnimvs-synth/src/sunny_cameras.yaml");
        omnimvs_camera::parse_config_rig(std::path::Path::new("sunny_cameras.yaml"), text).unwrap()
    }

    /// `rig` with its images resized to `height x width`.
    fn resize_rig(rig: &Rig, height: u32, width: u32) -> Rig {
        let resized = |c: &Camera| {
            let model = c.model.resized(height, width);
            Camera::new(c.id, c.img_dir.clone(), model, c.pose, None)
        };
        Rig::new(rig.cameras.iter().map(resized).collect())
    }

    #[test]
    fn columns_outside_the_visible_runs_see_no_sphere() {
        let rig = preset_rig();
        let grid = EquirectGrid::new(40, 160, 45.0).unwrap();
        let hyps = InvDepthHypotheses::new(64, 0.55).unwrap();
        let (near, far) = (hyps.inv_depth(0.0) as f32, hyps.inv_depth(63.0) as f32);
        let (mut culled, mut seen_near_edge) = (0, 0);
        for (cam, camera) in rig.cameras.iter().enumerate() {
            let p = SphereProjector::new(camera, cam + 1, &grid).unwrap();
            for row in 0..grid.height {
                let runs = p.visible_runs(row, grid.width, near, far);
                assert!(runs.windows(2).all(|r| r[0].1 < r[1].0), "{runs:?}");
                for col in 0..grid.width {
                    let i = row * grid.width + col;
                    let listed = runs.iter().any(|&(a, b)| (a..b).contains(&col));
                    let any =
                        (0..64).any(|n| p.project(i, hyps.inv_depth(n as f64) as f32).is_some());
                    if !listed {
                        assert!(!any, "cam {cam} row {row} col {col}: a sphere is seen");
                        culled += 1;
                    } else if !any {
                        seen_near_edge += 1; // listed by the margin or between spheres
                    }
                }
            }
        }
        // A 220-degree camera misses about a third of the panorama.
        let all = 4 * grid.len();
        assert!(culled > all / 4 && culled < all / 2, "{culled} of {all}");
        assert!(
            seen_near_edge < all / 50,
            "{seen_near_edge} listed but unseen"
        );
    }

    #[test]
    fn matches_the_lookup_table() {
        let preset = preset_rig();
        check_matches_the_lookup_table(&resize_rig(&preset, 192, 200));
    }

    /// The published rig's poses with closed-form lenses of about 220 degrees on 200x192
    /// images: Kannala-Brandt, double sphere, extended unified, unified.
    fn closed_form_rig() -> Rig {
        use omnimvs_camera::{
            CameraModel, CentralCamera, DoubleSphere, ExtendedUnified, KannalaBrandt4, Lens,
            Unified,
        };
        let (cx, cy) = (99.5, 95.5);
        let lenses = [
            Lens::KannalaBrandt4(
                KannalaBrandt4::new(50.0, 50.5, cx, cy, 0.01, -0.002, 0.0, 0.0).unwrap(),
            ),
            Lens::DoubleSphere(DoubleSphere::new(45.0, 45.0, cx, cy, -0.2, 0.6).unwrap()),
            Lens::ExtendedUnified(ExtendedUnified::new(48.0, 47.0, cx, cy, 0.6, 1.1).unwrap()),
            Lens::Unified(Unified::new(80.0, 80.0, cx, cy, 1.0).unwrap()),
        ];
        let preset = preset_rig();
        let cameras = preset
            .cameras
            .iter()
            .zip(lenses)
            .map(|(c, lens)| {
                let fov = lens.max_fov_deg().min(220.0);
                let model =
                    CameraModel::Central(CentralCamera::new(lens, 200, 192, Some(fov)).unwrap());
                Camera::new(c.id, c.img_dir.clone(), model, c.pose, None)
            })
            .collect();
        Rig::new(cameras)
    }

    #[test]
    fn matches_the_lookup_table_for_closed_form_lenses() {
        check_matches_the_lookup_table(&closed_form_rig());
    }

    /// Lenses with tangential distortion (Kalibr's `omni` + `radtan`, a pinhole with `radtan`)
    /// go through the exact projection and agree with the table as well.
    #[test]
    fn matches_the_lookup_table_for_tangential_lenses() {
        use omnimvs_camera::{CameraModel, CentralCamera, Lens, PinholeRadtan, Unified};
        let (cx, cy) = (99.5, 95.5);
        let omni = |xi, radtan| {
            Lens::Unified(Unified::with_radtan(80.0, 80.0, cx, cy, xi, radtan).unwrap())
        };
        let lenses = [
            omni(1.0, [-0.05, 0.01, 0.001, -0.002]),
            omni(1.2, [0.02, -0.003, -0.0015, 0.001]),
            Lens::PinholeRadtan(
                PinholeRadtan::new(70.0, 71.0, cx, cy, -0.1, 0.02, 0.001, 0.0005).unwrap(),
            ),
            omni(0.9, [0.0, 0.0, 0.002, 0.0]),
        ];
        let mut rig = preset_rig();
        for (camera, lens) in rig.cameras.iter_mut().zip(lenses) {
            assert!(!lens.is_radial());
            let fov = lens.max_fov_deg().min(200.0);
            camera.model =
                CameraModel::Central(CentralCamera::new(lens, 200, 192, Some(fov)).unwrap());
            assert!(camera.model.radial_projection().is_none());
        }
        check_matches_the_lookup_table(&rig);
    }

    /// The projector agrees with the lookup table built by the cameras' own projection.
    fn check_matches_the_lookup_table(rig: &Rig) {
        let rig = rig.clone();
        let grid = EquirectGrid::new(20, 80, 45.0).unwrap();
        let hyps = InvDepthHypotheses::new(16, 0.8).unwrap();
        let lut = LookupTable::build(&rig, &grid, &hyps, SphereSet::All).unwrap();
        let (mut checked, mut worst) = (0, 0f64);
        for (cam, camera) in rig.cameras.iter().enumerate() {
            let p = SphereProjector::new(camera, cam + 1, &grid).unwrap();
            for n in 0..16 {
                let d = hyps.inv_depth(n as f64) as f32;
                for i in 0..grid.len() {
                    let (row, col) = (i / grid.width, i % grid.width);
                    let (lc, lr) = lut.pixel(cam, n, row, col);
                    let ours = p.project(i, d);
                    if lc < -1.0 || lr < -1.0 {
                        // Invalid in the table: outside the FOV, or a position
                        // left of / above the image (which we also reject later).
                        if let Some((c, r)) = ours {
                            assert!(c < 0.5 || r < 0.5, "cam {cam} n {n} i {i}: {c},{r}");
                        }
                        continue;
                    }
                    let (c, r) = ours.expect("valid in the table");
                    // Far outside the image (a pinhole near 90 degrees) positions are never
                    // sampled, and the rays' f32 rounding grows with them.
                    let far = 4.0 * f64::from(camera.model.width().max(camera.model.height()));
                    if lc > far || lr > far {
                        continue;
                    }
                    worst = worst
                        .max((f64::from(c) - lc).abs())
                        .max((f64::from(r) - lr).abs());
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000);
        // The batch version agrees with the single one.
        let p = SphereProjector::new(&rig.cameras[1], 2, &grid).unwrap();
        let (mut cols, mut rows) = (vec![0f32; grid.len()], vec![0f32; grid.len()]);
        let mut tmp = vec![0f32; grid.len()];
        p.project_run(0, 0.3, &mut cols, &mut rows, &mut tmp);
        for i in 0..grid.len() {
            match p.project(i, 0.3) {
                Some((c, r)) => assert!((c - cols[i]).abs() < 1e-4 && (r - rows[i]).abs() < 1e-4),
                None => assert_eq!(cols[i], -1.0),
            }
        }
        assert!(worst < 2e-3, "worst difference {worst} px");
    }

    #[test]
    #[cfg(target_arch = "x86_64")]
    fn avx2_directions_equal_the_plain_loop_bit_for_bit() {
        let Some(simd) = pulp::x86::V3::try_new() else {
            eprintln!("no AVX2 here: only the plain loop runs");
            return;
        };
        let preset = preset_rig();
        let grid = EquirectGrid::new(20, 84, 45.0).unwrap();
        let n = grid.len();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for (cam, camera) in preset.cameras.iter().enumerate() {
            let p = SphereProjector::new(camera, cam + 1, &grid).unwrap();
            // Odd start and length: a tail for the plain loop.
            for (start, len, d) in [(0, n, 0.0), (5, n - 9, 0.3), (84, 83, 0.61)] {
                let mut fast = [vec![0f32; len], vec![0f32; len], vec![0f32; len]];
                let mut plain = fast.clone();
                let [c, r, t] = &mut fast;
                let done = p.directions_v3(simd, start, d, c, r, t);
                assert_eq!(done, len / 8 * 8);
                p.directions(
                    start + done,
                    d,
                    &mut c[done..],
                    &mut r[done..],
                    &mut t[done..],
                );
                let [c, r, t] = &mut plain;
                p.directions(start, d, c, r, t);
                for k in 0..3 {
                    assert_eq!(
                        bits(&fast[k]),
                        bits(&plain[k]),
                        "cam {cam} start {start} d {d}"
                    );
                }
                assert!(plain[2].contains(&-1.0), "some points outside the FOV");
            }
        }
    }
}
