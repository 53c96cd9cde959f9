//! Reading fisheye images as gray f32, the network's input normalisation, and
//! atomic PNG writing.

use std::path::Path;

use image::{DynamicImage, ExtendedColorType, ImageEncoder};
use omnimvs_camera::ValidityMask;
use omnimvs_core::GrayImage;

use crate::DataError;

/// Reads an image as gray f32 in `[0, 255]`: 8-bit gray as is, RGB(A) as the
/// mean of the three colour channels (the reference's `rgb2gray`), 16-bit
/// scaled by 1/257.
///
/// # Errors
/// [`DataError::Io`] for a missing file, [`DataError::Image`] for a corrupt one.
pub fn read_gray(path: &Path) -> Result<GrayImage, DataError> {
    let bytes = std::fs::read(path).map_err(|e| DataError::io(path, e))?;
    let img = image::load_from_memory(&bytes).map_err(|source| DataError::Image {
        path: path.to_path_buf(),
        source,
    })?;
    let (width, height) = (img.width() as usize, img.height() as usize);
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
    Ok(GrayImage {
        width,
        height,
        data,
    })
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
    let img = read_gray(path)?;
    if img.width != width || img.height != height {
        return Err(DataError::ImageSize {
            path: path.to_path_buf(),
            found_w: img.width,
            found_h: img.height,
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
