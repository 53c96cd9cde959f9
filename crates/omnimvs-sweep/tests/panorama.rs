#![allow(clippy::unwrap_used)]
//! The colour panorama is the gray panorama of each channel: same cameras, same weights.

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;

use omnimvs_core::{ColourPlanes, GrayImage};
use omnimvs_sweep::{
    EquirectGrid, InvDepthSource, compose_colour_panorama, compose_panorama,
    warp_camera_to_panorama,
};

/// A `w x h` plane whose value depends on the pixel, the camera and the channel.
fn plane(w: usize, h: usize, camera: usize, channel: usize) -> GrayImage {
    let data = (0..w * h)
        .map(|i| ((i % w) * (channel + 1) + (i / w) * 3 + camera * 40) as f32 % 256.0)
        .collect();
    GrayImage {
        width: w,
        height: h,
        data,
    }
}

#[test]
fn each_colour_channel_is_composed_as_a_gray_panorama() {
    let rig = omnimvs_camera::read_config_rig(&samples::sample_config("itbt_sample")).unwrap();
    let grid = EquirectGrid::new(24, 96, 60.0).unwrap();
    let colour: Vec<ColourPlanes> = rig
        .cameras
        .iter()
        .enumerate()
        .map(|(c, cam)| {
            let (w, h) = (cam.model.width() as usize, cam.model.height() as usize);
            ColourPlanes {
                planes: std::array::from_fn(|k| plane(w, h, c, k)),
            }
        })
        .collect();
    let inv_depth: Vec<f32> = (0..grid.len())
        .map(|i| 0.2 + (i % 7) as f32 * 0.1)
        .collect();
    let source = InvDepthSource::Map(&inv_depth);
    let pano = compose_colour_panorama(&rig, &grid, &colour, None, source).unwrap();
    for k in 0..3 {
        let gray: Vec<GrayImage> = colour.iter().map(|c| c.planes[k].clone()).collect();
        let expected = compose_panorama(&rig, &grid, &gray, None, source).unwrap();
        assert_eq!(pano.image.planes[k], expected.image, "channel {k}");
        assert_eq!(pano.count, expected.count);
    }
    // The channels differ where the images' channels do.
    let [r, g, _] = &pano.image.planes;
    assert!(r.data.iter().zip(&g.data).any(|(a, b)| a != b));

    // A gray image as colour gives the gray panorama in every channel, to the bit.
    let gray: Vec<GrayImage> = colour.iter().map(|c| c.planes[1].clone()).collect();
    let as_colour: Vec<ColourPlanes> = gray.iter().map(ColourPlanes::from_gray).collect();
    let expected = compose_panorama(&rig, &grid, &gray, None, source).unwrap();
    let pano = compose_colour_panorama(&rig, &grid, &as_colour, None, source).unwrap();
    for channel in &pano.image.planes {
        assert_eq!(channel, &expected.image);
    }
}

#[test]
fn the_gray_panorama_is_the_mean_of_the_cameras_views() {
    let rig = omnimvs_camera::read_config_rig(&samples::sample_config("itbt_sample")).unwrap();
    let grid = EquirectGrid::new(16, 64, 80.0).unwrap();
    let images: Vec<GrayImage> = rig
        .cameras
        .iter()
        .enumerate()
        .map(|(c, cam)| {
            plane(
                cam.model.width() as usize,
                cam.model.height() as usize,
                c,
                0,
            )
        })
        .collect();
    let source = InvDepthSource::Constant(0.5);
    let pano = compose_panorama(&rig, &grid, &images, None, source).unwrap();
    let mut sum = vec![0f32; grid.len()];
    let mut count = vec![0u8; grid.len()];
    for (camera, image) in rig.cameras.iter().zip(&images) {
        let (vals, seen) = warp_camera_to_panorama(camera, &grid, image, None, source).unwrap();
        for k in 0..grid.len() {
            if seen[k] {
                sum[k] += vals[k];
                count[k] += 1;
            }
        }
    }
    assert_eq!(pano.count, count);
    assert!(count.iter().any(|&c| c > 1));
    for k in 0..grid.len() {
        let expected = if count[k] > 0 {
            sum[k] / f32::from(count[k])
        } else {
            0.0
        };
        assert_eq!(pano.image.data[k], expected);
    }
}

#[test]
fn colour_images_of_the_wrong_size_are_named() {
    let rig = omnimvs_camera::read_config_rig(&samples::sample_config("itbt_sample")).unwrap();
    let grid = EquirectGrid::new(8, 32, 80.0).unwrap();
    let colour = vec![ColourPlanes::from_gray(&GrayImage::zeros(10, 10)); rig.len()];
    let err = compose_colour_panorama(&rig, &grid, &colour, None, InvDepthSource::Constant(0.0))
        .unwrap_err()
        .to_string();
    assert!(err.contains("image size"), "{err}");
}
