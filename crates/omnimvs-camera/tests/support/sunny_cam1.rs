//! Camera 1 of the published "Sunny" rig (`sunny_single/config.yaml`), written out so that a
//! test needs no data: 768x800, 220-degree FOV. Included with `#[path]` by the camera crate's
//! unit tests and by its property tests; the including module has `OcamModel` in scope.

use super::OcamModel;

/// Camera 1 of the published "Sunny" rig.
pub fn sunny_cam1() -> OcamModel {
    OcamModel {
        poly: vec![
            -1.966560e+02,
            0.0,
            3.053428e-03,
            -9.784996e-06,
            2.278718e-08,
        ],
        inv_poly: vec![
            300.888356, 180.967781, -21.353055, 14.896848, 31.786100, -12.778866, -10.889768,
            20.862822, 6.557302, -10.383775, -2.519069, 2.891402, 1.028544,
        ],
        center_row: 383.0,
        center_col: 399.0,
        c: 1.0,
        d: 0.0,
        e: 0.0,
        width: 800,
        height: 768,
        max_fov_deg: 220.0,
    }
}
