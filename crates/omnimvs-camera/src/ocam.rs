use nalgebra::Vector3;

use crate::Pixel;
use crate::batch::{BATCH_LANES, FovCone};

/// Scaramuzza's OCamCalib fisheye model, evaluated exactly as the public OmniMVS
/// reference code does (`FORMATS.md`, "OCamCalib").
///
/// OCamCalib names the image row `x` and the column `y`; this struct keeps the
/// file's parameters as they are and converts to [`Pixel`] `(col, row)` at the
/// boundary of [`project`](Self::project) / [`unproject`](Self::unproject).
#[derive(Debug, Clone, PartialEq)]
pub struct OcamModel {
    /// `cam2world` polynomial `z(rho) = sum poly[i] rho^i` (ascending powers).
    pub poly: Vec<f64>,
    /// `world2cam` polynomial `rho(theta) = sum inv_poly[i] theta^i`, with
    /// `theta` the angle from the image plane in radians.
    pub inv_poly: Vec<f64>,
    /// Distortion centre row `xc`, pixels, 0-based.
    pub center_row: f64,
    /// Distortion centre column `yc`, pixels, 0-based.
    pub center_col: f64,
    /// Affine term `c`.
    pub c: f64,
    /// Affine term `d`.
    pub d: f64,
    /// Affine term `e`.
    pub e: f64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Full field of view in degrees (220 for the published rigs).
    pub max_fov_deg: f64,
}

/// Horner evaluation of `sum coeffs[i] x^i`.
pub(crate) fn polyval(coeffs: &[f64], x: f64) -> f64 {
    coeffs.iter().rev().fold(0.0, |acc, &a| acc * x + a)
}

impl OcamModel {
    /// Half the field of view, radians: the largest angle from the optical
    /// axis that the camera sees.
    pub fn half_fov_rad(&self) -> f64 {
        self.max_fov_deg.to_radians() / 2.0
    }

    /// Projects a point in the camera frame to a pixel (`world2cam`).
    ///
    /// Returns `None` when the point's angle from the optical axis exceeds
    /// half the field of view. A point inside the field of view may still
    /// project outside the image rectangle; see [`Self::contains`].
    pub fn project(&self, p_cam: &Vector3<f64>) -> Option<Pixel> {
        let norm = (p_cam.x * p_cam.x + p_cam.y * p_cam.y).sqrt() + f64::EPSILON;
        let theta = (-p_cam.z).atan2(norm);
        if self.beyond_fov(theta) {
            return None;
        }
        Some(self.pixel_of(p_cam, norm, polyval(&self.inv_poly, theta)))
    }

    /// [`Self::project`] of every point of `points` into `pixels` (same length), with the
    /// same result to the bit. Faster: the `world2cam` polynomial runs over
    /// eight points at a time, whose Horner chains overlap instead of waiting on
    /// one another, and points clearly outside the field of view need no `atan2`.
    pub fn project_many(&self, points: &[Vector3<f64>], pixels: &mut [Option<Pixel>]) {
        debug_assert_eq!(points.len(), pixels.len());
        // The angle from the axis is atan2(norm, z): the cone skips it where the point is
        // clearly outside (the lane's rho is then computed and not used).
        let cone = FovCone::new(self.half_fov_rad());
        let mut chunks = points.chunks_exact(BATCH_LANES);
        let mut outs = pixels.chunks_exact_mut(BATCH_LANES);
        for (p, out) in (&mut chunks).zip(&mut outs) {
            let mut norm = [0.0; BATCH_LANES];
            let mut theta = [0.0; BATCH_LANES];
            for l in 0..BATCH_LANES {
                norm[l] = (p[l].x * p[l].x + p[l].y * p[l].y).sqrt() + f64::EPSILON;
                theta[l] = match cone.side(norm[l], p[l].z) {
                    Some(false) => f64::INFINITY,
                    _ => (-p[l].z).atan2(norm[l]),
                };
            }
            // polyval's fold, lane by lane.
            let mut rho = [0.0; BATCH_LANES];
            for &a in self.inv_poly.iter().rev() {
                for l in 0..BATCH_LANES {
                    rho[l] = rho[l] * theta[l] + a;
                }
            }
            for l in 0..BATCH_LANES {
                out[l] =
                    (!self.beyond_fov(theta[l])).then(|| self.pixel_of(&p[l], norm[l], rho[l]));
            }
        }
        for (p, out) in chunks.remainder().iter().zip(outs.into_remainder()) {
            *out = self.project(p);
        }
    }

    /// Whether a point at `theta` (radians from the image plane, towards `-z`) is outside
    /// the field of view (not for NaN: `project` has always let it through).
    #[inline(always)]
    fn beyond_fov(&self, theta: f64) -> bool {
        theta + std::f64::consts::FRAC_PI_2 > self.half_fov_rad()
    }

    /// The end of [`Self::project`] once `norm` and `rho` are known.
    #[inline(always)]
    fn pixel_of(&self, p_cam: &Vector3<f64>, norm: f64, rho: f64) -> Pixel {
        let x = p_cam.y / norm * rho;
        let y = p_cam.x / norm * rho;
        let row = self.c * x + self.d * y + self.center_row;
        let col = self.e * x + y + self.center_col;
        Pixel::new(col, row)
    }

    /// The unit ray (camera frame) of a pixel (`cam2world`).
    ///
    /// Returns `None` when the ray's angle from the optical axis exceeds half
    /// the field of view.
    pub fn unproject(&self, px: Pixel) -> Option<Vector3<f64>> {
        let u = px.row - self.center_row;
        let v = px.col - self.center_col;
        let inv_det = 1.0 / (self.c - self.d * self.e);
        let x = inv_det * (u - self.d * v);
        let y = inv_det * (-self.e * u + self.c * v);
        let rho = (x * x + y * y).sqrt();
        let z = polyval(&self.poly, rho);
        if rho.atan2(-z) > self.half_fov_rad() {
            return None;
        }
        Some(Vector3::new(y, x, -z).normalize())
    }

    /// The same rays for images resized to `height x width` pixels. Pixel
    /// centres map as `(p + 0.5) * s - 0.5`; the radius scales with the column
    /// factor and the row/column aspect goes into the affine terms `c`, `d`.
    pub fn resized(&self, height: u32, width: u32) -> Self {
        let sr = f64::from(height) / f64::from(self.height);
        let sc = f64::from(width) / f64::from(self.width);
        Self {
            // z'(rho') = s z(rho'/s): a_i' = a_i s^(1-i); rho' = s rho.
            poly: self
                .poly
                .iter()
                .enumerate()
                .map(|(i, a)| a * sc.powi(1 - i as i32))
                .collect(),
            inv_poly: self.inv_poly.iter().map(|p| p * sc).collect(),
            center_row: (self.center_row + 0.5) * sr - 0.5,
            center_col: (self.center_col + 0.5) * sc - 0.5,
            c: self.c * sr / sc,
            d: self.d * sr / sc,
            e: self.e,
            width,
            height,
            max_fov_deg: self.max_fov_deg,
        }
    }

    /// Whether a pixel position lies inside the image rectangle
    /// `[0, width-1] x [0, height-1]`.
    pub fn contains(&self, px: Pixel) -> bool {
        px.col >= 0.0
            && px.row >= 0.0
            && px.col <= f64::from(self.width) - 1.0
            && px.row <= f64::from(self.height) - 1.0
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) use crate::sunny_cam1::sunny_cam1;

    #[test]
    fn principal_point_looks_along_optical_axis() {
        let cam = sunny_cam1();
        let ray = cam.unproject(Pixel::new(399.0, 383.0)).unwrap();
        assert!((ray - Vector3::new(0.0, 0.0, 1.0)).norm() < 1e-12);
        let px = cam.project(&Vector3::new(0.0, 0.0, 5.0)).unwrap();
        assert!((px.col - 399.0).abs() < 1e-9 && (px.row - 383.0).abs() < 1e-9);
    }

    #[test]
    fn axes_map_to_columns_and_rows() {
        let cam = sunny_cam1();
        // +x (right) moves the projection right in columns, +y (down) down in rows.
        let right = cam.project(&Vector3::new(1.0, 0.0, 2.0)).unwrap();
        assert!(right.col > 399.0 + 10.0 && (right.row - 383.0).abs() < 1e-9);
        let down = cam.project(&Vector3::new(0.0, 1.0, 2.0)).unwrap();
        assert!(down.row > 383.0 + 10.0 && (down.col - 399.0).abs() < 1e-9);
    }

    #[test]
    fn field_of_view_limits_projection() {
        let cam = sunny_cam1();
        // 109 degrees from the axis: inside the 220-degree FOV.
        let a = 109f64.to_radians();
        assert!(cam.project(&Vector3::new(a.sin(), 0.0, a.cos())).is_some());
        // 111 degrees: outside.
        let a = 111f64.to_radians();
        assert!(cam.project(&Vector3::new(a.sin(), 0.0, a.cos())).is_none());
        // Straight behind.
        assert!(cam.project(&Vector3::new(0.0, 0.0, -1.0)).is_none());
        // Image corners of a 220-degree circular fisheye are outside the FOV.
        assert!(cam.unproject(Pixel::new(0.0, 0.0)).is_none());
    }
}
