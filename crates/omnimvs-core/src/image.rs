//! The single-channel image type.

use crate::interp::BilinearTap;

/// A single-channel f32 image, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct GrayImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f32>,
}

impl GrayImage {
    /// An image of zeros.
    pub fn zeros(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }

    /// Bilinear sample at a fractional pixel position, zero outside
    /// ([`crate::interp::sample_bilinear`]).
    pub fn sample(&self, col: f64, row: f64) -> f32 {
        BilinearTap::from_pixel(col, row, self.width, self.height).apply(&self.data)
    }
}
