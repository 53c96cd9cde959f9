//! Reading fisheye images as gray f32 (and, for panoramas and point clouds, their colour),
//! the network's input normalisation, and atomic PNG writing.

use std::path::Path;

use image::{DynamicImage, ExtendedColorType, ImageEncoder};
use omnimvs_camera::ValidityMask;
use omnimvs_core::{ColourPlanes, GrayImage};

use crate::DataError;

/// An image as decoded: its gray version (what matching reads) and, for a colour file, its
/// three colour planes (what panoramas and point clouds show).
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedImage {
    /// As [`read_gray`] reads it.
    pub gray: GrayImage,
    /// Red, green and blue in `[0, 255]` (16-bit channels scaled by 1/257), for a file with
    /// colour channels (RGB, RGBA); `None` for a single-channel one (gray, gray + alpha).
    pub colour: Option<ColourPlanes>,
}

impl DecodedImage {
    /// The size, `(width, height)`.
    pub fn size(&self) -> (usize, usize) {
        (self.gray.width, self.gray.height)
    }

    /// The colour planes, a gray image's own plane in all three (R = G = B).
    pub fn to_colour(&self) -> ColourPlanes {
        self.colour
            .clone()
            .unwrap_or_else(|| ColourPlanes::from_gray(&self.gray))
    }
}

/// The colour images of a frame's decoded images: `None` when every one is single-channel,
/// else every camera's colour, a gray camera's as R = G = B (a rig mixing gray and colour
/// cameras).
pub fn colour_of_frame(images: &[DecodedImage]) -> Option<Vec<ColourPlanes>> {
    images
        .iter()
        .any(|image| image.colour.is_some())
        .then(|| images.iter().map(DecodedImage::to_colour).collect())
}

/// Reads an image as gray f32 in `[0, 255]`: 8-bit gray as is, RGB(A) as the
/// mean of the three colour channels (the reference's `rgb2gray`), 16-bit
/// scaled by 1/257.
///
/// # Errors
/// [`DataError::Io`] for a missing file, [`DataError::Image`] for a corrupt one.
pub fn read_gray(path: &Path) -> Result<GrayImage, DataError> {
    Ok(read_decoded(path, false)?.gray)
}

/// Reads an image once as gray ([`read_gray`]) and, when `colour` is asked and the file has
/// colour channels, as its colour planes.
///
/// # Errors
/// As [`read_gray`].
pub fn read_decoded(path: &Path, colour: bool) -> Result<DecodedImage, DataError> {
    let bytes = std::fs::read(path).map_err(|e| DataError::io(path, e))?;
    let img = image::load_from_memory(&bytes).map_err(|source| DataError::Image {
        path: path.to_path_buf(),
        source,
    })?;
    let (width, height) = (img.width() as usize, img.height() as usize);
    let plane = |data: Vec<f32>| GrayImage {
        width,
        height,
        data,
    };
    let colour = (colour && img.color().has_color()).then(|| colour_planes(&img, plane));
    let data: Vec<f32> = match img {
        DynamicImage::ImageLuma8(g) => g.into_raw().into_iter().map(f32::from).collect(),
        DynamicImage::ImageLuma16(g) => g
            .into_raw()
            .into_iter()
            .map(|v| f32::from(v) / 257.0)
            .collect(),
        DynamicImage::ImageRgb8(rgb) => rgb
            .into_raw()
            .chunks_exact(3)
            .map(|p| (f32::from(p[0]) + f32::from(p[1]) + f32::from(p[2])) / 3.0)
            .collect(),
        other => other
            .into_rgb32f()
            .into_raw()
            .chunks_exact(3)
            .map(|p| (p[0] + p[1] + p[2]) / 3.0 * 255.0)
            .collect(),
    };
    Ok(DecodedImage {
        gray: plane(data),
        colour,
    })
}

/// The red, green and blue planes of a colour image in `[0, 255]`: 8-bit as is, others
/// through f32 (alpha dropped).
fn colour_planes(img: &DynamicImage, plane: impl Fn(Vec<f32>) -> GrayImage) -> ColourPlanes {
    let channel = |interleaved: &[f32], k: usize| -> Vec<f32> {
        interleaved.iter().skip(k).step_by(3).copied().collect()
    };
    let interleaved: Vec<f32> = match img {
        DynamicImage::ImageRgb8(rgb) => rgb.as_raw().iter().map(|&v| f32::from(v)).collect(),
        other => other
            .to_rgb32f()
            .into_raw()
            .into_iter()
            .map(|v| v * 255.0)
            .collect(),
    };
    ColourPlanes {
        planes: std::array::from_fn(|k| plane(channel(&interleaved, k))),
    }
}

/// [`read_gray`], checking the size against what the camera expects.
///
/// # Errors
/// As [`read_gray`], and [`DataError::ImageSize`] naming the file.
pub fn read_gray_sized(
    path: &Path,
    width: usize,
    height: usize,
    what: &str,
) -> Result<GrayImage, DataError> {
    Ok(read_decoded_sized(path, false, width, height, what)?.gray)
}

/// [`read_decoded`], checking the size against what the camera expects.
///
/// # Errors
/// As [`read_gray`], and [`DataError::ImageSize`] naming the file.
pub fn read_decoded_sized(
    path: &Path,
    colour: bool,
    width: usize,
    height: usize,
    what: &str,
) -> Result<DecodedImage, DataError> {
    let img = read_decoded(path, colour)?;
    let (found_w, found_h) = img.size();
    if found_w != width || found_h != height {
        return Err(DataError::ImageSize {
            path: path.to_path_buf(),
            found_w,
            found_h,
            want_w: width,
            want_h: height,
            what: what.to_string(),
        });
    }
    Ok(img)
}

/// The network input: zero mean and unit variance over the valid pixels
/// (population statistics), invalid pixels set to 0 afterwards. A constant
/// image becomes all zeros.
///
/// # Errors
/// [`SweepError::Mismatch`](omnimvs_sweep::SweepError::Mismatch) when the mask size differs from the image's.
pub fn normalize_for_network(
    img: &GrayImage,
    mask: Option<&ValidityMask>,
) -> Result<GrayImage, DataError> {
    if let Some(m) = mask
        && (m.width as usize != img.width || m.height as usize != img.height)
    {
        return Err(DataError::mismatch(
            "mask size",
            format!("{}x{}", img.width, img.height),
            format!("{}x{}", m.width, m.height),
        ));
    }
    let valid = |i: usize| mask.is_none_or(|m| m.valid[i]);
    let (mut sum, mut n) = (0f64, 0usize);
    for (i, &v) in img.data.iter().enumerate() {
        if valid(i) {
            sum += f64::from(v);
            n += 1;
        }
    }
    let mean = if n > 0 { sum / n as f64 } else { 0.0 };
    let mut var = 0f64;
    for (i, &v) in img.data.iter().enumerate() {
        if valid(i) {
            var += (f64::from(v) - mean).powi(2);
        }
    }
    let std = if n > 0 { (var / n as f64).sqrt() } else { 0.0 };
    let data = img
        .data
        .iter()
        .enumerate()
        .map(|(i, &v)| {
            if !valid(i) || std == 0.0 {
                0.0
            } else {
                ((f64::from(v) - mean) / std) as f32
            }
        })
        .collect();
    Ok(GrayImage {
        width: img.width,
        height: img.height,
        data,
    })
}

/// Encodes 8-bit pixels (`channels` = 1 gray, 3 RGB) as PNG and writes the
/// file atomically.
///
/// # Errors
/// [`DataError::Io`] naming the file, [`SweepError::Mismatch`](omnimvs_sweep::SweepError::Mismatch) for a buffer of
/// the wrong length.
pub fn write_png_u8(
    path: &Path,
    width: usize,
    height: usize,
    channels: usize,
    pixels: &[u8],
) -> Result<(), DataError> {
    if pixels.len() != width * height * channels {
        return Err(DataError::mismatch(
            format!("{}: pixel buffer length", path.display()),
            width * height * channels,
            pixels.len(),
        ));
    }
    let color = match channels {
        1 => ExtendedColorType::L8,
        3 => ExtendedColorType::Rgb8,
        4 => ExtendedColorType::Rgba8,
        _ => return Err(DataError::mismatch("PNG channels", "1, 3 or 4", channels)),
    };
    let mut buf = Vec::new();
    image::codecs::png::PngEncoder::new(&mut buf)
        .write_image(pixels, width as u32, height as u32, color)
        .map_err(|e| DataError::format(path, format!("cannot encode PNG: {e}")))?;
    omnimvs_core::fs::write_atomic(path, &buf).map_err(|e| DataError::io(path, e))
}

/// Writes colour planes as an 8-bit RGB PNG, values rounded and clamped to `[0, 255]` as
/// [`write_gray_png`] does.
///
/// # Errors
/// As [`write_png_u8`].
pub fn write_colour_png(path: &Path, img: &ColourPlanes) -> Result<(), DataError> {
    write_png_u8(path, img.width(), img.height(), 3, &img.to_rgb8())
}

/// Writes a gray f32 image as an 8-bit PNG, values clamped to `[0, 255]`.
///
/// # Errors
/// As [`write_png_u8`].
pub fn write_gray_png(path: &Path, img: &GrayImage) -> Result<(), DataError> {
    let px: Vec<u8> = img
        .data
        .iter()
        .map(|&v| v.round().clamp(0.0, 255.0) as u8)
        .collect();
    write_png_u8(path, img.width, img.height, 1, &px)
}
