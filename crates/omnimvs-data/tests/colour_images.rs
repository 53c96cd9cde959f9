#![allow(clippy::unwrap_used, clippy::expect_used)]
//! Images read once as gray (what matching reads) and as colour (what panoramas and point
//! clouds show): the colour planes are the file's channels, the gray image is unchanged.

use std::path::Path;

use omnimvs_data::Dataset;
use omnimvs_data::image_io::{read_decoded, read_gray, write_colour_png};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::samples;

const W: u32 = 7;
const H: u32 = 5;

fn rgb(x: u32, y: u32) -> [u8; 3] {
    [(x * 30) as u8, (y * 50) as u8, 200 - (x + y) as u8]
}

fn save(path: &Path, image: impl Into<image::DynamicImage>) {
    image.into().save(path).unwrap();
}

#[test]
fn an_rgb_file_gives_its_channels_and_the_same_gray() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rgb.png");
    save(
        &path,
        image::RgbImage::from_fn(W, H, |x, y| image::Rgb(rgb(x, y))),
    );
    let decoded = read_decoded(&path, true).unwrap();
    assert_eq!(decoded.gray, read_gray(&path).unwrap());
    let colour = decoded.colour.as_ref().expect("an RGB file is colour");
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let want = rgb(x, y);
            for (plane, &v) in colour.planes.iter().zip(&want) {
                assert_eq!(plane.data[i], f32::from(v));
            }
            let mean = want.iter().map(|&v| f32::from(v)).sum::<f32>() / 3.0;
            assert_eq!(decoded.gray.data[i], mean);
        }
    }
    // Not asked: no colour decoded.
    assert_eq!(read_decoded(&path, false).unwrap().colour, None);
    // Written back, the same pixels.
    let out = dir.path().join("out.png");
    write_colour_png(&out, colour).unwrap();
    let back = image::open(&out).unwrap();
    assert_eq!(back.color(), image::ColorType::Rgb8);
    assert_eq!(
        back.into_rgb8(),
        image::RgbImage::from_fn(W, H, |x, y| image::Rgb(rgb(x, y)))
    );
}

#[test]
fn rgba_and_16_bit_colour_files_are_colour_in_0_to_255() {
    let dir = tempfile::tempdir().unwrap();
    let rgba = dir.path().join("rgba.png");
    save(
        &rgba,
        image::RgbaImage::from_fn(W, H, |x, y| {
            let [r, g, b] = rgb(x, y);
            image::Rgba([r, g, b, 10])
        }),
    );
    let wide = dir.path().join("wide.png");
    save(
        &wide,
        image::ImageBuffer::<image::Rgb<u16>, Vec<u16>>::from_fn(W, H, |x, y| {
            image::Rgb(rgb(x, y).map(|v| u16::from(v) * 257))
        }),
    );
    for path in [&rgba, &wide] {
        let decoded = read_decoded(path, true).unwrap();
        assert_eq!(decoded.gray, read_gray(path).unwrap());
        let colour = decoded.colour.expect("colour");
        let i = (2 * W + 3) as usize;
        for k in 0..3 {
            let want = f32::from(rgb(3, 2)[k]);
            assert!((colour.planes[k].data[i] - want).abs() < 1e-3, "{path:?}");
        }
    }
}

#[test]
fn single_channel_files_have_no_colour() {
    let dir = tempfile::tempdir().unwrap();
    let gray = dir.path().join("gray.png");
    save(
        &gray,
        image::GrayImage::from_fn(W, H, |x, y| image::Luma([(x + y) as u8])),
    );
    let gray_alpha = dir.path().join("gray_alpha.png");
    save(
        &gray_alpha,
        image::GrayAlphaImage::from_fn(W, H, |x, _| image::LumaA([x as u8, 255])),
    );
    for path in [&gray, &gray_alpha] {
        let decoded = read_decoded(path, true).unwrap();
        assert_eq!(decoded.colour, None, "{path:?}");
        assert_eq!(decoded.gray, read_gray(path).unwrap());
        // As colour, the gray plane in all three channels.
        assert_eq!(
            decoded.to_colour().planes,
            [decoded.gray.clone(), decoded.gray.clone(), decoded.gray]
        );
    }
}

#[test]
fn the_samples_colour_frames() {
    // sunny_single is RGB: colour, whose channels differ; its gray frame is unchanged.
    let sunny = Dataset::open(&samples().join("sunny_single")).unwrap();
    let (gray, colour) = sunny.read_frame_and_colour(1).unwrap();
    assert_eq!(gray, sunny.read_frame(1).unwrap());
    let colour = colour.expect("sunny_single is colour");
    assert_eq!(colour, sunny.read_colour_frame(1).unwrap().unwrap());
    assert_eq!(colour.len(), sunny.rig.len());
    let [r, _, b] = &colour[0].planes;
    assert_eq!((r.width, r.height), (gray[0].width, gray[0].height));
    assert!(r.data.iter().zip(&b.data).any(|(x, y)| x != y));
    // itbt_sample is gray: no colour.
    let itbt = Dataset::open(&samples().join("itbt_sample")).unwrap();
    assert_eq!(itbt.read_colour_frame(1).unwrap(), None);
    let (gray, colour) = itbt.read_frame_and_colour(1).unwrap();
    assert_eq!(colour, None);
    assert_eq!(gray, itbt.read_frame(1).unwrap());
}
