//! The trainer's seeded generator: the workspace's one SplitMix64
//! ([`omnimvs_core::rng`]). Every epoch draws from its own stream,
//! [`SplitMix64::for_epoch`]`(seed, epoch)`, so a run resumed at an epoch boundary
//! makes the same choices as an uninterrupted one.

pub use omnimvs_core::rng::SplitMix64;
