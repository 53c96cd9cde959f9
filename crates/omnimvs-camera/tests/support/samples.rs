//! Where tests find the reference samples: `../shared/data/omnimvs-samples` beside the
//! repository (never copied into it). A test that needs them and does not find them fails
//! with a message that says what is missing and where it was looked for, not with an
//! unrelated error from deeper down. Included by the tests of several crates with
//! `#[path = "../../omnimvs-camera/tests/support/samples.rs"] mod samples;`.

// Each including test uses some of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// What holds the samples, as seen from the repository root.
const SAMPLES: &str = "../shared/data/omnimvs-samples";

/// The samples folder; panics naming where it was looked for when it is absent.
pub fn samples() -> PathBuf {
    // Every crate is at crates/<name>, so the repository root is two folders up.
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(SAMPLES);
    assert!(
        dir.is_dir(),
        "the reference samples are missing: this test reads {SAMPLES} (seen from the \
         repository root; looked for at {}); put the shared data beside the repository",
        dir.display()
    );
    dir
}

/// The sample dataset `name` (`sunny_single`, `itbt_sample`); panics naming the missing
/// `config.yaml` when the folder is absent or incomplete.
pub fn sample(name: &str) -> PathBuf {
    let dir = samples().join(name);
    let config = dir.join("config.yaml");
    assert!(
        config.is_file(),
        "the reference sample `{name}` is missing: this test reads {SAMPLES}/{name}/config.yaml \
         (looked for at {})",
        config.display()
    );
    dir
}

/// The `config.yaml` of the sample dataset `name`, checked as [`sample`] does.
pub fn sample_config(name: &str) -> PathBuf {
    sample(name).join("config.yaml")
}
