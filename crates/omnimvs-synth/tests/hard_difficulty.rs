//! The `hard` difficulty: deterministic for any thread count, exact ground
//! truth, camera effects on the images only, recorded in `synth.json` and
//! checked on resume; `standard` datasets keep their bytes.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)] // helpers of tests

use std::collections::BTreeMap;
use std::path::Path;

use omnimvs_sweep::EquirectGrid;
use omnimvs_synth::camera_effects::apply_all;
use omnimvs_synth::dataset::{GT_HEIGHT, GT_PHI_DEG, GT_WIDTH, render_scene};
use omnimvs_synth::rig::{preset_rig, rig_radius_m};
use omnimvs_synth::texture::TextureSpec;
use omnimvs_synth::{
    DatasetWriter, Difficulty, GenParams, ObjectSpec, Placement, SceneKind, SceneSpec, ShapeSpec,
    SynthError, SynthOptions, Tracer, generate, render_inverse_depth,
};

#[path = "support/datasets.rs"]
mod datasets;
use datasets::{files, small_rig};

fn writer(
    out: &Path,
    kind: SceneKind,
    difficulty: Difficulty,
) -> Result<DatasetWriter, SynthError> {
    let options = SynthOptions {
        difficulty,
        ..SynthOptions::new(kind, 5)
    };
    DatasetWriter::create_with(
        out,
        &small_rig(),
        &options,
        &"1..3".parse::<omnimvs_data::FrameRange>().unwrap(),
    )
}

/// FNV-1a over the sorted names and bytes of `files`.
fn fnv(files: &BTreeMap<String, Vec<u8>>) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for (k, v) in files {
        for b in k.bytes().chain(v.iter().copied()) {
            h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    h
}

#[test]
fn hard_datasets_are_byte_identical_with_one_or_several_threads() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    for (dir, threads) in [(a.path(), 1), (b.path(), 3)] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            for kind in [SceneKind::Things, SceneKind::House] {
                let out = dir.join(kind.name());
                writer(&out, kind, Difficulty::Hard)
                    .unwrap()
                    .run(&[1, 2], |_| {})
                    .unwrap();
            }
        });
    }
    let (fa, fb) = (files(a.path()), files(b.path()));
    assert_eq!(fa.len(), 2 * (2 + 4 + 2 * 6)); // config, synth.json, masks; frames
    assert_eq!(fa, fb);
    let settings = String::from_utf8(fa["things/synth.json"].clone()).unwrap();
    assert!(settings.contains("\"difficulty\": \"hard\""), "{settings}");
    let scene = String::from_utf8(fa["house/scene/00001.json"].clone()).unwrap();
    assert!(scene.contains("camera_effects") && scene.contains("range_m"));
}

/// A scene file with the generator's version left out of its `generator` field
/// (`"omnimvs-synth X.Y.Z"` -> `"omnimvs-synth"`): a release changes the version, not the scene.
fn without_version(scene: &[u8]) -> Vec<u8> {
    let text = String::from_utf8(scene.to_vec()).unwrap();
    let key = "\"generator\": \"omnimvs-synth";
    let start = text.find(key).expect("a scene names its generator") + key.len();
    let end = start + text[start..].find('"').unwrap();
    format!("{}{}", &text[..start], &text[end..]).into_bytes()
}

/// The bytes of a `standard` dataset (images, ground truth, scenes) are
/// those of the generator before `--difficulty` existed: the golden hash
/// was computed with commit 40da848 by this same test body, in the
/// workspace's build (num-traits with `libm`, as in the `omnimvs` binary;
/// the crate now asks for it itself, see its Cargo.toml), and again with
/// the generator's version left out of the scenes when version 0.2.0 was
/// released (every other byte checked unchanged against the 0.1.0 generator's).
#[test]
fn standard_datasets_keep_their_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let mut all = BTreeMap::new();
    for kind in [SceneKind::Things, SceneKind::House] {
        let out = dir.path().join(kind.name());
        writer(&out, kind, Difficulty::Standard)
            .unwrap()
            .run(&[1, 2], |_| {})
            .unwrap();
        for (k, v) in files(&out) {
            if k == "synth.json" || k == "config.yaml" || k.starts_with("mask") {
                continue;
            }
            // The ground truth by its values (little-endian f32), not its TIFF's bytes: the
            // file's layout (pages, compression) is a format choice, the values are the
            // generator's.
            let v = if k.starts_with(omnimvs_synth::dataset::GT_DIR) {
                omnimvs_data::gt::read_inv_depth(&out.join(&k))
                    .unwrap()
                    .data
                    .iter()
                    .flat_map(|x| x.to_le_bytes())
                    .collect()
            } else if k.starts_with(omnimvs_synth::dataset::SCENE_DIR) {
                without_version(&v)
            } else {
                v
            };
            all.insert(format!("{}/{k}", kind.name()), v);
        }
        // config.yaml is the serialiser's text (its float notation is serde-saphyr's since
        // the writer serialises a struct): what matters is the rig it reads back as.
        // The cameras name their masks, which hold what the field of view gives.
        let mut written = omnimvs_camera::read_config_rig(&out.join("config.yaml")).unwrap();
        for (i, camera) in written.cameras.iter_mut().enumerate() {
            let name = camera.invalid_mask.take();
            assert_eq!(name.as_deref(), Some(format!("mask{}.png", i + 1).as_str()));
            let with_file = omnimvs_camera::ValidityMask::for_camera(
                &omnimvs_camera::Camera {
                    invalid_mask: name,
                    ..camera.clone()
                },
                &out,
            )
            .unwrap();
            assert_eq!(
                with_file,
                omnimvs_camera::ValidityMask::from_fov(&camera.model)
            );
        }
        assert_eq!(written, small_rig().rig);
    }
    let scene = String::from_utf8(all["things/scene/00001.json"].clone()).unwrap();
    assert!(!scene.contains("camera_effects") && !scene.contains("extra_lights"));
    assert_eq!(fnv(&all), GOLDEN_STANDARD_FNV, "{:#x}", fnv(&all));
}

/// Images, scenes and the ground truth's values (not its TIFF's bytes), without config.yaml
/// and the masks. Computed by this test body with the one-page ground-truth TIFF (commit
/// dc8a205's writer) and with the two-page one of the released datasets: the same. (The
/// golden before, 0xa5b4_f2eb_3812_4569, hashed the TIFF's bytes; the one before that,
/// 0x8fd0_06b4_4476_f170, config.yaml too.)
const GOLDEN_STANDARD_FNV: u64 = 0xc713_2e75_cc3f_8b1b;

#[test]
fn camera_effects_change_the_images_but_not_the_ground_truth() {
    let dir = tempfile::tempdir().unwrap();
    let rig = small_rig().rig;
    let grid = EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG).unwrap();
    for kind in [SceneKind::Things, SceneKind::House] {
        let w = writer(&dir.path().join(kind.name()), kind, Difficulty::Hard).unwrap();
        let frame = w.render_frame(2).unwrap();
        assert_eq!(frame.scene.camera_effects.len(), rig.cameras.len());
        // The same scene without the effects: the ideal images.
        let (mut ideal, inv_depth) = render_scene(&frame.scene, &[], &rig, 1, &grid).unwrap();
        assert_eq!(inv_depth, frame.inv_depth, "{kind:?}: ground truth changed");
        let mut differing = 0usize;
        let mut total = 0usize;
        for (a, b) in ideal.iter().zip(&frame.images) {
            differing += a.iter().zip(b).filter(|(x, y)| x != y).count();
            total += a.len();
        }
        assert!(
            differing * 4 > total,
            "{kind:?}: only {differing} of {total} pixels changed"
        );
        // scene.json is enough to make the dataset's images again.
        apply_all(&frame.scene.camera_effects, &rig.cameras, &mut ideal).unwrap();
        assert_eq!(ideal, frame.images);
    }
}

#[test]
fn hard_scenes_have_thin_and_concave_shapes_and_uneven_darker_light() {
    let source = preset_rig().unwrap();
    let mut params = GenParams::new(source.min_depth_m, rig_radius_m(&source.rig));
    params.difficulty = Difficulty::Hard;
    let (mut thin_or_holed, mut objects, mut lights) = (0, 0, 0);
    for frame in 1..=8 {
        let scene = generate(SceneKind::Things, 11, frame, &params).unwrap();
        assert!(scene.light.ambient <= 0.2, "{:?}", scene.light);
        lights += scene.extra_lights.len();
        for o in &scene.objects {
            objects += 1;
            let s = o.placement.scale;
            let (lo, hi) = (
                s.iter().copied().fold(f64::INFINITY, f64::min),
                s.iter().copied().fold(0.0, f64::max),
            );
            if lo < 0.1 * hi
                || matches!(
                    o.shape,
                    ShapeSpec::Grid { .. } | ShapeSpec::Lattice { .. } | ShapeSpec::Tube { .. }
                )
                || matches!(o.shape, ShapeSpec::Torus { minor, .. } if minor < 0.16)
            {
                thin_or_holed += 1;
            }
        }
        let house = generate(SceneKind::House, 11, frame, &params).unwrap();
        assert!(!house.extra_lights.is_empty() && house.light.range_m.is_some());
    }
    let share = f64::from(thin_or_holed) / f64::from(objects);
    assert!((0.45..0.8).contains(&share), "thin or holed {share}");
    assert!(lights >= 4, "{lights} extra lights in 8 scenes");
    // Standard scenes have none of it.
    let standard = generate(SceneKind::Things, 11, 1, &GenParams::new(1.65, 0.3)).unwrap();
    assert!(standard.extra_lights.is_empty() && standard.light.range_m.is_none());
}

/// A plate with 4x3 holes 2 m below the rig: inverse depth `d_y / y_top`
/// on its bars, 0 through its holes and beyond it.
#[test]
fn plate_with_holes_matches_its_analytic_inverse_depth() {
    let (cells_x, cells_z, bar, half_y) = (4u32, 3u32, 0.1f64, 0.01f64);
    let (h, size) = (2.0, 10.0);
    let scene = SceneSpec {
        objects: vec![ObjectSpec {
            shape: ShapeSpec::Grid {
                cells_x,
                cells_z,
                bar: bar as f32,
                half_y: half_y as f32,
            },
            placement: Placement::at([0.0, h, 0.0], [size, 1.0, size]),
            texture: TextureSpec::flat(0.5),
            texture_scale_m: 1.0,
        }],
        ..SceneSpec::empty()
    };
    let tracer = Tracer::new(&scene, &[]).unwrap();
    let grid = EquirectGrid::new(320, 640, 90.0).unwrap();
    let gt = render_inverse_depth(&tracer, &grid);
    let y_top = h - half_y;
    // Distance (unit space) to the nearest bar centre line along one axis.
    let on_bar = |u: f64, n: u32| {
        (0..=n)
            .map(|i| {
                let c = -1.0 + bar / 2.0 + (2.0 - bar) * f64::from(i) / f64::from(n);
                (u - c).abs() - bar / 2.0
            })
            .fold(f64::INFINITY, f64::min)
    };
    let margin = 0.01;
    let (mut bars, mut holes) = (0, 0);
    for row in 0..grid.height {
        for col in 0..grid.width {
            let d = grid.ray(row as f64, col as f64).normalize();
            if d.y < 0.3 {
                continue;
            }
            let p = d * (y_top / d.y);
            let (u, v) = (p.x / size, p.z / size);
            let got = f64::from(gt[row * grid.width + col]);
            let outside = u.abs().max(v.abs()) - 1.0;
            let bar_dist = on_bar(u, cells_x).min(on_bar(v, cells_z));
            if outside < -margin && bar_dist < -margin {
                let want = d.y / y_top;
                assert!(
                    ((got - want) / want).abs() < 2e-6,
                    "({row},{col}) on a bar: {got} vs {want}"
                );
                bars += 1;
            } else if outside > margin || (outside < -margin && bar_dist > margin) {
                assert_eq!(got, 0.0, "({row},{col}) through a hole");
                holes += 1;
            }
        }
    }
    assert!(
        bars > 5_000 && holes > 20_000,
        "{bars} bar, {holes} hole pixels"
    );
}

#[test]
fn synth_json_records_the_difficulty_and_a_resume_with_another_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("d");
    writer(&out, SceneKind::Things, Difficulty::Hard).unwrap();
    let text = std::fs::read_to_string(out.join("synth.json")).unwrap();
    assert!(text.contains("\"difficulty\": \"hard\""), "{text}");
    let err = writer(&out, SceneKind::Things, Difficulty::Standard)
        .err()
        .unwrap();
    assert!(matches!(err, SynthError::SettingsMismatch { .. }));
    let msg = err.to_string();
    assert!(
        msg.contains("synth.json") && msg.contains("difficulty hard there, standard now"),
        "{msg}"
    );
    assert!(writer(&out, SceneKind::Things, Difficulty::Hard).is_ok());

    // A dataset written before the option existed has no `difficulty`: it
    // is standard, resumes as standard and is refused as hard.
    let old = dir.path().join("old");
    writer(&old, SceneKind::House, Difficulty::Standard).unwrap();
    let path = old.join("synth.json");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut json: serde_json::Value = serde_json::from_str(&text).unwrap();
    json.as_object_mut().unwrap().remove("difficulty").unwrap();
    std::fs::write(&path, serde_json::to_string_pretty(&json).unwrap()).unwrap();
    assert!(writer(&old, SceneKind::House, Difficulty::Standard).is_ok());
    assert!(writer(&old, SceneKind::House, Difficulty::Hard).is_err());
}
