use std::f64::consts::PI;

use omnimvs_camera::nalgebra::Vector3;

use crate::SweepError;

/// An equirectangular grid of `height x width` pixels covering all longitudes
/// and the latitudes `±phi_deg` (45 for the network output, 90 for a full
/// panorama), in the rig frame (`FORMATS.md`):
///
/// ```text
/// theta = (col - w/2) / (w/2) * pi + pi/2
/// phi   = (row - (h-1)/2) / ((h-1)/2) * phi_rad
/// ray   = (-cos(phi) cos(theta), sin(phi), cos(phi) sin(theta))
/// ```
///
/// The middle column looks along +z, row 0 is the top (y points down), and
/// columns wrap around: column `w` is column `0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EquirectGrid {
    pub height: usize,
    pub width: usize,
    pub phi_deg: f64,
}

impl EquirectGrid {
    /// A grid; `height >= 2`, `width >= 2`, `0 < phi_deg <= 90`.
    ///
    /// # Errors
    /// [`SweepError::Grid`] for sizes or latitudes out of range.
    pub fn new(height: usize, width: usize, phi_deg: f64) -> Result<Self, SweepError> {
        if height < 2 || width < 2 {
            return Err(SweepError::Grid(format!(
                "size {height}x{width}: expected at least 2x2 (height x width)"
            )));
        }
        if !(phi_deg > 0.0 && phi_deg <= 90.0) {
            return Err(SweepError::Grid(format!(
                "phi_deg {phi_deg}: expected a latitude range in (0, 90] degrees"
            )));
        }
        Ok(Self {
            height,
            width,
            phi_deg,
        })
    }

    /// Number of pixels.
    pub fn len(&self) -> usize {
        self.height * self.width
    }

    /// Whether the grid has no pixel (never true for a validated grid).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Longitude `theta` (radians) of a (fractional) column.
    pub fn theta_rad(&self, col: f64) -> f64 {
        let half_w = self.width as f64 / 2.0;
        (col - half_w) / half_w * PI + PI / 2.0
    }

    /// Latitude `phi` (radians) of a (fractional) row; positive is down.
    pub fn phi_rad(&self, row: f64) -> f64 {
        let half_h = (self.height as f64 - 1.0) / 2.0;
        (row - half_h) / half_h * self.phi_deg.to_radians()
    }

    /// The unit ray in the rig frame of a (fractional) grid position.
    pub fn ray(&self, row: f64, col: f64) -> Vector3<f64> {
        let theta = self.theta_rad(col);
        let phi = self.phi_rad(row);
        Vector3::new(-phi.cos() * theta.cos(), phi.sin(), phi.cos() * theta.sin())
    }

    /// The rays of every pixel, row-major.
    pub fn rays(&self) -> Vec<Vector3<f64>> {
        let mut out = Vec::with_capacity(self.len());
        for row in 0..self.height {
            for col in 0..self.width {
                out.push(self.ray(row as f64, col as f64));
            }
        }
        out
    }

    /// The fractional `(row, col)` of a direction in the rig frame (the
    /// inverse of [`Self::ray`]); `col` in `[0, width)`. Rows outside
    /// `[0, height-1]` mean the direction is outside the latitude range.
    pub fn position_of(&self, dir: &Vector3<f64>) -> (f64, f64) {
        let n = dir.norm();
        let phi = (dir.y / n).clamp(-1.0, 1.0).asin();
        let theta = (dir.z / n).atan2(-dir.x / n);
        let half_w = self.width as f64 / 2.0;
        let mut col = ((theta - PI / 2.0) / PI + 1.0) * half_w;
        let w = self.width as f64;
        col = col.rem_euclid(w);
        let half_h = (self.height as f64 - 1.0) / 2.0;
        let row = phi / self.phi_deg.to_radians() * half_h + half_h;
        (row, col)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn middle_column_looks_forward_and_top_row_up() {
        let g = EquirectGrid::new(161, 640, 90.0).unwrap();
        let fwd = g.ray(80.0, 320.0);
        assert!((fwd - Vector3::new(0.0, 0.0, 1.0)).norm() < 1e-12);
        // Row 0 at phi = -90 deg: y = -1 (up, since y points down).
        let up = g.ray(0.0, 100.0);
        assert!((up.y + 1.0).abs() < 1e-12);
        // Column 0 looks along -z (theta = -pi/2).
        let back = g.ray(80.0, 0.0);
        assert!((back - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-12);
        // col = 3w/4 (theta = pi) looks along +x, col = w/4 along -x.
        let side = g.ray(80.0, 480.0);
        assert!((side - Vector3::new(1.0, 0.0, 0.0)).norm() < 1e-12);
        let other = g.ray(80.0, 160.0);
        assert!((other - Vector3::new(-1.0, 0.0, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn position_of_inverts_ray() {
        let g = EquirectGrid::new(160, 640, 45.0).unwrap();
        for &(row, col) in &[(0.0, 0.0), (10.5, 33.25), (159.0, 639.5), (80.0, 320.0)] {
            let (r, c) = g.position_of(&g.ray(row, col));
            assert!((r - row).abs() < 1e-9, "row {row} -> {r}");
            assert!((c - col).abs() < 1e-9, "col {col} -> {c}");
        }
    }

    #[test]
    fn rejects_bad_grids() {
        assert!(EquirectGrid::new(1, 640, 45.0).is_err());
        assert!(EquirectGrid::new(160, 640, 0.0).is_err());
        assert!(EquirectGrid::new(160, 640, 91.0).is_err());
    }
}
