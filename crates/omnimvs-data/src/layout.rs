//! How a folder holds its images when no `config.yaml` states it: the camera folders
//! (`cam0`.. or `cam1`..), the frames' file names (zero-padded or not, PNG, JPEG, ...), and
//! each camera's validity mask beside its images.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::DataError;

/// Image extensions read as frames, lower case.
const IMAGE_EXTS: [&str; 7] = ["png", "jpg", "jpeg", "bmp", "tif", "tiff", "webp"];

/// File names (without extension) of a camera's validity mask, nonzero = valid, looked for in
/// that camera's image folder.
pub const MASK_STEMS: [&str; 2] = ["mask", "valid_mask"];

/// The camera folders and file names found in a dataset folder.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ImageLayout {
    /// The number of the first camera's folder: 0 (`cam0`, `cam1`, ...) or 1 (`cam1`, ...).
    pub first_camera_number: u32,
    /// printf pattern of an image by camera number and frame, e.g. `cam%d/%05d.jpg`.
    pub img_fmt: String,
    /// The frames whose image exists in the first camera's folder, ascending.
    pub frames: Vec<u32>,
}

impl ImageLayout {
    /// Finds the folders of `num_cameras` cameras under `root`: `cam0`.. `cam{n-1}` or, failing
    /// that, `cam1`.. `cam{n}`; and the naming of the frames in the first one (numbered files
    /// of an image type; the naming most files share when several are present).
    ///
    /// # Errors
    /// [`DataError::Format`] naming the folder: no complete set of camera folders, or no
    /// numbered images in the first.
    pub fn discover(root: &Path, num_cameras: usize) -> Result<Self, DataError> {
        let complete = |first: u32| {
            (0..num_cameras as u32).all(|i| root.join(format!("cam{}", first + i)).is_dir())
        };
        let Some(first) = [0, 1].into_iter().find(|&f| complete(f)) else {
            let last = num_cameras.saturating_sub(1);
            return Err(DataError::format(
                root,
                format!(
                    "expected one image folder per camera of the rig ({num_cameras}): cam0..cam{last} or cam1..cam{num_cameras}"
                ),
            ));
        };
        let cam_dir = root.join(format!("cam{first}"));
        let (naming, frames) = frame_naming(&cam_dir)?;
        Ok(Self {
            first_camera_number: first,
            img_fmt: format!("cam%d/{naming}"),
            frames,
        })
    }
}

/// The printf pattern of the numbered images in `dir` (`%05d.png`, `%d.jpg`, ...) and their
/// frame numbers, ascending: among several namings, the one most files share.
///
/// # Errors
/// [`DataError::Format`] naming `dir` when it holds no numbered image.
pub fn frame_naming(dir: &Path) -> Result<(String, Vec<u32>), DataError> {
    let entries = std::fs::read_dir(dir).map_err(|e| DataError::io(dir, e))?;
    // (zero-padded width or 0 for unpadded, extension) -> frames.
    let mut namings: BTreeMap<(usize, String), Vec<u32>> = BTreeMap::new();
    for entry in entries {
        let path = entry.map_err(|e| DataError::io(dir, e))?.path();
        let (Some(stem), Some(ext)) = (
            path.file_stem().and_then(|s| s.to_str()),
            path.extension().and_then(|s| s.to_str()),
        ) else {
            continue;
        };
        if !IMAGE_EXTS.contains(&ext.to_ascii_lowercase().as_str())
            || stem.is_empty()
            || !stem.bytes().all(|b| b.is_ascii_digit())
        {
            continue;
        }
        let Ok(frame) = stem.parse::<u32>() else {
            continue;
        };
        // `00042` is padded to 5; `42` may be unpadded or padded to 2: it joins whichever
        // naming the padded names of its width do not claim (decided below).
        let width = if stem.len() > 1 && stem.starts_with('0') {
            stem.len()
        } else {
            0
        };
        namings
            .entry((width, ext.to_string()))
            .or_default()
            .push(frame);
    }
    // Unpadded names as long as a padded naming's width are that naming's too (`10000` among
    // `00001`..): move them there.
    let padded: Vec<(usize, String)> = namings.keys().filter(|(w, _)| *w > 0).cloned().collect();
    for (width, ext) in padded {
        if let Some(unpadded) = namings.get_mut(&(0, ext.clone())) {
            let (same, other): (Vec<u32>, Vec<u32>) =
                unpadded.iter().partition(|f| f.to_string().len() == width);
            *unpadded = other;
            namings.entry((width, ext)).or_default().extend(same);
        }
    }
    let Some(((width, ext), mut frames)) = namings
        .into_iter()
        .filter(|(_, f)| !f.is_empty())
        .max_by_key(|(_, f)| f.len())
    else {
        return Err(DataError::format(
            dir,
            "no numbered images (such as 00001.png, 1.jpg) in the first camera's folder",
        ));
    };
    frames.sort_unstable();
    frames.dedup();
    let naming = if width > 0 {
        format!("%0{width}d.{ext}")
    } else {
        format!("%d.{ext}")
    };
    Ok((naming, frames))
}

/// The validity mask beside a camera's images (`mask.png`, ... in `image_dir`), if any, as a
/// path relative to `root`.
pub fn mask_beside(root: &Path, image_dir: &Path) -> Option<String> {
    for stem in MASK_STEMS {
        for ext in ["png", "bmp", "tif", "tiff"] {
            let rel: PathBuf = image_dir.join(format!("{stem}.{ext}"));
            if root.join(&rel).is_file() {
                return Some(rel.to_string_lossy().into_owned());
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(dir: &Path, names: &[&str]) {
        std::fs::create_dir_all(dir).unwrap();
        for n in names {
            omnimvs_core::fs::write_atomic(&dir.join(n), b"").unwrap();
        }
    }

    #[test]
    fn finds_folders_from_zero_and_unpadded_jpegs() {
        let root = tempfile::tempdir().unwrap();
        for c in 0..3 {
            touch(
                &root.path().join(format!("cam{c}")),
                &["0.jpg", "1.jpg", "2.jpg", "10.jpg", "mask.png"],
            );
        }
        let layout = ImageLayout::discover(root.path(), 3).unwrap();
        assert_eq!(layout.first_camera_number, 0);
        assert_eq!(layout.img_fmt, "cam%d/%d.jpg");
        assert_eq!(layout.frames, [0, 1, 2, 10]);
        assert_eq!(
            mask_beside(root.path(), Path::new("cam2")).as_deref(),
            Some("cam2/mask.png")
        );
        assert_eq!(mask_beside(root.path(), Path::new("cam9")), None);
    }

    #[test]
    fn finds_folders_from_one_and_padded_names() {
        let root = tempfile::tempdir().unwrap();
        for c in 1..=4 {
            touch(
                &root.path().join(format!("cam{c}")),
                &["00001.png", "00002.png", "10000.png", "notes.txt", "x1.png"],
            );
        }
        let layout = ImageLayout::discover(root.path(), 4).unwrap();
        assert_eq!(layout.first_camera_number, 1);
        assert_eq!(layout.img_fmt, "cam%d/%05d.png");
        assert_eq!(layout.frames, [1, 2, 10000]);
    }

    #[test]
    fn a_missing_camera_folder_or_no_images_is_named() {
        let root = tempfile::tempdir().unwrap();
        touch(&root.path().join("cam0"), &["1.png"]);
        touch(&root.path().join("cam1"), &["1.png"]);
        let e = ImageLayout::discover(root.path(), 3)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cam0..cam2 or cam1..cam3"), "{e}");
        touch(&root.path().join("cam2"), &[]);
        std::fs::remove_file(root.path().join("cam0/1.png")).unwrap();
        let e = ImageLayout::discover(root.path(), 3)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("cam0") && e.contains("no numbered images"),
            "{e}"
        );
    }
}
