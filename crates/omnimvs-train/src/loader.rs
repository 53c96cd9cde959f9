//! The loader threads: read and prepare the samples of an epoch in order while the main
//! thread runs the training steps, `prefetch` samples ahead.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, sync_channel};
use std::thread::JoinHandle;

use crate::error::TrainError;
use crate::photometric::PhotometricAugment;
use crate::sample::{Sample, SampleSource};

/// One item of an epoch's plan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PlanItem {
    /// Source (dataset) index.
    pub source: usize,
    /// Frame.
    pub frame: u32,
    /// Rotation index in the source's rotation set.
    pub rotation: usize,
    /// Cyclic shift of the camera order at the concatenation.
    pub shift: usize,
    /// First column of the training window of longitudes (0 without one).
    pub window_start: usize,
    /// Seed of the sample's photometric augmentation (0 without one).
    pub photometric_seed: u64,
}

/// A running loader; dropping it stops its threads after their current samples.
pub struct Loader {
    /// One channel per thread; item `i` of the plan comes from channel `i % threads`.
    channels: Vec<Receiver<(PlanItem, Result<Sample, TrainError>)>>,
    /// Items received so far (which channel is next).
    received: usize,
    handles: Vec<JoinHandle<()>>,
}

impl Loader {
    /// Starts `threads` threads (at least 1) that load `plan` from `sources`, applying
    /// `photometric` (with each item's seed) when given; thread `t` prepares items `t`,
    /// `t + threads`, ... up to `prefetch / threads` (at least 1) ahead, so the samples come
    /// out in plan order and each is what one thread would have made of it (a sample depends
    /// on its item alone). More than one thread is for a GPU, whose steps outrun one thread
    /// decoding four full-size images per step.
    pub fn spawn(
        sources: Arc<Vec<SampleSource>>,
        plan: Vec<PlanItem>,
        prefetch: usize,
        threads: usize,
        photometric: Option<PhotometricAugment>,
    ) -> Self {
        let threads = threads.max(1);
        let depth = prefetch.div_ceil(threads).max(1);
        let plan = Arc::new(plan);
        let mut channels = Vec::with_capacity(threads);
        let mut handles = Vec::with_capacity(threads);
        for thread in 0..threads {
            let (tx, rx) = sync_channel(depth);
            let (sources, plan, photometric) =
                (Arc::clone(&sources), Arc::clone(&plan), photometric.clone());
            handles.push(std::thread::spawn(move || {
                for item in plan.iter().skip(thread).step_by(threads) {
                    let augment = photometric.as_ref().map(|p| (p, item.photometric_seed));
                    let sample =
                        sources[item.source].load(item.source, item.frame, item.rotation, augment);
                    if tx.send((*item, sample)).is_err() {
                        break;
                    }
                }
            }));
            channels.push(rx);
        }
        Self {
            channels,
            received: 0,
            handles,
        }
    }
}

/// The samples in plan order; `None` after the last one (or when its thread ended).
impl Iterator for Loader {
    type Item = (PlanItem, Result<Sample, TrainError>);

    fn next(&mut self) -> Option<Self::Item> {
        let channel = &self.channels[self.received % self.channels.len()];
        let next = channel.recv().ok()?;
        self.received += 1;
        Some(next)
    }
}

impl Drop for Loader {
    fn drop(&mut self) {
        // Unblock the senders waiting on full channels, then wait for the threads.
        self.channels.clear();
        for handle in self.handles.drain(..) {
            let _ = handle.join();
        }
    }
}
