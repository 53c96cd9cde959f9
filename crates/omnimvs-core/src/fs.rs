//! File helpers shared by every crate of the workspace (this is the lowest one).
//!
//! Every output file of the workspace is written here, atomically; `clippy.toml`
//! disallows `std::fs::write` and `File::create` everywhere else (tests aside).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Writes `bytes` to `path` atomically: the data goes to a temporary file in
/// the same folder, is flushed to disk, and is then renamed over `path`. A
/// reader (or an interrupted run) sees either the old file or the whole new
/// one, never a partial file.
///
/// # Errors
/// Any I/O error, with the temporary file removed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Like [`write_atomic`], but the content is produced by `fill`, which writes
/// into a buffered writer (for large outputs that need not be held in memory).
///
/// # Errors
/// Any I/O error from `fill`, the flush or the rename; the temporary file is
/// removed.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> std::io::Result<()> {
    let tmp = temp_path_for(path);
    let result = (|| {
        #[allow(clippy::disallowed_methods)] // the one place that creates output files
        let file = std::fs::File::create(&tmp)?;
        let mut writer = std::io::BufWriter::new(file);
        fill(&mut writer)?;
        let file = writer.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// The temporary file name used while writing `path`: hidden, in the same
/// folder (so the rename is atomic), unique per process and per call (two
/// threads writing the same file do not share a temporary file).
pub fn temp_path_for(path: &Path) -> PathBuf {
    static NEXT: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".to_string());
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    let tmp_name = format!(".{name}.{}-{n}.tmp", std::process::id());
    path.with_file_name(tmp_name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn write_atomic_replaces_whole_file_and_leaves_no_temp() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.bin");
        write_atomic(&path, b"first").unwrap();
        write_atomic(&path, b"second").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"second");
        let names: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
        assert_eq!(names.len(), 1);
    }

    #[test]
    fn failed_fill_keeps_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.bin");
        write_atomic(&path, b"old").unwrap();
        let err = write_atomic_with(&path, |w| {
            w.write_all(b"partial")?;
            Err(std::io::Error::other("disk full"))
        });
        assert!(err.is_err());
        assert_eq!(std::fs::read(&path).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    /// A failure after more than the buffer's worth of bytes has reached the
    /// temporary file: the old file is untouched and the temporary file gone.
    #[test]
    fn failure_after_bytes_reached_the_disk_keeps_old_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("big.bin");
        write_atomic(&path, b"old content").unwrap();
        let err = write_atomic_with(&path, |w| {
            for _ in 0..64 {
                w.write_all(&[7u8; 4096])?;
            }
            Err(std::io::Error::other("the producer failed"))
        })
        .unwrap_err();
        assert_eq!(err.to_string(), "the producer failed");
        assert_eq!(std::fs::read(&path).unwrap(), b"old content");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
    }

    #[test]
    fn temporary_names_differ_per_call_and_stay_in_the_folder() {
        let path = Path::new("/some/dir/out.tiff");
        let (a, b) = (temp_path_for(path), temp_path_for(path));
        assert_ne!(a, b);
        assert_eq!(a.parent(), path.parent());
        assert!(
            a.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with(".out.tiff.")
        );
    }
}
