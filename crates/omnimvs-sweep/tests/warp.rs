#![allow(clippy::unwrap_used)]
//! Warping through a real rig's lookup table: a ramp image proves the
//! sampling position and the align-corners convention, a constant image the
//! zero padding outside.

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;

use omnimvs_sweep::{
    EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet, warp_camera_onto_spheres,
};

#[test]
fn ramp_images_sample_at_the_table_positions() {
    let cfg = samples::sample_config("itbt_sample");
    let rig = omnimvs_camera::read_config_rig(&cfg).unwrap();
    let grid = EquirectGrid::new(16, 64, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(8, 0.5).unwrap();
    let lut = LookupTable::build(&rig, &grid, &hyps, SphereSet::EveryOther).unwrap();
    // Two channels: value = column, value = row (a linear ramp is reproduced
    // exactly by bilinear interpolation), at half the image resolution as a
    // feature map would be.
    let (w, h) = (800usize, 766usize);
    let mut src = vec![0f32; 2 * w * h];
    for r in 0..h {
        for c in 0..w {
            src[r * w + c] = c as f32;
            src[w * h + r * w + c] = r as f32;
        }
    }
    for cam in 0..rig.len() {
        let mut out = vec![0f32; lut.num_spheres() * 2 * grid.len()];
        warp_camera_onto_spheres(&lut, cam, &src, 2, w, h, &mut out).unwrap();
        let (mut inside, mut outside) = (0, 0);
        for s in 0..lut.num_spheres() {
            for i in 0..grid.len() {
                let (col, row) = lut.pixel(cam, s, i / grid.width, i % grid.width);
                // Scale the full-resolution position to the half-size map.
                let (fc, fr) = (
                    col / 1599.0 * (w as f64 - 1.0),
                    row / 1531.0 * (h as f64 - 1.0),
                );
                let got_c = out[(s * 2) * grid.len() + i];
                let got_r = out[(s * 2 + 1) * grid.len() + i];
                if fc >= 0.0 && fr >= 0.0 && fc <= (w - 1) as f64 && fr <= (h - 1) as f64 {
                    assert!(
                        (f64::from(got_c) - fc).abs() < 1e-2,
                        "cam {cam}: col {got_c} vs {fc}"
                    );
                    assert!(
                        (f64::from(got_r) - fr).abs() < 1e-2,
                        "cam {cam}: row {got_r} vs {fr}"
                    );
                    inside += 1;
                } else if fc < -1.0 || fr < -1.0 || fc > w as f64 || fr > h as f64 {
                    assert_eq!(
                        (got_c, got_r),
                        (0.0, 0.0),
                        "cam {cam}: outside must sample zero"
                    );
                    outside += 1;
                }
            }
        }
        assert!(
            inside > 1000 && outside > 1000,
            "cam {cam}: inside {inside}, outside {outside}"
        );
    }
}

#[test]
fn warp_rejects_wrong_sizes() {
    let cfg = samples::sample_config("sunny_single");
    let rig = omnimvs_camera::read_config_rig(&cfg).unwrap();
    let grid = EquirectGrid::new(4, 8, 45.0).unwrap();
    let hyps = InvDepthHypotheses::new(4, 1.0).unwrap();
    let lut = LookupTable::build(&rig, &grid, &hyps, SphereSet::All).unwrap();
    let mut out = vec![0f32; 4 * 32];
    let e = warp_camera_onto_spheres(&lut, 0, &[0.0; 10], 1, 4, 4, &mut out).unwrap_err();
    assert!(e.to_string().contains("source map length"), "{e}");
    let e = warp_camera_onto_spheres(&lut, 0, &[0.0; 16], 1, 4, 4, &mut out[..5]).unwrap_err();
    assert!(e.to_string().contains("warp output length"), "{e}");
    assert!(warp_camera_onto_spheres(&lut, 9, &[0.0; 16], 1, 4, 4, &mut out).is_err());
}
