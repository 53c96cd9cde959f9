//! The colour image type: three planes of the gray type.

use crate::GrayImage;

/// A colour image as three f32 planes (red, green, blue) of the same size, each in the
/// units of a [`GrayImage`] (0..255 for 8-bit images).
///
/// Planar, so that every gray operation (bilinear sampling, panorama composition) applies
/// to each channel unchanged.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourPlanes {
    /// Red, green, blue.
    pub planes: [GrayImage; 3],
}

impl ColourPlanes {
    /// A gray image as colour: the same plane in red, green and blue.
    pub fn from_gray(gray: &GrayImage) -> Self {
        Self {
            planes: [gray.clone(), gray.clone(), gray.clone()],
        }
    }

    /// Width in pixels (that of every plane).
    pub fn width(&self) -> usize {
        self.planes[0].width
    }

    /// Height in pixels (that of every plane).
    pub fn height(&self) -> usize {
        self.planes[0].height
    }

    /// Interleaved 8-bit RGB, row-major (values rounded and clamped to 0..255).
    pub fn to_rgb8(&self) -> Vec<u8> {
        let [r, g, b] = &self.planes;
        r.data
            .iter()
            .zip(&g.data)
            .zip(&b.data)
            .flat_map(|((&r, &g), &b)| [to_u8(r), to_u8(g), to_u8(b)])
            .collect()
    }
}

/// A gray value as 8 bits, rounded and clamped (as the gray PNG writer does).
fn to_u8(v: f32) -> u8 {
    v.round().clamp(0.0, 255.0) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(values: &[f32]) -> GrayImage {
        GrayImage {
            width: values.len(),
            height: 1,
            data: values.to_vec(),
        }
    }

    #[test]
    fn gray_as_colour_repeats_the_plane() {
        let gray = plane(&[0.0, 127.6, 300.0]);
        let colour = ColourPlanes::from_gray(&gray);
        assert_eq!((colour.width(), colour.height()), (3, 1));
        assert_eq!(
            colour.to_rgb8(),
            vec![0, 0, 0, 128, 128, 128, 255, 255, 255]
        );
    }

    #[test]
    fn rgb8_interleaves_the_planes() {
        let colour = ColourPlanes {
            planes: [plane(&[1.0, 4.0]), plane(&[2.0, 5.0]), plane(&[3.0, -6.0])],
        };
        assert_eq!(colour.to_rgb8(), vec![1, 2, 3, 4, 5, 0]);
    }
}
