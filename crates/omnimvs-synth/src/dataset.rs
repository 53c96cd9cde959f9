//! Writing a dataset in the reference layout (`FORMATS.md`):
//!
//! ```text
//! <out>/config.yaml                      the rig, min depth, img_fmt, frames, the train/test
//!                                         split (`split.rs`: the reference trains on it as is)
//! <out>/mask1.png ... maskN.png           each camera's `invalid_mask` (non-zero outside the FOV)
//! <out>/synth.json                       generator settings (checked on resume)
//! <out>/cam1/00001.png ... camN/         8-bit gray fisheye images
//! <out>/omnidepth_gt_640/00001.tiff      f32 inverse depth, 320x640, +-90 deg (two pages: an
//!                                         RGB picture, then the f32 values, as released)
//! <out>/scene/00001.json                 the scene, enough to render it again
//! ```
//!
//! Every file is written atomically (temporary file + rename), the ground
//! truth last; a frame counts as done when all its files exist, so an
//! interrupted run leaves whole files only and a re-run resumes.

use std::path::{Path, PathBuf};

use omnimvs_camera::Rig;
use omnimvs_data::{DatasetConfig, FrameRange, write_config_yaml};
use omnimvs_sweep::EquirectGrid;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::camera_effects::{CameraEffects, apply_all, auto_expose};
use crate::mesh::TriMesh;
use crate::mesh_file::load_mesh;
use crate::rig::{RigSource, rig_radius_m};
use crate::scene::{SceneKind, SceneSpec, generator_name};
use crate::{
    Difficulty, GenParams, SynthError, Tracer, generate, render_fisheye, render_inverse_depth,
};

/// Ground-truth grid of the published datasets: 320 x 640, +-90 degrees.
pub const GT_HEIGHT: usize = 320;
pub const GT_WIDTH: usize = 640;
pub const GT_PHI_DEG: f64 = 90.0;
/// Image file pattern (camera index 1-based, frame index).
pub const IMG_FMT: &str = "cam%d/%05d.png";
/// Ground-truth folder and pattern.
pub const GT_DIR: &str = "omnidepth_gt_640";
pub const GT_FMT: &str = "omnidepth_gt_640/%05d.tiff";
pub const SCENE_DIR: &str = "scene";

/// The settings that decide what a dataset contains; written to
/// `synth.json`, and a resumed run must use the same ones.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SynthSettings {
    pub generator: String,
    pub kind: SceneKind,
    pub seed: u64,
    /// Samples per pixel of the fisheye images.
    pub spp: u32,
    pub num_objects: usize,
    /// User mesh files (OBJ/PLY) for `things` scenes.
    pub meshes: Vec<String>,
    /// Image size of every camera, `[height, width]`.
    pub image_size: Vec<[u32; 2]>,
    pub min_depth_m: f64,
    /// Scene and camera difficulty; a `synth.json` written before this
    /// option existed reads as `standard`.
    #[serde(default)]
    pub difficulty: Difficulty,
}

/// What a dataset is made of, besides the rig and the frames: the choices of
/// `omnimvs synth`.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthOptions {
    pub kind: SceneKind,
    pub seed: u64,
    /// Samples per pixel of the fisheye images (1 to 4096).
    pub spp: u32,
    /// User mesh files (OBJ/PLY) for `things` scenes.
    pub meshes: Vec<String>,
    pub difficulty: Difficulty,
}

impl SynthOptions {
    /// `kind` and `seed`, 1 sample per pixel, no user mesh, `standard`.
    pub fn new(kind: SceneKind, seed: u64) -> Self {
        Self {
            kind,
            seed,
            spp: 1,
            meshes: Vec::new(),
            difficulty: Difficulty::Standard,
        }
    }
}

/// Which part of the frames a machine renders: frames `k` (0-based position
/// in the range) with `k % count == index - 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1-based.
    pub index: u32,
    pub count: u32,
}

impl Shard {
    pub const ALL: Self = Self { index: 1, count: 1 };

    /// Parses `i/n`, `1 <= i <= n`.
    ///
    /// # Errors
    /// [`SynthError::Invalid`] naming the shard and the text.
    pub fn parse(s: &str) -> Result<Self, SynthError> {
        let bad = || {
            SynthError::invalid(
                "shard",
                format!("expected i/n with 1 <= i <= n, such as 2/4, found {s:?}"),
            )
        };
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse::<u32>().map_err(|_| bad())?,
            n.trim().parse::<u32>().map_err(|_| bad())?,
        );
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }

    /// The frames of `range` that belong to this shard.
    pub fn frames(&self, range: &FrameRange) -> Vec<u32> {
        range
            .indices()
            .into_iter()
            .enumerate()
            .filter(|(k, _)| *k as u32 % self.count == self.index - 1)
            .map(|(_, f)| f)
            .collect()
    }
}

/// The files of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePaths {
    pub images: Vec<PathBuf>,
    pub gt: PathBuf,
    pub scene: PathBuf,
}

impl FramePaths {
    fn all(&self) -> impl Iterator<Item = &PathBuf> {
        self.images.iter().chain([&self.scene, &self.gt])
    }
}

/// The frame range `config.yaml` announces after rendering `frames` into a dataset whose
/// `config.yaml` (if any) already announces a range: both together (first to last, step 1
/// when both ranges have step 1), so that a dataset filled in several runs, e.g. its
/// validation frames first, lists every frame it holds.
///
/// # Errors
/// [`SynthError`] when an existing `config.yaml` cannot be read or parsed.
fn covered_frames(config_path: &Path, frames: &FrameRange) -> Result<FrameRange, SynthError> {
    if !config_path.exists() {
        return Ok(*frames);
    }
    let text = std::fs::read_to_string(config_path).map_err(io(config_path, "cannot read"))?;
    let old = DatasetConfig::parse(config_path, &text)?.frames;
    if old.step != 1 || frames.step != 1 {
        return Ok(*frames);
    }
    Ok(FrameRange {
        start: old.start.min(frames.start),
        step: 1,
        end: old.end.max(frames.end),
    })
}

/// One rendered frame, in memory.
pub struct Frame {
    pub scene: SceneSpec,
    /// Per camera, 8-bit gray, row-major.
    pub images: Vec<Vec<u8>>,
    /// `GT_HEIGHT x GT_WIDTH` inverse depth, 1/m.
    pub inv_depth: Vec<f32>,
}

/// What happened to a frame during [`DatasetWriter::run`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameEvent {
    Rendered(u32),
    /// Already complete on disk (resume).
    Skipped(u32),
}

/// Renders and writes frames of one dataset folder.
pub struct DatasetWriter {
    out: PathBuf,
    rig: Rig,
    settings: SynthSettings,
    params: GenParams,
    meshes: Vec<TriMesh>,
    grid: EquirectGrid,
}

fn io<'a>(path: &'a Path, action: &'static str) -> impl FnOnce(std::io::Error) -> SynthError + 'a {
    move |e| SynthError::io(path, action, e)
}

impl DatasetWriter {
    /// [`Self::create_with`] at the `standard` difficulty.
    ///
    /// # Errors
    /// As [`Self::create_with`].
    pub fn create(
        out: &Path,
        rig: &RigSource,
        kind: SceneKind,
        seed: u64,
        spp: u32,
        meshes: &[String],
        frames: &FrameRange,
    ) -> Result<Self, SynthError> {
        let options = SynthOptions {
            spp,
            meshes: meshes.to_vec(),
            ..SynthOptions::new(kind, seed)
        };
        Self::create_with(out, rig, &options, frames)
    }

    /// Prepares `out`: creates the folders, writes `config.yaml` (the rig,
    /// min depth and the whole frame range) and `synth.json`, or checks that
    /// an existing `synth.json` has the same settings (resume).
    ///
    /// # Errors
    /// [`SynthError`] naming the folder or file: not creatable or writable,
    /// a user mesh that does not load, settings that differ from those of
    /// the dataset already there.
    pub fn create_with(
        out: &Path,
        rig: &RigSource,
        options: &SynthOptions,
        frames: &FrameRange,
    ) -> Result<Self, SynthError> {
        let SynthOptions {
            kind,
            seed,
            spp,
            ref meshes,
            difficulty,
        } = *options;
        if kind == SceneKind::Custom {
            return Err(SynthError::invalid(
                "scene kind",
                "expected things or house (a custom scene cannot fill a dataset)",
            ));
        }
        if spp == 0 || spp > 4096 {
            return Err(SynthError::invalid(
                "samples per pixel (spp)",
                format!("expected 1 to 4096 samples per pixel, found {spp}"),
            ));
        }
        let loaded = meshes
            .iter()
            .map(|m| load_mesh(Path::new(m)))
            .collect::<Result<Vec<_>, _>>()?;
        let mut params = GenParams::new(rig.min_depth_m, rig_radius_m(&rig.rig));
        params.meshes = meshes.to_vec();
        params.difficulty = difficulty;
        let settings = SynthSettings {
            generator: generator_name(),
            kind,
            seed,
            spp,
            num_objects: params.num_objects,
            meshes: meshes.to_vec(),
            image_size: rig
                .rig
                .cameras
                .iter()
                .map(|c| [c.model.height(), c.model.width()])
                .collect(),
            min_depth_m: rig.min_depth_m,
            difficulty,
        };
        std::fs::create_dir_all(out).map_err(io(out, "cannot create the output folder"))?;
        for dir in rig
            .rig
            .cameras
            .iter()
            .map(|c| c.img_dir.as_str())
            .chain([GT_DIR, SCENE_DIR])
        {
            let p = out.join(dir);
            std::fs::create_dir_all(&p).map_err(io(&p, "cannot create folder"))?;
        }
        write_or_check_settings(&out.join("synth.json"), &settings)?;
        write_config_and_masks(out, rig, kind, frames)?;
        Ok(Self {
            out: out.to_path_buf(),
            rig: rig.rig.clone(),
            settings,
            params,
            meshes: loaded,
            grid: EquirectGrid::new(GT_HEIGHT, GT_WIDTH, GT_PHI_DEG)?,
        })
    }

    pub fn settings(&self) -> &SynthSettings {
        &self.settings
    }

    /// The files of frame `frame`.
    pub fn frame_paths(&self, frame: u32) -> FramePaths {
        FramePaths {
            images: self
                .rig
                .cameras
                .iter()
                .map(|c| self.out.join(&c.img_dir).join(format!("{frame:05}.png")))
                .collect(),
            gt: self.out.join(GT_DIR).join(format!("{frame:05}.tiff")),
            scene: self.out.join(SCENE_DIR).join(format!("{frame:05}.json")),
        }
    }

    /// Whether every file of the frame is on disk.
    pub fn is_complete(&self, frame: u32) -> bool {
        self.frame_paths(frame).all().all(|p| p.is_file())
    }

    /// Generates and renders one frame in memory. At the `hard` difficulty
    /// the images then go through the frame's real-camera effects (recorded
    /// in the scene); the ground truth never does.
    ///
    /// # Errors
    /// [`SynthError`] if the scene cannot be built.
    pub fn render_frame(&self, frame: u32) -> Result<Frame, SynthError> {
        let mut scene = generate(self.settings.kind, self.settings.seed, frame, &self.params)?;
        if self.settings.difficulty.is_hard() {
            scene.camera_effects =
                CameraEffects::draw(self.settings.seed, frame, self.rig.cameras.len());
        }
        let (mut images, inv_depth) = render_scene(
            &scene,
            &self.meshes,
            &self.rig,
            self.settings.spp,
            &self.grid,
        )?;
        if !scene.camera_effects.is_empty() {
            auto_expose(&mut scene.camera_effects, &images);
            apply_all(&scene.camera_effects, &self.rig.cameras, &mut images)?;
        }
        Ok(Frame {
            scene,
            images,
            inv_depth,
        })
    }

    /// Writes a rendered frame: scene, images, then the ground truth.
    ///
    /// # Errors
    /// [`SynthError`] naming the file that could not be written; files of
    /// other frames are untouched and this frame is redone by a re-run.
    pub fn write_frame(&self, frame: u32, data: &Frame) -> Result<(), SynthError> {
        let paths = self.frame_paths(frame);
        let json = serde_json::to_string_pretty(&data.scene).map_err(|e| SynthError::Json {
            path: paths.scene.clone(),
            message: e.to_string(),
        })?;
        omnimvs_core::fs::write_atomic(&paths.scene, json.as_bytes())
            .map_err(io(&paths.scene, "cannot write"))?;
        self.rig
            .cameras
            .par_iter()
            .zip(&data.images)
            .zip(&paths.images)
            .try_for_each(|((cam, img), path)| {
                let (w, h) = (cam.model.width() as usize, cam.model.height() as usize);
                omnimvs_data::image_io::write_png_u8(path, w, h, 1, img).map_err(SynthError::from)
            })?;
        omnimvs_data::gt::write_gt_tiff(&paths.gt, GT_WIDTH, GT_HEIGHT, &data.inv_depth)?;
        Ok(())
    }

    /// Renders and writes `frames`, skipping complete ones; `on_frame` is
    /// called after each.
    ///
    /// # Errors
    /// The first failure; frames finished before it stay on disk.
    pub fn run(
        &self,
        frames: &[u32],
        mut on_frame: impl FnMut(FrameEvent),
    ) -> Result<(), SynthError> {
        for &f in frames {
            if self.is_complete(f) {
                on_frame(FrameEvent::Skipped(f));
                continue;
            }
            let data = self.render_frame(f)?;
            self.write_frame(f, &data)?;
            on_frame(FrameEvent::Rendered(f));
        }
        Ok(())
    }
}

fn describe_difference(old: &SynthSettings, new: &SynthSettings) -> String {
    let mut d = Vec::new();
    if old.kind != new.kind {
        d.push(format!(
            "kind {} there, {} now",
            old.kind.name(),
            new.kind.name()
        ));
    }
    if old.seed != new.seed {
        d.push(format!("seed {} there, {} now", old.seed, new.seed));
    }
    if old.difficulty != new.difficulty {
        d.push(format!(
            "difficulty {} there, {} now",
            old.difficulty.name(),
            new.difficulty.name()
        ));
    }
    if old.spp != new.spp {
        d.push(format!("spp {} there, {} now", old.spp, new.spp));
    }
    if old.image_size != new.image_size {
        d.push(format!(
            "image size {:?} there, {:?} now",
            old.image_size, new.image_size
        ));
    }
    if old.min_depth_m != new.min_depth_m {
        d.push(format!(
            "min depth {} there, {} now",
            old.min_depth_m, new.min_depth_m
        ));
    }
    if old.meshes != new.meshes {
        d.push("different user meshes".to_string());
    }
    if old.generator != new.generator {
        d.push(format!(
            "generator {} there, {} now",
            old.generator, new.generator
        ));
    }
    if d.is_empty() {
        d.push("other settings differ".to_string());
    }
    d.join(", ")
}

/// Renders every camera of `rig` and the ground truth on `grid` for a scene.
///
/// # Errors
/// [`SynthError`] if the scene cannot be built (bad placement, mesh index).
pub fn render_scene(
    scene: &SceneSpec,
    meshes: &[TriMesh],
    rig: &Rig,
    spp: u32,
    grid: &EquirectGrid,
) -> Result<(Vec<Vec<u8>>, Vec<f32>), SynthError> {
    let tracer = Tracer::new(scene, meshes)?;
    let images = rig
        .cameras
        .iter()
        .map(|c| render_fisheye(&tracer, c, spp))
        .collect();
    let inv_depth = render_inverse_depth(&tracer, grid);
    Ok((images, inv_depth))
}

/// Writes `settings` to `path` (`synth.json`), or, when the dataset is already there, checks
/// that its settings are the same (a resumed generation must not mix two kinds of frames).
fn write_or_check_settings(path: &Path, settings: &SynthSettings) -> Result<(), SynthError> {
    let settings_json = serde_json::to_string_pretty(settings).map_err(|e| SynthError::Json {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    if path.exists() {
        let text = std::fs::read_to_string(path).map_err(io(path, "cannot read"))?;
        let old: SynthSettings = serde_json::from_str(&text).map_err(|e| SynthError::Json {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        if old != *settings {
            return Err(SynthError::SettingsMismatch {
                path: path.to_path_buf(),
                message: describe_difference(&old, settings),
            });
        }
        Ok(())
    } else {
        omnimvs_core::fs::write_atomic(path, settings_json.as_bytes())
            .map_err(io(path, "cannot write"))
    }
}

/// Writes `out/config.yaml` (the rig, the minimum depth, every frame written so far and
/// `frames`, the published split) and every camera's mask `out/maskN.png`.
fn write_config_and_masks(
    out: &Path,
    rig: &RigSource,
    kind: SceneKind,
    frames: &FrameRange,
) -> Result<(), SynthError> {
    let config_path = out.join("config.yaml");
    let covered = covered_frames(&config_path, frames)?;
    let config = DatasetConfig {
        min_depth_m: rig.min_depth_m,
        img_fmt: IMG_FMT.to_string(),
        frames: covered,
        gt_fmt: Some(GT_FMT.to_string()),
        // The reference implementation's train/test frames (`split.rs`).
        split: Some(crate::split::published_split(kind, &covered, GT_PHI_DEG)),
    };
    // Every camera names its `invalid_mask` (the reference's reader needs the field) and
    // the mask is written: non-zero outside the field of view, what a reader derives
    // from `max_fov` alone anyway.
    let mut rig_with_masks = rig.stated_rig().clone();
    for (i, camera) in rig_with_masks.cameras.iter_mut().enumerate() {
        let name = format!("mask{}.png", i + 1);
        let mask = omnimvs_camera::ValidityMask::from_fov(&camera.model);
        let pixels: Vec<u8> = mask
            .valid
            .iter()
            .map(|&v| if v { 0 } else { 255 })
            .collect();
        omnimvs_data::image_io::write_png_u8(
            &out.join(&name),
            mask.width as usize,
            mask.height as usize,
            1,
            &pixels,
        )?;
        camera.invalid_mask = Some(name);
    }
    let text = write_config_yaml(&rig_with_masks, &config)?;
    omnimvs_core::fs::write_atomic(&config_path, text.as_bytes())
        .map_err(io(&config_path, "cannot write"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_and_shards_parse() {
        assert_eq!(
            "1..1000".parse::<FrameRange>().unwrap(),
            FrameRange {
                start: 1,
                step: 1,
                end: 1000
            }
        );
        assert_eq!(
            "5".parse::<FrameRange>().unwrap(),
            FrameRange {
                start: 5,
                step: 1,
                end: 5
            }
        );
        assert_eq!("3..=4".parse::<FrameRange>().unwrap().end, 4);
        let err = "10..2".parse::<FrameRange>().unwrap_err().to_string();
        assert!(err.contains("10..2") && err.contains("reversed"), "{err}");
        assert!("a..b".parse::<FrameRange>().is_err());
        let range: FrameRange = "1..10".parse().unwrap();
        let s = Shard::parse("2/3").unwrap();
        assert_eq!(s.frames(&range), vec![2, 5, 8]);
        let all: Vec<u32> = (1..=3)
            .flat_map(|i| Shard { index: i, count: 3 }.frames(&range))
            .collect();
        assert_eq!(all.len(), 10);
        assert!(Shard::parse("0/3").is_err());
        assert!(Shard::parse("4/3").is_err());
        assert!(Shard::parse("x").is_err());
    }
}
