//! Contact sheets: the fisheye images of a frame in a row (reduced), the
//! ground-truth inverse depth in colour below.

use omnimvs_data::colormap::{Colormap, colorize};

/// An RGB8 picture.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub data: Vec<u8>,
}

impl RgbImage {
    fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            data: vec![0; width * height * 3],
        }
    }

    fn blit(&mut self, x0: usize, y0: usize, w: usize, h: usize, rgb: &[u8]) {
        for y in 0..h.min(self.height.saturating_sub(y0)) {
            for x in 0..w.min(self.width.saturating_sub(x0)) {
                let (s, d) = ((y * w + x) * 3, ((y0 + y) * self.width + x0 + x) * 3);
                self.data[d..d + 3].copy_from_slice(&rgb[s..s + 3]);
            }
        }
    }
}

/// Box-filter reduction of a gray image by an integer `factor`, as RGB.
fn reduce_gray(img: &[u8], w: usize, h: usize, factor: usize) -> (usize, usize, Vec<u8>) {
    let f = factor.max(1);
    let (ow, oh) = (w / f, h / f);
    let mut out = Vec::with_capacity(ow * oh * 3);
    for y in 0..oh {
        for x in 0..ow {
            let mut s = 0u32;
            for dy in 0..f {
                for dx in 0..f {
                    s += u32::from(img[(y * f + dy) * w + x * f + dx]);
                }
            }
            let v = (s / (f * f) as u32) as u8;
            out.extend([v, v, v]);
        }
    }
    (ow, oh, out)
}

/// A contact sheet: each `(image, width, height)` reduced by `factor` in a
/// row, then the inverse-depth panorama (`gt_w x gt_h`) coloured with the
/// turbo map from 0 to `max_inv_depth` (1/m), centred below.
pub fn contact_sheet(
    images: &[(&[u8], usize, usize)],
    factor: usize,
    inv_depth: &[f32],
    gt_w: usize,
    gt_h: usize,
    max_inv_depth: f64,
) -> RgbImage {
    let reduced: Vec<_> = images
        .iter()
        .map(|(img, w, h)| reduce_gray(img, *w, *h, factor))
        .collect();
    let row_w: usize = reduced.iter().map(|r| r.0).sum();
    let row_h = reduced.iter().map(|r| r.1).max().unwrap_or(0);
    let width = row_w.max(gt_w);
    let mut sheet = RgbImage::new(width, row_h + gt_h);
    let mut x = 0;
    for (w, h, rgb) in &reduced {
        sheet.blit(x, 0, *w, *h, rgb);
        x += w;
    }
    let colored = colorize(inv_depth, 0.0, max_inv_depth, Colormap::Turbo, None);
    sheet.blit((width - gt_w) / 2, row_h, gt_w, gt_h, &colored);
    sheet
}
