//! The training curves: a PNG of the expected size with both curves and dark text (the
//! embedded font, no system font), written atomically.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use omnimvs_train::EpochRecord;
use omnimvs_train::plot::{HEIGHT, WIDTH, plot_curves, read_metrics};

fn record(epoch: usize, train_loss: f64, val_loss: Option<f64>) -> EpochRecord {
    EpochRecord {
        epoch,
        lr: 1e-3,
        train_loss,
        steps: 10,
        train_seconds: 1.0,
        steps_per_second: 10.0,
        loader_wait_seconds: 0.0,
        val_loss,
        val: None,
        val_reference: None,
        val_seconds: 0.1,
    }
}

fn count(rgb: &image::RgbImage, f: impl Fn(&image::Rgb<u8>) -> bool) -> usize {
    rgb.pixels().filter(|p| f(p)).count()
}

#[test]
fn curves_have_both_series_and_labels() {
    let history: Vec<_> = (1..=8)
        .map(|e| record(e, 10.0 / e as f64, (e % 2 == 0).then(|| 12.0 / e as f64)))
        .chain([record(9, f64::NAN, None)])
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("curves.png");
    plot_curves(&history, &path).unwrap();
    let png = image::open(&path).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (WIDTH, HEIGHT));
    let train = count(&png, |p| p.0 == [31, 119, 180]);
    let val = count(&png, |p| p.0 == [255, 127, 14]);
    assert!(train > 500 && val > 300, "train {train} val {val} pixels");
    // Tick labels and axis titles: dark anti-aliased text left of and below the plot.
    let dark = |x0: u32, x1: u32, y0: u32, y1: u32| {
        (x0..x1)
            .flat_map(|x| (y0..y1).map(move |y| (x, y)))
            .filter(|&(x, y)| png.get_pixel(x, y).0.iter().all(|&c| c < 100))
            .count()
    };
    assert!(dark(0, 70, 0, HEIGHT) > 100, "no y labels");
    assert!(dark(0, WIDTH, HEIGHT - 60, HEIGHT) > 100, "no x labels");
    // Only the PNG: written through a temporary file that is gone.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn metrics_are_read_back_for_a_redraw() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("metrics.jsonl");
    let history = vec![record(1, 3.0, Some(4.0)), record(2, 2.0, None)];
    let text: String = history
        .iter()
        .map(|r| serde_json::to_string(r).unwrap() + "\n")
        .collect();
    omnimvs_core::fs::write_atomic(&path, text.as_bytes()).unwrap();
    assert_eq!(read_metrics(&path).unwrap(), history);
}
