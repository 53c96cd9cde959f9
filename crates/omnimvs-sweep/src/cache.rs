use std::path::{Path, PathBuf};

use omnimvs_camera::Rig;

use crate::{EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet, SweepError};

/// A folder of lookup tables keyed by the rig's content and the sweep
/// parameters, outside any dataset folder (datasets may be read-only).
#[derive(Debug, Clone)]
pub struct LutCache {
    pub dir: PathBuf,
}

/// What [`LutCache::load_or_build`] did.
#[derive(Debug, Clone, PartialEq)]
pub enum CacheStatus {
    /// Read from the cache file.
    Hit(PathBuf),
    /// Built and saved to the cache file.
    Built(PathBuf),
    /// Built, but the cache could not be written (the reason); the table is
    /// still correct.
    BuiltNotSaved(String),
}

/// 64-bit FNV-1a: a stable hash (unlike `DefaultHasher`, it never changes
/// between Rust versions), enough to key cache files.
fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

impl LutCache {
    /// The cache in `dir`.
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        Self { dir: dir.into() }
    }

    /// The user cache: `$OMNIMVS_CACHE_DIR`, else `$XDG_CACHE_HOME/omnimvs/lut`,
    /// else `$HOME/.cache/omnimvs/lut`, else the system temporary folder.
    pub fn default_location() -> Self {
        let env = |k: &str| {
            std::env::var_os(k)
                .filter(|v| !v.is_empty())
                .map(PathBuf::from)
        };
        let dir = if let Some(d) = env("OMNIMVS_CACHE_DIR") {
            d.join("lut")
        } else if let Some(d) = env("XDG_CACHE_HOME") {
            d.join("omnimvs").join("lut")
        } else if let Some(d) = env("HOME") {
            d.join(".cache").join("omnimvs").join("lut")
        } else {
            std::env::temp_dir().join("omnimvs").join("lut")
        };
        Self { dir }
    }

    /// The cache file for these parameters:
    /// `lt_(h,w,N)-<hash of rig and parameters>.hwd`.
    pub fn path_for(
        &self,
        rig: &Rig,
        grid: &EquirectGrid,
        hypotheses: &InvDepthHypotheses,
        spheres: SphereSet,
    ) -> PathBuf {
        let key = format!(
            "v1|{}|grid={}x{}@{:?}|N={}|min_depth={:?}|{:?}",
            rig.content_key(),
            grid.height,
            grid.width,
            grid.phi_deg,
            hypotheses.count,
            hypotheses.min_depth_m,
            spheres
        );
        let stem = crate::hwd_file_name(grid.height, grid.width, hypotheses.count);
        let stem = stem.trim_end_matches(".hwd");
        let set = match spheres {
            SphereSet::All => "all",
            SphereSet::EveryOther => "half",
        };
        self.dir
            .join(format!("{stem}-{set}-{:016x}.hwd", fnv1a64(key.as_bytes())))
    }

    /// Reads the table from the cache, or builds it and saves it there.
    ///
    /// # Errors
    /// Only what [`LookupTable::build`] returns; a cache file that cannot be
    /// read (wrong size, say) is rebuilt and a cache that cannot be written is
    /// reported in [`CacheStatus::BuiltNotSaved`].
    pub fn load_or_build(
        &self,
        rig: &Rig,
        grid: &EquirectGrid,
        hypotheses: &InvDepthHypotheses,
        spheres: SphereSet,
    ) -> Result<(LookupTable, CacheStatus), SweepError> {
        let path = self.path_for(rig, grid, hypotheses, spheres);
        if path.is_file()
            && let Ok(lut) = LookupTable::read_hwd(&path, rig, grid, hypotheses, spheres)
        {
            return Ok((lut, CacheStatus::Hit(path)));
        }
        let lut = LookupTable::build(rig, grid, hypotheses, spheres)?;
        let status = match self.save(&path, &lut) {
            Ok(()) => CacheStatus::Built(path),
            Err(e) => CacheStatus::BuiltNotSaved(e.to_string()),
        };
        Ok((lut, status))
    }

    fn save(&self, path: &Path, lut: &LookupTable) -> Result<(), SweepError> {
        std::fs::create_dir_all(&self.dir).map_err(|source| SweepError::Io {
            path: self.dir.clone(),
            source,
        })?;
        lut.write_hwd(path)
    }
}

#[cfg(test)]
mod tests {
    use super::fnv1a64;

    #[test]
    fn fnv_is_stable() {
        // Published FNV-1a 64 test vectors.
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
    }
}
