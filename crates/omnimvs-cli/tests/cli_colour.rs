#![allow(clippy::unwrap_used, clippy::expect_used)]
//! Colour images keep their colour in `pano` and in `infer --ply`'s point clouds, while the
//! methods match on gray; gray images give the same gray files as the gray path always did.

mod support;

use std::path::{Path, PathBuf};

use omnimvs_data::Dataset;
use omnimvs_data::image_io::write_gray_png;
use omnimvs_sweep::{EquirectGrid, InvDepthSource, compose_panorama};
use support::{run_ok, synth_dataset};

/// A copy of the dataset `from` in `to` whose images are saved as RGB, each gray pixel `v`
/// becoming `colour(v)`.
fn recoloured(from: &Path, to: &Path, colour: fn(u8) -> [u8; 3]) -> PathBuf {
    copy_dir(from, to);
    let ds = Dataset::open(to).unwrap();
    for frame in ds.frames_found() {
        for camera in 0..ds.rig.len() {
            let path = ds.image_path(camera, frame).unwrap();
            let gray = image::open(&path).unwrap().into_luma8();
            let rgb = image::RgbImage::from_fn(gray.width(), gray.height(), |x, y| {
                image::Rgb(colour(gray.get_pixel(x, y)[0]))
            });
            rgb.save(&path).unwrap();
        }
    }
    to.to_path_buf()
}

/// Red above and blue below the gray `v`, green at it: the channels' mean is `v`.
fn tinted(v: u8) -> [u8; 3] {
    let d = v.min(255 - v).min(40);
    [v + d, v, v - d]
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

/// `omnimvs pano` of frame 1 at 2 m on a 40x80 grid into `out`.
fn pano(data: &Path, out: &Path, cache: &Path) -> String {
    run_ok(
        &[
            "pano",
            data.to_str().unwrap(),
            "--frame",
            "1",
            "--depth",
            "2",
            "--size",
            "40x80",
            "--out",
            out.to_str().unwrap(),
        ],
        cache,
    )
}

/// `omnimvs infer --weights tiny --ply` of frame 1 into `out`; returns the PLY's points
/// (x, y, z, r, g, b).
fn infer_ply(data: &Path, out: &Path, cache: &Path) -> (Vec<u8>, Vec<[u8; 3]>) {
    run_ok(
        &[
            "infer",
            data.to_str().unwrap(),
            "--weights",
            "tiny",
            "--frames",
            "1",
            "--ply",
            "--out",
            out.to_str().unwrap(),
        ],
        cache,
    );
    let bytes = std::fs::read(out.join("00001.ply")).unwrap();
    let end = b"end_header\n";
    let start = bytes.windows(end.len()).position(|w| w == end).unwrap() + end.len();
    let colours = bytes[start..]
        .chunks_exact(15)
        .map(|p| [p[12], p[13], p[14]])
        .collect();
    (bytes, colours)
}

#[test]
fn colour_images_give_colour_panoramas_and_point_clouds() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let gray = synth_dataset(dir.path(), "gray", "1", "96x100", 5);
    // Channels that differ from one another around the gray (their mean, what the methods
    // match on, is the gray image), and the gray images saved as RGB (R = G = B).
    let colour = recoloured(&gray, &dir.path().join("colour"), tinted);
    let rgb_gray = recoloured(&gray, &dir.path().join("rgb_gray"), |v| [v, v, v]);

    // Gray images: a gray PNG, the bytes of the gray composition.
    let gray_png = dir.path().join("gray.png");
    let said = pano(&gray, &gray_png, &cache);
    assert!(said.contains("(gray,"), "{said}");
    let ds = Dataset::open(&gray).unwrap();
    let grid = EquirectGrid::new(40, 80, 90.0).unwrap();
    let expected = compose_panorama(
        &ds.rig,
        &grid,
        &ds.read_frame(1).unwrap(),
        Some(&ds.masks().unwrap()),
        InvDepthSource::Constant(0.5),
    )
    .unwrap();
    let expected_png = dir.path().join("expected.png");
    write_gray_png(&expected_png, &expected.image).unwrap();
    assert_eq!(
        std::fs::read(&gray_png).unwrap(),
        std::fs::read(&expected_png).unwrap()
    );
    let gray_pixels = image::open(&gray_png).unwrap();
    assert_eq!(gray_pixels.color(), image::ColorType::L8);
    let gray_pixels = gray_pixels.into_luma8();

    // Colour images: an RGB PNG whose channels differ where the images' do, each composed
    // with the gray panorama's weights and coverage.
    let colour_png = dir.path().join("colour.png");
    let said = pano(&colour, &colour_png, &cache);
    assert!(said.contains("(colour,"), "{said}");
    let rgb = image::open(&colour_png).unwrap();
    assert_eq!(rgb.color(), image::ColorType::Rgb8);
    assert_eq!((rgb.width(), rgb.height()), (80, 40));
    let rgb = rgb.into_rgb8();
    let seen: Vec<bool> = expected.count.iter().map(|&c| c > 0).collect();
    let mut differing = 0;
    for ((i, p), g) in rgb.pixels().enumerate().zip(gray_pixels.pixels()) {
        if !seen[i] {
            assert_eq!(p.0, [0, 0, 0]);
            continue;
        }
        // Green is the gray image in every camera, so the panorama's green is the gray
        // panorama; red is above it and blue below it, in the mean too.
        assert_eq!(p[1], g[0]);
        assert!(p[0] >= p[1] && p[1] >= p[2], "{p:?}");
        if p[0] != p[2] {
            differing += 1;
        }
    }
    assert!(differing > seen.len() / 2, "{differing} pixels of colour");

    // The gray images saved as RGB: every channel is the gray panorama.
    let rgb_gray_png = dir.path().join("rgb_gray.png");
    pano(&rgb_gray, &rgb_gray_png, &cache);
    let rgb_gray_pixels = image::open(&rgb_gray_png).unwrap().into_rgb8();
    for (c, g) in rgb_gray_pixels.pixels().zip(gray_pixels.pixels()) {
        assert_eq!(c.0, [g[0]; 3]);
    }

    // Point clouds: gray points from gray images, the same file from the gray images saved
    // as RGB (the methods match on the same gray), coloured points from colour images.
    let (gray_ply, gray_colours) = infer_ply(&gray, &dir.path().join("net_gray"), &cache);
    assert!(!gray_colours.is_empty());
    assert!(gray_colours.iter().all(|c| c[0] == c[1] && c[1] == c[2]));
    let (rgb_gray_ply, _) = infer_ply(&rgb_gray, &dir.path().join("net_rgb_gray"), &cache);
    assert_eq!(gray_ply, rgb_gray_ply);
    let (colour_ply, colours) = infer_ply(&colour, &dir.path().join("net_colour"), &cache);
    // The same points (the methods matched on the same gray), green the gray points' gray,
    // red above and blue below it.
    assert_eq!(colour_ply.len(), gray_ply.len());
    assert_eq!(colours.len(), gray_colours.len());
    for (c, g) in colours.iter().zip(&gray_colours) {
        assert_eq!(c[1], g[1]);
        assert!(c[0] >= c[1] && c[1] >= c[2], "{c:?}");
    }
    let coloured = colours.iter().filter(|c| c[0] != c[2]).count();
    assert!(
        coloured > colours.len() / 2,
        "{coloured} of {} points",
        colours.len()
    );
}
