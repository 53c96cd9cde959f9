//! Build script shared by the crates that link libtorch (feature `libtorch`): it records the
//! directory of the libtorch shared libraries as an rpath, so that the binaries and tests find
//! them at run time without `LD_LIBRARY_PATH`. It also sets `OMNIMVS_VERSION`, the version
//! that `omnimvs --version` prints: the package's version, followed by the git revision when
//! the crate is built from a git checkout.
//!
//! The directory is `$LIBTORCH/lib` when `LIBTORCH` is set, otherwise the `lib` folder of the
//! PyTorch that the active Python imports (`python` inside `$VIRTUAL_ENV`, else `python3`),
//! the same interpreter that `torch-sys` asks when `LIBTORCH_USE_PYTORCH=1`.

use std::env;
use std::path::PathBuf;
use std::process::Command;

const PRINT_TORCH_LIB: &str =
    "import os, torch; print(os.path.join(os.path.dirname(torch.__file__), 'lib'))";

fn main() {
    version();
    println!("cargo:rerun-if-env-changed=LIBTORCH");
    println!("cargo:rerun-if-env-changed=VIRTUAL_ENV");
    println!("cargo:rerun-if-env-changed=LIBTORCH_USE_PYTORCH");
    if env::var_os("CARGO_FEATURE_LIBTORCH").is_none() {
        return;
    }
    match torch_lib_dir() {
        Ok(dir) => println!("cargo:rustc-link-arg=-Wl,-rpath,{}", dir.display()),
        Err(message) => println!(
            "cargo:warning=libtorch rpath not set ({message}); run with LD_LIBRARY_PATH pointing at torch/lib"
        ),
    }
}

fn torch_lib_dir() -> Result<PathBuf, String> {
    if let Some(libtorch) = env::var_os("LIBTORCH") {
        return Ok(PathBuf::from(libtorch).join("lib"));
    }
    let python = if env::var_os("VIRTUAL_ENV").is_some() {
        "python"
    } else {
        "python3"
    };
    let output = Command::new(python)
        .args(["-c", PRINT_TORCH_LIB])
        .output()
        .map_err(|e| format!("cannot run {python}: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "{python} cannot import torch: {}",
            String::from_utf8_lossy(&output.stderr).trim()
        ));
    }
    let dir = PathBuf::from(String::from_utf8_lossy(&output.stdout).trim());
    if dir.is_dir() {
        Ok(dir)
    } else {
        Err(format!("{} is not a directory", dir.display()))
    }
}

/// Sets `OMNIMVS_VERSION` to `VERSION` or `VERSION (REVISION)`, and asks to run again when the
/// checkout's HEAD moves.
fn version() {
    let version = env::var("CARGO_PKG_VERSION").unwrap_or_default();
    let git = |args: &[&str]| -> Option<String> {
        let output = Command::new("git").args(args).output().ok()?;
        let text = String::from_utf8(output.stdout).ok()?;
        (output.status.success() && !text.trim().is_empty()).then(|| text.trim().to_string())
    };
    let revision = git(&["rev-parse", "--short=10", "HEAD"]);
    if let Some(git_dir) = git(&["rev-parse", "--absolute-git-dir"]) {
        let git_dir = PathBuf::from(git_dir);
        println!("cargo:rerun-if-changed={}", git_dir.join("HEAD").display());
        println!(
            "cargo:rerun-if-changed={}",
            git_dir.join("packed-refs").display()
        );
        if let Some(head_ref) = git(&["symbolic-ref", "-q", "HEAD"]) {
            println!(
                "cargo:rerun-if-changed={}",
                git_dir.join(head_ref).display()
            );
        }
    }
    match revision {
        Some(rev) => println!("cargo:rustc-env=OMNIMVS_VERSION={version} ({rev})"),
        None => println!("cargo:rustc-env=OMNIMVS_VERSION={version}"),
    }
}
