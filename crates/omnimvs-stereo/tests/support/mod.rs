//! Fixtures shared by the integration tests (and, by path, the examples and benchmarks).

pub mod scenes;
