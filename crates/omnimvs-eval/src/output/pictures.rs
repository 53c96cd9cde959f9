//! Building blocks of the result pictures (RGB8 rows stacked into one image).

use omnimvs_core::GrayImage;
use omnimvs_data::colormap::{Colormap, colorize};
use omnimvs_data::gt::GroundTruth;
use omnimvs_sweep::EquirectGrid;

use crate::ply::ColoredPoint;

/// Error maps saturate at this error, in percent of N.
pub const ERROR_MAP_MAX_PCT: f64 = 10.0;

/// Inverse depths below this (farther than 1 km) are left out of point clouds.
pub const FAR_INV_DEPTH: f32 = 1e-3;

/// Rows of separator between stacked pictures.
const SEPARATOR_ROWS: usize = 3;

/// Box-filter downscale of a gray image to `width x height` (each output
/// pixel averages the input pixels it covers).
pub fn downscale(image: &GrayImage, width: usize, height: usize) -> GrayImage {
    let mut out = GrayImage::zeros(width, height);
    for r in 0..height {
        let (r0, r1) = (
            r * image.height / height,
            ((r + 1) * image.height / height).max(r * image.height / height + 1),
        );
        for c in 0..width {
            let (c0, c1) = (
                c * image.width / width,
                ((c + 1) * image.width / width).max(c * image.width / width + 1),
            );
            let mut sum = 0f32;
            for rr in r0..r1.min(image.height) {
                sum += image.data[rr * image.width + c0..c1.min(image.width) + rr * image.width]
                    .iter()
                    .sum::<f32>();
            }
            out.data[r * width + c] = sum / ((r1 - r0) * (c1 - c0)) as f32;
        }
    }
    out
}

/// The fisheye images side by side, scaled to a strip `width` pixels wide (RGB8).
pub fn fisheye_strip(images: &[GrayImage], width: usize) -> Vec<u8> {
    let tile_w = width / images.len().max(1);
    let tile_h = images
        .iter()
        .map(|im| tile_w * im.height / im.width.max(1))
        .max()
        .unwrap_or(0);
    let mut rgb = vec![0u8; width * tile_h * 3];
    for (k, im) in images.iter().enumerate() {
        let th = tile_w * im.height / im.width.max(1);
        let small = downscale(im, tile_w, th);
        for r in 0..th {
            for c in 0..tile_w {
                let v = small.data[r * tile_w + c].clamp(0.0, 255.0) as u8;
                let o = (r * width + k * tile_w + c) * 3;
                rgb[o..o + 3].copy_from_slice(&[v, v, v]);
            }
        }
    }
    rgb
}

/// A gray image as RGB8.
pub fn gray_to_rgb(image: &GrayImage) -> Vec<u8> {
    image
        .data
        .iter()
        .flat_map(|&v| {
            let v = v.clamp(0.0, 255.0) as u8;
            [v, v, v]
        })
        .collect()
}

/// Stacks named RGB8 rows `width` pixels wide, with a white separator between
/// them; returns the pixels and the height. (The names document the order in
/// the code and the command's help; no text is drawn.)
pub fn label_rows(rows: &[(String, Vec<u8>)], width: usize) -> (Vec<u8>, usize) {
    let mut px = Vec::new();
    for (i, (_, row)) in rows.iter().enumerate() {
        if i > 0 {
            px.extend(std::iter::repeat_n(255u8, SEPARATOR_ROWS * width * 3));
        }
        px.extend_from_slice(row);
    }
    let height = px.len() / (3 * width.max(1));
    (px, height)
}

/// The error `|n_hat - n*| / N * 100` of an index map as RGB8, saturating at
/// [`ERROR_MAP_MAX_PCT`]; pixels invalid in the ground truth are black.
pub fn error_map(index: &[f32], gt: &GroundTruth, ndepth: usize) -> Vec<u8> {
    let err: Vec<f32> = index
        .iter()
        .zip(&gt.index)
        .map(|(p, g)| (p - g).abs() / ndepth as f32 * 100.0)
        .collect();
    colorize(
        &err,
        0.0,
        ERROR_MAP_MAX_PCT,
        Colormap::Inferno,
        Some(&gt.valid),
    )
}

/// The points of an inverse-depth map on `grid` (rig frame, metres), coloured by `rgb` (the
/// red, green and blue planes of the panorama at that depth; a gray panorama three times);
/// points farther than 1 km are left out.
pub fn point_cloud(grid: &EquirectGrid, inv_depth: &[f32], rgb: [&[f32]; 3]) -> Vec<ColoredPoint> {
    (0..grid.len())
        .filter(|&i| inv_depth[i] > FAR_INV_DEPTH)
        .map(|i| {
            let p = grid.ray((i / grid.width) as f64, (i % grid.width) as f64)
                / f64::from(inv_depth[i]);
            ColoredPoint {
                xyz_m: [p.x as f32, p.y as f32, p.z as f32],
                rgb: rgb.map(|plane| plane[i].clamp(0.0, 255.0) as u8),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn downscale_averages_blocks() {
        let img = GrayImage {
            width: 4,
            height: 2,
            data: vec![0.0, 2.0, 4.0, 6.0, 2.0, 4.0, 6.0, 8.0],
        };
        let s = downscale(&img, 2, 1);
        assert_eq!(s.data, vec![2.0, 6.0]);
    }

    #[test]
    fn rows_stack_with_separators() {
        let rows = vec![
            ("a".to_string(), vec![0u8; 2 * 3]),
            ("b".to_string(), vec![0u8; 2 * 3 * 2]),
        ];
        let (px, h) = label_rows(&rows, 2);
        assert_eq!(h, 1 + SEPARATOR_ROWS + 2);
        assert_eq!(px.len(), h * 2 * 3);
    }

    #[test]
    fn points_take_each_channel_of_their_pixel() {
        let grid = EquirectGrid::new(2, 4, 45.0).unwrap();
        let inv_depth = [0.5, 0.0, 0.5, 0.5, 0.5, 0.5, 0.5, 2.0];
        let ramp: Vec<f32> = (0..8).map(|i| i as f32 * 40.0).collect();
        let flat = [7.9f32; 8];
        let negative = [-3.0f32; 8];
        let points = point_cloud(&grid, &inv_depth, [&ramp, &flat, &negative]);
        // The pixel at infinity is left out.
        assert_eq!(points.len(), 7);
        assert_eq!(points[0].rgb, [0, 7, 0]);
        assert_eq!(points[1].rgb, [80, 7, 0]);
        assert_eq!(points[6].rgb, [255, 7, 0]);
        // Two metres along the ray of the first pixel.
        let ray = grid.ray(0.0, 0.0) * 2.0;
        assert_eq!(points[0].xyz_m, [ray.x as f32, ray.y as f32, ray.z as f32]);
        // A gray panorama three times: gray points.
        let gray = point_cloud(&grid, &inv_depth, [&ramp, &ramp, &ramp]);
        assert!(
            gray.iter()
                .all(|p| p.rgb[0] == p.rgb[1] && p.rgb[1] == p.rgb[2])
        );
    }
}
