//! Mesh files: [`load_mesh`] reads Wavefront OBJ (through `tobj`) and PLY, with a minimal PLY
//! reader of its own: vertices (`x`, `y`, `z`) and polygonal faces
//! (`vertex_indices` / `vertex_index`, fan-triangulated), ASCII or binary
//! little-endian; other elements and properties are skipped.

use std::path::Path;

use glam::Vec3A;

use crate::SynthError;
use crate::mesh::TriMesh;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Result<Self, String> {
        Ok(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return Err(format!("unknown PLY property type {name:?}")),
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn read_le(self, b: &[u8]) -> f64 {
        let arr = |n: usize| -> [u8; 8] {
            let mut a = [0u8; 8];
            a[..n].copy_from_slice(&b[..n]);
            a
        };
        match self {
            Self::I8 => f64::from(b[0] as i8),
            Self::U8 => f64::from(b[0]),
            Self::I16 => f64::from(i16::from_le_bytes([b[0], b[1]])),
            Self::U16 => f64::from(u16::from_le_bytes([b[0], b[1]])),
            Self::I32 => f64::from(i32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Self::U32 => f64::from(u32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Self::F32 => f64::from(f32::from_le_bytes([b[0], b[1], b[2], b[3]])),
            Self::F64 => f64::from_le_bytes(arr(8)),
        }
    }
}

#[derive(Debug)]
enum Property {
    Scalar {
        name: String,
        ty: Scalar,
    },
    List {
        name: String,
        count: Scalar,
        item: Scalar,
    },
}

#[derive(Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

/// Parses the bytes of a PLY file.
///
/// # Errors
/// A message naming what was wrong (header, format, truncated data, a face
/// index that is not a whole number).
pub fn parse_ply(bytes: &[u8]) -> Result<TriMesh, String> {
    let header_end = find_subslice(bytes, b"end_header")
        .ok_or_else(|| "no `end_header` line: not a PLY file".to_string())?;
    let header = std::str::from_utf8(&bytes[..header_end])
        .map_err(|_| "the PLY header is not text".to_string())?;
    let mut body_start = header_end + b"end_header".len();
    if bytes.get(body_start) == Some(&b'\r') {
        body_start += 1;
    }
    if bytes.get(body_start) == Some(&b'\n') {
        body_start += 1;
    }
    let mut lines = header.lines().map(str::trim);
    if lines.next() != Some("ply") {
        return Err("the file does not start with `ply`".to_string());
    }
    let mut binary = None;
    let mut elements: Vec<Element> = Vec::new();
    for line in lines {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", "ascii", ..] => binary = Some(false),
            ["format", "binary_little_endian", ..] => binary = Some(true),
            ["format", other, ..] => return Err(format!("unsupported PLY format {other:?}")),
            ["element", name, count] => elements.push(Element {
                name: (*name).to_string(),
                count: count
                    .parse()
                    .map_err(|_| format!("bad element count {count:?}"))?,
                props: Vec::new(),
            }),
            ["property", "list", count, item, name] => elements
                .last_mut()
                .ok_or("a property before any element")?
                .props
                .push(Property::List {
                    name: (*name).to_string(),
                    count: Scalar::parse(count)?,
                    item: Scalar::parse(item)?,
                }),
            ["property", ty, name] => elements
                .last_mut()
                .ok_or("a property before any element")?
                .props
                .push(Property::Scalar {
                    name: (*name).to_string(),
                    ty: Scalar::parse(ty)?,
                }),
            _ => {} // comment, obj_info, blank
        }
    }
    let binary = binary.ok_or("no `format` line")?;
    let mut reader: Box<dyn ValueReader> = if binary {
        Box::new(BinReader {
            bytes: &bytes[body_start..],
            pos: 0,
        })
    } else {
        let text = std::str::from_utf8(&bytes[body_start..])
            .map_err(|_| "ASCII PLY body is not text".to_string())?;
        Box::new(AsciiReader {
            words: text.split_ascii_whitespace(),
        })
    };
    let mut mesh = TriMesh::default();
    for el in &elements {
        for _ in 0..el.count {
            let mut xyz = [0.0f32; 3];
            let mut face: Vec<u32> = Vec::new();
            for prop in &el.props {
                match prop {
                    Property::Scalar { name, ty } => {
                        let v = reader.next(*ty)?;
                        if el.name == "vertex" {
                            match name.as_str() {
                                "x" => xyz[0] = v as f32,
                                "y" => xyz[1] = v as f32,
                                "z" => xyz[2] = v as f32,
                                _ => {}
                            }
                        }
                    }
                    Property::List { name, count, item } => {
                        let n = reader.next(*count)?;
                        if !(0.0..=1e6).contains(&n) {
                            return Err(format!("bad list length {n}"));
                        }
                        let is_face = el.name == "face"
                            && (name == "vertex_indices" || name == "vertex_index");
                        for _ in 0..n as usize {
                            let v = reader.next(*item)?;
                            if is_face {
                                if v < 0.0 || v.fract() != 0.0 || v > f64::from(u32::MAX) {
                                    return Err(format!("bad vertex index {v}"));
                                }
                                face.push(v as u32);
                            }
                        }
                    }
                }
            }
            if el.name == "vertex" {
                mesh.positions.push(Vec3A::from_array(xyz));
            } else if face.len() >= 3 {
                for k in 1..face.len() - 1 {
                    mesh.triangles.push([face[0], face[k], face[k + 1]]);
                }
            }
        }
    }
    Ok(mesh)
}

fn find_subslice(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

trait ValueReader {
    fn next(&mut self, ty: Scalar) -> Result<f64, String>;
}

struct BinReader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl ValueReader for BinReader<'_> {
    fn next(&mut self, ty: Scalar) -> Result<f64, String> {
        let end = self.pos + ty.size();
        let b = self
            .bytes
            .get(self.pos..end)
            .ok_or("the binary PLY data ends early")?;
        self.pos = end;
        Ok(ty.read_le(b))
    }
}

struct AsciiReader<'a> {
    words: std::str::SplitAsciiWhitespace<'a>,
}

impl ValueReader for AsciiReader<'_> {
    fn next(&mut self, _ty: Scalar) -> Result<f64, String> {
        let w = self.words.next().ok_or("the ASCII PLY data ends early")?;
        w.parse().map_err(|_| format!("not a number: {w:?}"))
    }
}

/// Loads a user mesh (`.obj` or `.ply`, ASCII or binary little-endian),
/// triangulated and normalised into the unit ball.
///
/// # Errors
/// [`SynthError::Mesh`] for an unreadable or malformed file, an unknown
/// extension, a mesh without triangles or with non-finite coordinates.
pub fn load_mesh(path: &Path) -> Result<TriMesh, SynthError> {
    let err = |message: String| SynthError::Mesh {
        path: path.to_path_buf(),
        message,
    };
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let mut mesh = match ext.as_str() {
        "obj" => load_obj(path).map_err(err)?,
        "ply" => {
            let bytes =
                std::fs::read(path).map_err(|e| SynthError::io(path, "cannot read mesh", e))?;
            parse_ply(&bytes).map_err(err)?
        }
        _ => {
            return Err(err(format!(
                "unknown mesh format {ext:?}, expected .obj or .ply"
            )));
        }
    };
    if mesh.triangles.is_empty() {
        return Err(err("the file holds no triangles".to_string()));
    }
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err(err("a vertex has a non-finite coordinate".to_string()));
    }
    let n = mesh.positions.len() as u32;
    if let Some(bad) = mesh.triangles.iter().flatten().find(|&&i| i >= n) {
        return Err(err(format!(
            "a face refers to vertex {bad} but there are only {n}"
        )));
    }
    mesh.normalize_to_unit_ball();
    Ok(mesh)
}

fn load_obj(path: &Path) -> Result<TriMesh, String> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let (models, _materials) = tobj::load_obj(path, &opts).map_err(|e| e.to_string())?;
    let mut mesh = TriMesh::default();
    for model in models {
        let base = mesh.positions.len() as u32;
        let pos = &model.mesh.positions;
        for p in pos.chunks_exact(3) {
            mesh.positions.push(Vec3A::new(p[0], p[1], p[2]));
        }
        for t in model.mesh.indices.chunks_exact(3) {
            mesh.triangles.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
#[allow(clippy::disallowed_methods)] // fixtures are written directly
mod tests {
    use super::*;

    const ASCII: &str = "ply\nformat ascii 1.0\ncomment test\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1\n1 0 0 1\n1 1 0 1\n0 1 0 1\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_becomes_two_triangles() {
        let m = parse_ply(ASCII.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions[2], Vec3A::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn binary_triangle_and_truncation() {
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
        for v in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 2.0, 0.0] {
            bytes.extend(v.to_le_bytes());
        }
        bytes.push(3);
        for i in [0u32, 1, 2] {
            bytes.extend(i.to_le_bytes());
        }
        let m = parse_ply(&bytes).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert_eq!(m.positions[2], Vec3A::new(0.0, 2.0, 0.0));
        let cut = &bytes[..bytes.len() - 2];
        assert!(parse_ply(cut).unwrap_err().contains("ends early"));
        assert!(parse_ply(b"hello").unwrap_err().contains("end_header"));
    }

    #[test]
    fn load_mesh_reads_obj_and_rejects_bad_files() {
        let dir = tempfile::tempdir().unwrap();
        let obj = dir.path().join("quad.obj");
        std::fs::write(&obj, "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nf 1 2 3 4\n").unwrap();
        let m = load_mesh(&obj).unwrap();
        assert_eq!(m.triangles.len(), 2);
        let r = m
            .positions
            .iter()
            .map(|p| p.length())
            .fold(0.0f32, f32::max);
        assert!((r - 1.0).abs() < 1e-6);

        let bad = dir.path().join("x.stl");
        std::fs::write(&bad, "solid").unwrap();
        assert!(
            load_mesh(&bad)
                .unwrap_err()
                .to_string()
                .contains("unknown mesh format")
        );
        let missing = dir.path().join("missing.obj");
        assert!(
            load_mesh(&missing)
                .unwrap_err()
                .to_string()
                .contains("missing.obj")
        );
    }
}
