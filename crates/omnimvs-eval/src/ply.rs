//! Binary PLY point clouds (x, y, z in metres, rig frame; RGB colour).

use std::path::Path;

use omnimvs_data::DataError;

/// A coloured point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColoredPoint {
    pub xyz_m: [f32; 3],
    pub rgb: [u8; 3],
}

/// Writes a binary little-endian PLY file atomically.
///
/// # Errors
/// [`DataError`] naming the file.
pub fn write_ply(path: &Path, points: &[ColoredPoint]) -> Result<(), DataError> {
    omnimvs_core::fs::write_atomic_with(path, |w| {
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment omnimvs point cloud, rig frame, metres\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
            points.len()
        )?;
        for p in points {
            for c in p.xyz_m {
                w.write_all(&c.to_le_bytes())?;
            }
            w.write_all(&p.rgb)?;
        }
        Ok(())
    })
    .map_err(|e| DataError::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn header_and_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("a.ply");
        let pts = [ColoredPoint {
            xyz_m: [1.0, 2.0, 3.0],
            rgb: [4, 5, 6],
        }; 3];
        write_ply(&path, &pts).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.starts_with("ply\nformat binary_little_endian 1.0\n"));
        assert!(text.contains("element vertex 3\n"));
        let header_len = text.find("end_header\n").unwrap() + "end_header\n".len();
        assert_eq!(bytes.len() - header_len, 3 * 15);
    }
}
