//! The PNG of the training curves: training and validation loss (index units) per epoch,
//! drawn with `plotters` into an RGB buffer and written atomically. The labels use DejaVu Sans
//! (its ASCII subset, `fonts/`, embedded in the binary), so drawing needs no system font.

use std::path::Path;
use std::sync::OnceLock;

use omnimvs_data::image_io::write_png_u8;
use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use crate::error::TrainError;
use crate::record::EpochRecord;

/// Width of the picture, pixels.
pub const WIDTH: u32 = 640;
/// Height of the picture, pixels.
pub const HEIGHT: u32 = 400;
const TRAIN_COLOR: RGBColor = RGBColor(31, 119, 180);
const VAL_COLOR: RGBColor = RGBColor(255, 127, 14);
/// The family name the embedded font is registered under: plotters' default, so every text
/// of a chart (ticks, legend) finds it.
const FONT_FAMILY: &str = "sans-serif";
const FONT: &[u8] = include_bytes!("../fonts/DejaVuSans-ascii.ttf");

/// Registers the embedded font with plotters once per process.
fn font() -> Result<(), TrainError> {
    static REGISTERED: OnceLock<bool> = OnceLock::new();
    let ok =
        *REGISTERED.get_or_init(|| register_font(FONT_FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(TrainError::Plot("the embedded font cannot be read".into()))
    }
}

fn plot_error(e: impl std::fmt::Display) -> TrainError {
    TrainError::Plot(e.to_string())
}

/// The curves of `history` as `WIDTH x HEIGHT` RGB pixels (row-major, 3 bytes a pixel): the
/// training loss and, where there is one, the validation loss of every epoch, a dot per
/// epoch. Non-finite losses are left out.
///
/// # Errors
/// [`TrainError::Plot`] when plotters fails to draw.
pub fn draw_curves(history: &[EpochRecord]) -> Result<Vec<u8>, TrainError> {
    font()?;
    let finite = |(e, l): (i32, f64)| l.is_finite().then_some((e, l));
    let train: Vec<(i32, f64)> = history
        .iter()
        .filter_map(|r| finite((r.epoch as i32, r.train_loss)))
        .collect();
    let val: Vec<(i32, f64)> = history
        .iter()
        .filter_map(|r| r.val_loss.and_then(|v| finite((r.epoch as i32, v))))
        .collect();
    let max_epoch = history.iter().map(|r| r.epoch).max().unwrap_or(1).max(2) as i32;
    let max_loss = train
        .iter()
        .chain(&val)
        .map(|p| p.1)
        .fold(0f64, f64::max)
        .max(1e-3)
        * 1.05;
    let mut pixels = vec![255u8; (WIDTH * HEIGHT * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (WIDTH, HEIGHT)).into_drawing_area();
        root.fill(&WHITE).map_err(plot_error)?;
        let mut chart = ChartBuilder::on(&root)
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(1..max_epoch, 0f64..max_loss)
            .map_err(plot_error)?;
        chart
            .configure_mesh()
            .x_labels((max_epoch as usize).min(11))
            .y_labels(6)
            .x_desc("epoch")
            .y_desc("loss (index units)")
            .label_style((FONT_FAMILY, 14))
            .axis_desc_style((FONT_FAMILY, 15))
            .y_label_formatter(&|v| format!("{v:.2}"))
            .light_line_style(WHITE)
            .draw()
            .map_err(plot_error)?;
        for (name, points, color) in [("train", &train, TRAIN_COLOR), ("val", &val, VAL_COLOR)] {
            if points.is_empty() {
                continue;
            }
            chart
                .draw_series(LineSeries::new(
                    points.iter().copied(),
                    color.stroke_width(2),
                ))
                .map_err(plot_error)?
                .label(name)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 22, y)], color.stroke_width(2))
                });
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(plot_error)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FONT_FAMILY, 14))
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK.mix(0.4))
            .draw()
            .map_err(plot_error)?;
        root.present().map_err(plot_error)?;
    }
    Ok(pixels)
}

/// Draws the training and validation loss of `history` ([`draw_curves`]) and writes the PNG
/// to `path` atomically.
///
/// # Errors
/// [`TrainError`] when the curves cannot be drawn or the file cannot be written.
pub fn plot_curves(history: &[EpochRecord], path: &Path) -> Result<(), TrainError> {
    let pixels = draw_curves(history)?;
    write_png_u8(path, WIDTH as usize, HEIGHT as usize, 3, &pixels)?;
    Ok(())
}

/// Reads a run's `metrics.jsonl` (one [`EpochRecord`] a line), e.g. to redraw its curves.
///
/// # Errors
/// [`TrainError`] when the file cannot be read or a line is not a record.
pub fn read_metrics(path: &Path) -> Result<Vec<EpochRecord>, TrainError> {
    let text = std::fs::read_to_string(path).map_err(|source| TrainError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|line| {
            serde_json::from_str(line).map_err(|source| TrainError::Json {
                path: path.to_path_buf(),
                source,
            })
        })
        .collect()
}
