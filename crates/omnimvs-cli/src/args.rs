//! Parsers for argument values shared by several subcommands.

use std::ops::RangeInclusive;

/// `HxW`, e.g. `160x640`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Size {
    pub height: usize,
    pub width: usize,
}

impl std::str::FromStr for Size {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || format!("expected HEIGHTxWIDTH such as 160x640, found {s:?}");
        let (h, w) = s.split_once(['x', 'X']).ok_or_else(bad)?;
        let height: usize = h.trim().parse().map_err(|_| bad())?;
        let width: usize = w.trim().parse().map_err(|_| bad())?;
        if height == 0 || width == 0 {
            return Err(bad());
        }
        Ok(Self { height, width })
    }
}

impl std::fmt::Display for Size {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.height, self.width)
    }
}

/// A frame range `A..B` (inclusive) or a single frame `A`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frames(pub RangeInclusive<u32>);

impl std::str::FromStr for Frames {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = || {
            format!(
                "expected a frame range such as 1..10 (inclusive) or a single frame, found {s:?}"
            )
        };
        let (a, b) = match s.split_once("..") {
            Some((a, b)) => (a, b.trim_start_matches('=')),
            None => (s, s),
        };
        let a: u32 = a.trim().parse().map_err(|_| bad())?;
        let b: u32 = b.trim().parse().map_err(|_| bad())?;
        if b < a {
            return Err(format!(
                "frame range {s:?} is reversed: the end ({b}) is before the start ({a})"
            ));
        }
        Ok(Self(a..=b))
    }
}

/// Help of every `--backend` option.
pub const BACKEND_HELP: &str = "Compute backend: cpu (burn flex, the default), libtorch, \
     libtorch-cuda[:N], wgpu[:N], vulkan or wgpu-cpu; all but cpu need a build with the \
     `libtorch` or `wgpu` Cargo feature (see the README)";

/// Parses a `--backend` value and checks that this build has it.
pub fn parse_backend(text: &str) -> Result<omnimvs_net::Backend, String> {
    let backend: omnimvs_net::Backend = text.parse().map_err(|e| format!("{e}"))?;
    backend.device().map_err(|e| format!("{e}"))?;
    Ok(backend)
}

/// Parses the path of an output file and checks, before any work is done, that its folder
/// exists (a report written after minutes of benchmarking must not fail then).
pub fn parse_output_file(text: &str) -> Result<std::path::PathBuf, String> {
    let path = std::path::PathBuf::from(text);
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => std::path::Path::new("."),
    };
    if path.file_name().is_none() || !folder.is_dir() {
        return Err(format!(
            "expected a file in an existing folder, but {} is not a folder",
            folder.display()
        ));
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_sizes_and_ranges() {
        assert_eq!(
            "160x640".parse::<Size>().unwrap(),
            Size {
                height: 160,
                width: 640
            }
        );
        assert!("160".parse::<Size>().is_err());
        assert!("0x640".parse::<Size>().is_err());
        assert_eq!("1..3".parse::<Frames>().unwrap().0, 1..=3);
        assert_eq!("7".parse::<Frames>().unwrap().0, 7..=7);
        assert!("5..2".parse::<Frames>().unwrap_err().contains("reversed"));
    }
}
