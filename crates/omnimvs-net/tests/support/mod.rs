//! Helpers shared by the integration tests.

#![allow(dead_code)] // each test file uses a part

use omnimvs_net::Backend;

/// The backends this build can test: `cpu` (flex) always, `libtorch` with the `libtorch`
/// feature, and the wgpu device named by `OMNIMVS_TEST_WGPU` (e.g. `wgpu-cpu` on Mesa's
/// lavapipe) with the `wgpu` feature.
pub fn test_backends() -> Vec<Backend> {
    let mut backends = vec![Backend::Cpu];
    if cfg!(feature = "libtorch") {
        backends.push(Backend::LibTorch);
    }
    if cfg!(feature = "wgpu")
        && let Ok(name) = std::env::var("OMNIMVS_TEST_WGPU")
    {
        backends.push(name.parse().expect("OMNIMVS_TEST_WGPU names a backend"));
    }
    backends
}
