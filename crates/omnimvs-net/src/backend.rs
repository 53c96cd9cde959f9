//! Run-time choice of the compute backend (`--backend`).
//!
//! One model implementation runs on every backend through burn's dispatch [`Device`]. The
//! default build has only `cpu` (burn's pure-Rust `flex`); Cargo features add the others:
//!
//! | name | feature | device |
//! |---|---|---|
//! | `cpu` (alias `flex`) | default | burn `flex`, the pure-Rust CPU engine |
//! | `libtorch` | `libtorch` | libtorch on the CPU |
//! | `libtorch-cuda[:N]` (alias `cuda[:N]`) | `libtorch` | libtorch on CUDA device `N` (default 0) |
//! | `wgpu[:N]` | `wgpu` | wgpu on discrete GPU `N`, or the best adapter without `:N` |
//! | `vulkan` | `wgpu` | wgpu pinned to Vulkan, best adapter |
//! | `wgpu-cpu` | `wgpu` | wgpu on a CPU adapter (e.g. Mesa's lavapipe), for tests |

use std::fmt;
use std::str::FromStr;

use burn::tensor::Device;

use crate::error::NetError;

/// A compute backend and, where it has several, the device.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    /// burn `flex`: pure Rust, multi-threaded CPU.
    Cpu,
    /// libtorch on the CPU.
    LibTorch,
    /// libtorch on a CUDA device.
    LibTorchCuda(usize),
    /// wgpu on a discrete GPU, or the best adapter (`None`).
    Wgpu(Option<usize>),
    /// wgpu pinned to Vulkan.
    Vulkan,
    /// wgpu on a CPU adapter.
    WgpuCpu,
}

impl Backend {
    /// The Cargo feature a backend needs, `None` for the default one.
    pub fn feature(self) -> Option<&'static str> {
        match self {
            Backend::Cpu => None,
            Backend::LibTorch | Backend::LibTorchCuda(_) => Some("libtorch"),
            Backend::Wgpu(_) | Backend::Vulkan | Backend::WgpuCpu => Some("wgpu"),
        }
    }

    /// Whether this build has the backend.
    pub fn is_available(self) -> bool {
        match self {
            Backend::Cpu => true,
            Backend::LibTorch | Backend::LibTorchCuda(_) => cfg!(feature = "libtorch"),
            Backend::Wgpu(_) | Backend::Vulkan | Backend::WgpuCpu => cfg!(feature = "wgpu"),
        }
    }

    /// The burn device of this backend.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] (field `backend`) when this build lacks the backend's
    /// Cargo feature.
    pub fn device(self) -> Result<Device, NetError> {
        if !self.is_available() {
            return Err(NetError::InvalidConfig {
                field: "backend",
                message: format!(
                    "`{self}` needs a build with `--features {}` (this build has {})",
                    self.feature().unwrap_or_default(),
                    available_names().join(", ")
                ),
            });
        }
        Ok(self.device_unchecked())
    }

    #[allow(unreachable_patterns, deprecated)]
    fn device_unchecked(self) -> Device {
        match self {
            #[cfg(feature = "libtorch")]
            Backend::LibTorch => Device::libtorch(),
            #[cfg(feature = "libtorch")]
            Backend::LibTorchCuda(index) => Device::libtorch_cuda(index),
            #[cfg(feature = "wgpu")]
            Backend::Wgpu(index) => Device::wgpu(match index {
                Some(i) => burn::tensor::DeviceKind::DiscreteGpu(i),
                None => burn::tensor::DeviceKind::DefaultDevice,
            }),
            #[cfg(feature = "wgpu")]
            Backend::Vulkan => Device::vulkan(burn::tensor::DeviceKind::DefaultDevice),
            #[cfg(feature = "wgpu")]
            Backend::WgpuCpu => Device::wgpu(burn::tensor::DeviceKind::Cpu),
            _ => Device::flex(),
        }
    }

    /// Whether the backend computes on a GPU.
    pub fn is_gpu(self) -> bool {
        matches!(
            self,
            Backend::LibTorchCuda(_) | Backend::Wgpu(_) | Backend::Vulkan
        )
    }
}

/// Every backend name this build accepts (the form of devices with an index: `cuda:0`).
pub fn available_names() -> Vec<&'static str> {
    let mut names = vec!["cpu"];
    if cfg!(feature = "libtorch") {
        names.extend(["libtorch", "libtorch-cuda[:N]"]);
    }
    if cfg!(feature = "wgpu") {
        names.extend(["wgpu[:N]", "vulkan", "wgpu-cpu"]);
    }
    names
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Backend::Cpu => write!(f, "cpu"),
            Backend::LibTorch => write!(f, "libtorch"),
            Backend::LibTorchCuda(i) => write!(f, "libtorch-cuda:{i}"),
            Backend::Wgpu(None) => write!(f, "wgpu"),
            Backend::Wgpu(Some(i)) => write!(f, "wgpu:{i}"),
            Backend::Vulkan => write!(f, "vulkan"),
            Backend::WgpuCpu => write!(f, "wgpu-cpu"),
        }
    }
}

impl FromStr for Backend {
    type Err = NetError;

    /// Parses a backend name; it does not check that this build has it (see
    /// [`Backend::device`]).
    fn from_str(text: &str) -> Result<Self, NetError> {
        let invalid = |message: String| NetError::InvalidConfig {
            field: "backend",
            message,
        };
        let lower = text.trim().to_ascii_lowercase();
        let (name, index) = match lower.split_once(':') {
            Some((name, index)) => {
                let index = index.parse::<usize>().map_err(|_| {
                    invalid(format!(
                        "`{text}`: the device index after `:` must be a number"
                    ))
                })?;
                (name, Some(index))
            }
            None => (lower.as_str(), None),
        };
        let backend = match (name, index) {
            ("cpu" | "flex", None) => Backend::Cpu,
            ("libtorch" | "tch", None) => Backend::LibTorch,
            ("libtorch-cuda" | "cuda", index) => Backend::LibTorchCuda(index.unwrap_or(0)),
            ("wgpu", index) => Backend::Wgpu(index),
            ("vulkan", None) => Backend::Vulkan,
            ("wgpu-cpu", None) => Backend::WgpuCpu,
            _ => {
                return Err(invalid(format!(
                    "unknown backend `{text}` (expected cpu, libtorch, libtorch-cuda[:N], \
                     wgpu[:N], vulkan or wgpu-cpu; this build has {})",
                    available_names().join(", ")
                )));
            }
        };
        Ok(backend)
    }
}

/// The device of a backend name (see [`Backend`]).
///
/// # Errors
/// [`NetError::InvalidConfig`] for an unknown name or a backend this build lacks.
pub fn device_from_name(name: &str) -> Result<Device, NetError> {
    name.parse::<Backend>()?.device()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for name in [
            "cpu",
            "libtorch",
            "libtorch-cuda:1",
            "wgpu",
            "wgpu:0",
            "vulkan",
            "wgpu-cpu",
        ] {
            let backend: Backend = name.parse().unwrap();
            assert_eq!(backend.to_string(), name);
        }
        assert_eq!("flex".parse::<Backend>().unwrap(), Backend::Cpu);
        assert_eq!("CUDA".parse::<Backend>().unwrap(), Backend::LibTorchCuda(0));
    }

    #[test]
    fn bad_names_are_explained() {
        let message = "gpu".parse::<Backend>().unwrap_err().to_string();
        assert!(message.contains("unknown backend `gpu`"), "{message}");
        let message = "cuda:x".parse::<Backend>().unwrap_err().to_string();
        assert!(message.contains("device index"), "{message}");
    }

    #[test]
    fn missing_features_are_explained() {
        if !cfg!(feature = "libtorch") {
            let message = device_from_name("libtorch").unwrap_err().to_string();
            assert!(message.contains("--features libtorch"), "{message}");
        }
        assert!(device_from_name("cpu").is_ok());
    }
}
