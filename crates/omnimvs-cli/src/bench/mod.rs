//! The benchmarks of `omnimvs bench`: forward-pass time per stage, training-step time and
//! peak memory on synthetic inputs, for both network families. The paper's network runs on
//! a synthetic lookup table (`omnimvs_net::synthetic`); the cascade's forward pass and
//! training step run on a real rig (its per-pixel sampler needs camera models).

mod forward;
mod train_step;

use burn::tensor::{Device, Distribution, Tensor};
use omnimvs_net::NetConfig;

pub use forward::{
    BenchReport, CascadeBenchReport, ForwardOptions, bench_cascade_forward, bench_forward,
};
pub use train_step::{TrainStepReport, bench_cascade_train_step, bench_train_step};

/// The median of `f` over `runs` (the upper one for an even count); `runs` is not empty.
fn median_of<T>(runs: &[T], f: fn(&T) -> f64) -> f64 {
    let mut v: Vec<f64> = runs.iter().map(f).collect();
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The row of per-stage medians over `runs`, built by `row` from the median of a stage (a
/// field of a run); `None` for no run.
pub(crate) fn median_row<T, R>(
    runs: &[T],
    row: impl FnOnce(&dyn Fn(fn(&T) -> f64) -> f64) -> R,
) -> Option<R> {
    if runs.is_empty() {
        return None;
    }
    Some(row(&|f| median_of(runs, f)))
}

/// Peak resident set size of this process in bytes (`VmHWM`), `None` off Linux.
pub fn peak_rss_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Random `[1, 1, H_I, W_I]` images, one per camera.
pub(crate) fn random_images(config: &NetConfig, device: &Device) -> Vec<Tensor<4>> {
    (0..config.num_cameras)
        .map(|_| {
            Tensor::random(
                [1, 1, config.input_height, config.input_width],
                Distribution::Normal(0.0, 1.0),
                device,
            )
        })
        .collect()
}
