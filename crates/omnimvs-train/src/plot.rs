//! The PNG of the training curves: training and validation loss (index units) per epoch,
//! drawn directly into an RGB buffer (a 3x5 pixel font for the labels) so that the crate
//! needs no plotting library.

use std::path::Path;

use omnimvs_data::image_io::write_png_u8;

use crate::error::TrainError;
use crate::trainer::EpochRecord;

const WIDTH: usize = 640;
const HEIGHT: usize = 400;
const LEFT: usize = 70;
const RIGHT: usize = 20;
const TOP: usize = 40;
const BOTTOM: usize = 50;
const TRAIN_COLOR: [u8; 3] = [31, 119, 180];
const VAL_COLOR: [u8; 3] = [255, 127, 14];
const AXIS_COLOR: [u8; 3] = [40, 40, 40];
const GRID_COLOR: [u8; 3] = [225, 225, 225];
const FONT_SCALE: usize = 2;

/// 3x5 glyphs, one row per 3 bits (most significant bit on the left).
fn glyph(c: char) -> Option<[u8; 5]> {
    Some(match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '6' => [7, 4, 7, 5, 7],
        '7' => [7, 1, 1, 1, 1],
        '8' => [7, 5, 7, 5, 7],
        '9' => [7, 5, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        '-' => [0, 0, 7, 0, 0],
        'a' => [0, 7, 1, 7, 7],
        'c' => [0, 7, 4, 4, 7],
        'e' => [7, 5, 7, 4, 7],
        'h' => [4, 4, 7, 5, 5],
        'i' => [2, 0, 2, 2, 2],
        'l' => [6, 2, 2, 2, 7],
        'n' => [0, 6, 5, 5, 5],
        'o' => [0, 7, 5, 5, 7],
        'p' => [7, 5, 7, 4, 4],
        'r' => [0, 7, 4, 4, 4],
        's' => [7, 4, 7, 1, 7],
        't' => [4, 7, 4, 4, 7],
        'v' => [0, 5, 5, 5, 2],
        ' ' => [0; 5],
        _ => return None,
    })
}

struct Canvas {
    pixels: Vec<u8>,
}

impl Canvas {
    fn new() -> Self {
        Self {
            pixels: vec![255; WIDTH * HEIGHT * 3],
        }
    }

    fn put(&mut self, x: i64, y: i64, color: [u8; 3]) {
        if x >= 0 && y >= 0 && (x as usize) < WIDTH && (y as usize) < HEIGHT {
            let i = (y as usize * WIDTH + x as usize) * 3;
            self.pixels[i..i + 3].copy_from_slice(&color);
        }
    }

    /// A line of width 2 (Bresenham, thickened).
    fn line(&mut self, (x0, y0): (f64, f64), (x1, y1): (f64, f64), color: [u8; 3]) {
        let steps = (x1 - x0).abs().max((y1 - y0).abs()).ceil().max(1.0) as usize;
        for s in 0..=steps {
            let t = s as f64 / steps as f64;
            let (x, y) = (x0 + (x1 - x0) * t, y0 + (y1 - y0) * t);
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                self.put(x.round() as i64 + dx, y.round() as i64 + dy, color);
            }
        }
    }

    fn text(&mut self, x: usize, y: usize, text: &str, color: [u8; 3]) {
        for (k, c) in text.chars().enumerate() {
            let Some(rows) = glyph(c) else { continue };
            let x0 = x + k * 4 * FONT_SCALE;
            for (r, bits) in rows.iter().enumerate() {
                for col in 0..3 {
                    if bits >> (2 - col) & 1 == 1 {
                        for sy in 0..FONT_SCALE {
                            for sx in 0..FONT_SCALE {
                                self.put(
                                    (x0 + col * FONT_SCALE + sx) as i64,
                                    (y + r * FONT_SCALE + sy) as i64,
                                    color,
                                );
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Width in pixels of `text` in the plot's font.
fn text_width(text: &str) -> usize {
    text.chars().count() * 4 * FONT_SCALE
}

/// Draws the training and validation loss of `history` and writes the PNG to `path`
/// (through a temporary file).
///
/// # Errors
/// [`TrainError`] when the file cannot be written.
pub fn plot_curves(history: &[EpochRecord], path: &Path) -> Result<(), TrainError> {
    let mut canvas = Canvas::new();
    let train: Vec<(f64, f64)> = history
        .iter()
        .map(|r| (r.epoch as f64, r.train_loss))
        .collect();
    let val: Vec<(f64, f64)> = history
        .iter()
        .filter_map(|r| r.val_loss.map(|v| (r.epoch as f64, v)))
        .collect();
    let max_epoch = history.iter().map(|r| r.epoch).max().unwrap_or(1).max(2) as f64;
    let max_loss = train
        .iter()
        .chain(&val)
        .map(|p| p.1)
        .filter(|v| v.is_finite())
        .fold(0f64, f64::max)
        .max(1e-3)
        * 1.05;
    let (x0, x1) = (LEFT as f64, (WIDTH - RIGHT) as f64);
    let (y0, y1) = ((HEIGHT - BOTTOM) as f64, TOP as f64);
    let px = |(e, l): (f64, f64)| {
        (
            x0 + (e - 1.0) / (max_epoch - 1.0) * (x1 - x0),
            y0 + l / max_loss * (y1 - y0),
        )
    };
    // Grid and tick labels.
    for k in 0..=5 {
        let value = max_loss * k as f64 / 5.0;
        let y = y0 + value / max_loss * (y1 - y0);
        canvas.line((x0, y), (x1, y), GRID_COLOR);
        let label = format!("{value:.2}");
        canvas.text(
            LEFT - 8 - text_width(&label),
            y as usize - 5,
            &label,
            AXIS_COLOR,
        );
    }
    let ticks = (max_epoch as usize).saturating_sub(1).clamp(1, 10);
    for k in 0..=ticks {
        let epoch = 1.0 + (max_epoch - 1.0) * k as f64 / ticks as f64;
        let (x, _) = px((epoch, 0.0));
        canvas.line((x, y0), (x, y0 + 5.0), AXIS_COLOR);
        let label = format!("{}", epoch.round() as usize);
        canvas.text(
            x as usize - text_width(&label) / 2,
            y0 as usize + 10,
            &label,
            AXIS_COLOR,
        );
    }
    canvas.line((x0, y0), (x1, y0), AXIS_COLOR);
    canvas.line((x0, y0), (x0, y1), AXIS_COLOR);
    canvas.text(
        WIDTH / 2 - text_width("epoch") / 2,
        HEIGHT - 20,
        "epoch",
        AXIS_COLOR,
    );
    canvas.text(10, 12, "loss", AXIS_COLOR);
    // Legend.
    canvas.line((x1 - 150.0, 18.0), (x1 - 125.0, 18.0), TRAIN_COLOR);
    canvas.text(WIDTH - RIGHT - 118, 13, "train", TRAIN_COLOR);
    canvas.line((x1 - 60.0, 18.0), (x1 - 35.0, 18.0), VAL_COLOR);
    canvas.text(WIDTH - RIGHT - 28, 13, "val", VAL_COLOR);
    // Curves, with a dot per epoch.
    for (points, color) in [(&train, TRAIN_COLOR), (&val, VAL_COLOR)] {
        for pair in points.windows(2) {
            canvas.line(px(pair[0]), px(pair[1]), color);
        }
        for &p in points.iter() {
            let (x, y) = px(p);
            for dy in -2..=2 {
                for dx in -2..=2 {
                    canvas.put(x.round() as i64 + dx, y.round() as i64 + dy, color);
                }
            }
        }
    }
    let tmp = path.with_extension("partial.png");
    write_png_u8(&tmp, WIDTH, HEIGHT, 3, &canvas.pixels)?;
    std::fs::rename(&tmp, path).map_err(|source| TrainError::Io {
        path: path.to_path_buf(),
        source,
    })
}
