#![allow(clippy::unwrap_used, clippy::expect_used)]
//! The closed-form camera models against golden values computed from the published formulas
//! (double sphere, EUCM, Mei's unified model with radial-tangential distortion, OpenCV's
//! fisheye and pinhole models) by a script that shares no code with the crate:
//! `scripts/camera_golden/make_camera_golden.py` wrote `tests/golden/camera_models.json`;
//! rerun it from the repository root to regenerate the file.
//!
//! Each golden camera is also round-tripped over its whole domain: rays at every angle up
//! to half its field of view and every azimuth, and the pixels of its full image.

use std::collections::BTreeMap;

use omnimvs_camera::nalgebra::Vector3;
use omnimvs_camera::{
    DoubleSphere, ExtendedUnified, KannalaBrandt4, Lens, PinholeRadtan, Pixel, Unified,
};
use serde::Deserialize;

/// Largest pixel error of a projection against its golden value.
const PROJECT_TOLERANCE_PX: f64 = 1e-9;
/// Largest angle between an unprojected ray and its golden value, radians.
const UNPROJECT_TOLERANCE_RAD: f64 = 1e-9;
/// Largest pixel error of a round trip ray -> pixel -> ray -> pixel or pixel -> ray -> pixel.
const ROUND_TRIP_TOLERANCE_PX: f64 = 1e-6;

/// Distance from the principal point beyond which a pixel's round-trip error is relative.
const FAR_PX: f64 = 1e4;
/// Largest round-trip error of a pixel beyond [`FAR_PX`], relative to its distance from the
/// principal point.
const FAR_RELATIVE_TOLERANCE: f64 = 1e-8;

#[derive(Deserialize)]
struct Golden {
    cameras: Vec<GoldenCamera>,
}

#[derive(Deserialize)]
struct GoldenCamera {
    name: String,
    model: String,
    intrinsics: Vec<f64>,
    #[serde(default)]
    distortion: Option<Vec<f64>>,
    /// The field of view a KB4 lens is given, degrees (the model's default otherwise).
    #[serde(default)]
    max_fov: Option<f64>,
    /// `[height, width]`, pixels.
    image_size: [u32; 2],
    /// The model's full field of view, degrees.
    max_fov_deg: f64,
    project: Vec<ProjectCase>,
    unproject: Vec<UnprojectCase>,
}

#[derive(Deserialize)]
struct ProjectCase {
    point: [f64; 3],
    /// `[col, row]`, or `None` outside the domain.
    pixel: Option<[f64; 2]>,
}

#[derive(Deserialize)]
struct UnprojectCase {
    /// `[col, row]`.
    pixel: [f64; 2],
    /// The unit ray, or `None` where the pixel does not unproject.
    ray: Option<[f64; 3]>,
    /// The published closed form's ray of a pixel that does not unproject because that ray
    /// lies outside the published projection domain.
    #[serde(default)]
    formula_ray: Option<[f64; 3]>,
}

fn golden() -> Golden {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/golden/camera_models.json"
    );
    let text = std::fs::read_to_string(path).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The golden camera's lens, built through the model's public constructor.
fn lens(cam: &GoldenCamera) -> Lens {
    let i = &cam.intrinsics;
    let d = cam.distortion.clone().unwrap_or_default();
    let lens = match cam.model.as_str() {
        "ds" => DoubleSphere::new(i[0], i[1], i[2], i[3], i[4], i[5]).map(Lens::DoubleSphere),
        "eucm" => {
            ExtendedUnified::new(i[0], i[1], i[2], i[3], i[4], i[5]).map(Lens::ExtendedUnified)
        }
        "ucm" if d.is_empty() => Unified::new(i[0], i[1], i[2], i[3], i[4]).map(Lens::Unified),
        "ucm" => Unified::with_radtan(i[0], i[1], i[2], i[3], i[4], [d[0], d[1], d[2], d[3]])
            .map(Lens::Unified),
        "kb4" => KannalaBrandt4::new(i[0], i[1], i[2], i[3], d[0], d[1], d[2], d[3])
            .and_then(|m| match cam.max_fov {
                Some(fov) => m.with_max_fov_deg(fov),
                None => Ok(m),
            })
            .map(Lens::KannalaBrandt4),
        "pinhole-radtan" => PinholeRadtan::new(i[0], i[1], i[2], i[3], d[0], d[1], d[2], d[3])
            .map(Lens::PinholeRadtan),
        other => panic!("{}: unknown model {other}", cam.name),
    };
    lens.unwrap_or_else(|e| panic!("{}: {e}", cam.name))
}

fn vector([x, y, z]: [f64; 3]) -> Vector3<f64> {
    Vector3::new(x, y, z)
}

fn distance_px(a: Pixel, b: Pixel) -> f64 {
    (a.col - b.col).hypot(a.row - b.row)
}

/// The angle between two rays, radians (exact for small angles).
fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// 1, or the pixel's distance from the principal point over 1000 px when larger: errors are
/// measured relative to it (near the open edge of a unified model's domain pixels run to
/// 1e7 px, where float64 resolves 1e-9 px no more).
fn far_scale(lens: &Lens, px: Pixel) -> f64 {
    let f = lens.focal();
    1f64.max(distance_px(px, Pixel::new(f.cx(), f.cy())) / 1000.0)
}

/// Keeps the worst error per model and prints them.
#[derive(Default)]
struct Worst(BTreeMap<String, f64>);

impl Worst {
    fn add(&mut self, model: &str, error: f64) {
        let worst = self.0.entry(model.to_owned()).or_insert(0.0);
        *worst = worst.max(error);
    }

    fn print(&self, what: &str) {
        for (model, error) in &self.0 {
            println!("{what} {model}: {error:.3e}");
        }
    }
}

#[test]
fn projection_matches_the_published_formulas() {
    let mut worst = Worst::default();
    for cam in golden().cameras {
        let lens = lens(&cam);
        for case in &cam.project {
            let got = lens.project(&vector(case.point));
            match (case.pixel, got) {
                (None, None) => {}
                (Some([col, row]), Some(px)) => {
                    let error = distance_px(px, Pixel::new(col, row)) / far_scale(&lens, px);
                    worst.add(&cam.model, error);
                    assert!(
                        error < PROJECT_TOLERANCE_PX,
                        "{}: {:?} -> {px:?}, want [{col}, {row}] ({error:e} px)",
                        cam.name,
                        case.point
                    );
                }
                (want, got) => panic!("{}: {:?} -> {got:?}, want {want:?}", cam.name, case.point),
            }
        }
    }
    worst.print("project, px");
}

#[test]
fn unprojection_matches_the_published_formulas() {
    let mut worst = Worst::default();
    for cam in golden().cameras {
        let lens = lens(&cam);
        for case in &cam.unproject {
            let [col, row] = case.pixel;
            let got = lens.unproject(Pixel::new(col, row));
            match (case.ray, got) {
                (None, None) => {}
                (Some(want), Some(ray)) => {
                    let error = angle_between(&ray, &vector(want));
                    worst.add(&cam.model, error);
                    assert!((ray.norm() - 1.0).abs() < 1e-12, "{}: {ray:?}", cam.name);
                    assert!(
                        error < UNPROJECT_TOLERANCE_RAD,
                        "{}: [{col}, {row}] -> {ray:?}, want {want:?} ({error:e} rad)",
                        cam.name
                    );
                }
                (want, got) => panic!("{}: [{col}, {row}] -> {got:?}, want {want:?}", cam.name),
            }
            // Where the closed form gives a ray the model does not project, the pixel does
            // not unproject: the two directions agree.
            if let Some(ray) = case.formula_ray {
                assert!(
                    lens.project(&vector(ray)).is_none(),
                    "{}: {ray:?}",
                    cam.name
                );
            }
        }
    }
    worst.print("unproject, rad");
}

#[test]
fn fields_of_view_match_the_published_domains() {
    for cam in golden().cameras {
        let fov = lens(&cam).max_fov_deg();
        assert!(
            (fov - cam.max_fov_deg).abs() < 1e-9,
            "{}: {fov} degrees, want {}",
            cam.name,
            cam.max_fov_deg
        );
    }
}

/// The widest angle from the optical axis the round trip covers, radians: half the field of
/// view, 1e-7 rad inside it where the domain is open (the double sphere, EUCM and unified
/// models exclude their boundary cone; where the image radius peaks on it, the pixel of a
/// ray closer to it can exceed the largest radius that unprojects by a rounding error),
/// and for a pinhole at most 80 degrees (towards 90 degrees its image grows without bound).
/// With tangential distortion, 2 % inside: the field of view ignores the tangential terms,
/// whose Jacobian can end the domain a little earlier at some azimuths.
fn round_trip_half_angle(cam: &GoldenCamera, lens: &Lens) -> f64 {
    let half = lens.max_fov_deg().to_radians() / 2.0;
    let half = if lens.is_radial() { half } else { 0.98 * half };
    match cam.model.as_str() {
        "kb4" => half,
        "pinhole-radtan" => (half - 1e-6).min(80f64.to_radians()),
        _ => half - 1e-7,
    }
}

#[test]
fn golden_cameras_round_trip_over_their_whole_domain() {
    let mut worst_rays = Worst::default();
    let mut worst_pixels = Worst::default();
    let mut worst_far = Worst::default();
    for cam in golden().cameras {
        let lens = lens(&cam);
        let half = round_trip_half_angle(&cam, &lens);
        // Rays: 400 angles up to the edge, 72 azimuths.
        let steps = 400;
        for i in 0..=steps {
            let theta = half * f64::from(i) / f64::from(steps);
            for j in 0..72 {
                let azimuth = std::f64::consts::TAU * f64::from(j) / 72.0 + 0.01;
                let ray = Vector3::new(
                    theta.sin() * azimuth.cos(),
                    theta.sin() * azimuth.sin(),
                    theta.cos(),
                );
                let px = lens
                    .project(&ray)
                    .unwrap_or_else(|| panic!("{}: {ray:?} does not project", cam.name));
                let back = lens.unproject(px).unwrap_or_else(|| {
                    panic!("{}: {ray:?} -> {px:?} does not unproject", cam.name)
                });
                let px2 = lens.project(&back).unwrap();
                // Towards the open edge of a domain whose image is unbounded (all but KB4
                // and the folding models) the pixels run to 1e10 px: there the error is
                // relative, what float64 resolves of the vanishing denominator.
                let dist = distance_px(px, Pixel::new(lens.focal().cx(), lens.focal().cy()));
                let error = distance_px(px, px2);
                let ok = if dist < FAR_PX {
                    worst_rays.add(&cam.model, error);
                    error < ROUND_TRIP_TOLERANCE_PX
                } else {
                    worst_far.add(&cam.model, error / dist);
                    error < FAR_RELATIVE_TOLERANCE * dist
                };
                assert!(ok, "{}: {ray:?} -> {px:?} -> {back:?} -> {px2:?}", cam.name);
            }
        }
        // Pixels: about 128 x 128 over the full image.
        let [height, width] = cam.image_size;
        let step = (height.max(width) / 128).max(1) as usize;
        let mut unprojected = 0;
        for row in (0..height).step_by(step) {
            for col in (0..width).step_by(step) {
                let px = Pixel::new(f64::from(col) + 0.25, f64::from(row) + 0.5);
                let Some(ray) = lens.unproject(px) else {
                    continue;
                };
                unprojected += 1;
                let back = lens
                    .project(&ray)
                    .unwrap_or_else(|| panic!("{}: {px:?} -> {ray:?}", cam.name));
                let error = distance_px(px, back);
                worst_pixels.add(&cam.model, error);
                assert!(
                    error < ROUND_TRIP_TOLERANCE_PX,
                    "{}: {px:?} -> {ray:?} -> {back:?}",
                    cam.name
                );
            }
        }
        assert!(unprojected > 1000, "{}: {unprojected} pixels", cam.name);
    }
    worst_rays.print("ray round trip, px");
    worst_far.print("ray round trip beyond 1e4 px, relative");
    worst_pixels.print("pixel round trip, px");
}
