//! What the dataset tests share: a small rig and a folder's files as bytes. Included with
//! `#[path = "support/datasets.rs"] mod datasets;`.

#![allow(clippy::unwrap_used, clippy::disallowed_methods)] // helpers of tests

use std::collections::BTreeMap;
use std::path::Path;

use omnimvs_synth::rig::{RigSource, preset_rig, resize_rig};

/// The published rig with its images shrunk to 48x50, for fast datasets.
pub fn small_rig() -> RigSource {
    let p = preset_rig().unwrap();
    RigSource::new(resize_rig(&p.rig, 48, 50).unwrap(), p.min_depth_m)
}

/// Every file under `dir` (relative path -> bytes).
pub fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut out = BTreeMap::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
                out.insert(rel, std::fs::read(&p).unwrap());
            }
        }
    }
    out
}
