use std::path::Path;

use crate::{Camera, CameraError, CameraModel, Pixel};

/// Which pixels of a fisheye image carry scene content: inside the field of
/// view and not marked in the camera's `invalid_mask` PNG.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidityMask {
    pub width: u32,
    pub height: u32,
    /// Row-major, `true` = valid.
    pub valid: Vec<bool>,
}

impl ValidityMask {
    /// The pixels whose ray lies inside the model's field of view.
    pub fn from_fov(model: &CameraModel) -> Self {
        let (width, height) = (model.width(), model.height());
        let mut valid = Vec::with_capacity(width as usize * height as usize);
        for row in 0..height {
            for col in 0..width {
                valid.push(
                    model
                        .unproject(Pixel::new(f64::from(col), f64::from(row)))
                        .is_some(),
                );
            }
        }
        Self {
            width,
            height,
            valid,
        }
    }

    /// The camera's mask: the field of view, combined with the `invalid_mask` image
    /// (non-zero = invalid) when the configuration names one and the file exists in
    /// `dataset_dir` (the reference datasets often ship without them), and with the
    /// `valid_mask` image (non-zero = valid) when the camera has one; nothing is ever written.
    ///
    /// # Errors
    /// A mask image that cannot be decoded, a `valid_mask` that is missing, or a mask whose
    /// size differs from the camera's.
    pub fn for_camera(camera: &Camera, dataset_dir: &Path) -> Result<Self, CameraError> {
        let mut mask = Self::from_fov(&camera.model);
        if let Some(name) = &camera.invalid_mask {
            let path = dataset_dir.join(name);
            if path.is_file() {
                mask.combine(&path, false)?;
            }
        }
        if let Some(name) = &camera.valid_mask {
            mask.combine(&dataset_dir.join(name), true)?;
        }
        Ok(mask)
    }

    /// Keeps the pixels that the image at `path` marks valid: non-zero ones when
    /// `nonzero_valid`, zero ones otherwise.
    fn combine(&mut self, path: &Path, nonzero_valid: bool) -> Result<(), CameraError> {
        let img = image::open(path)
            .map_err(|source| CameraError::MaskImage {
                path: path.to_path_buf(),
                source,
            })?
            .into_luma8();
        if img.width() != self.width || img.height() != self.height {
            return Err(CameraError::MaskSize {
                path: path.to_path_buf(),
                found_w: img.width(),
                found_h: img.height(),
                want_w: self.width,
                want_h: self.height,
            });
        }
        for (v, p) in self.valid.iter_mut().zip(img.as_raw()) {
            *v &= (*p != 0) == nonzero_valid;
        }
        Ok(())
    }

    /// Whether the pixel at integer `(col, row)` is valid; `false` outside.
    pub fn is_valid(&self, col: i64, row: i64) -> bool {
        if col < 0 || row < 0 || col >= i64::from(self.width) || row >= i64::from(self.height) {
            return false;
        }
        self.valid[row as usize * self.width as usize + col as usize]
    }

    /// Number of valid pixels.
    pub fn count_valid(&self) -> usize {
        self.valid.iter().filter(|&&v| v).count()
    }
}
