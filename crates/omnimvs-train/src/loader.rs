//! The loader thread: reads and prepares the samples of an epoch in order while the main
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

/// A running loader; dropping the receiver stops the thread after its current sample.
pub struct Loader {
    /// Prepared samples in plan order, with the plan item they belong to.
    pub samples: Receiver<(PlanItem, Result<Sample, TrainError>)>,
    handle: Option<JoinHandle<()>>,
}

impl Loader {
    /// Starts a thread that loads `plan` from `sources`, applying `photometric` (with each
    /// item's seed) when given.
    pub fn spawn(
        sources: Arc<Vec<SampleSource>>,
        plan: Vec<PlanItem>,
        prefetch: usize,
        photometric: Option<PhotometricAugment>,
    ) -> Self {
        let (tx, rx) = sync_channel(prefetch.max(1));
        let handle = std::thread::spawn(move || {
            for item in plan {
                let augment = photometric.as_ref().map(|p| (p, item.photometric_seed));
                let sample =
                    sources[item.source].load(item.source, item.frame, item.rotation, augment);
                if tx.send((item, sample)).is_err() {
                    break;
                }
            }
        });
        Self {
            samples: rx,
            handle: Some(handle),
        }
    }
}

impl Drop for Loader {
    fn drop(&mut self) {
        // Unblock a sender waiting on a full channel, then wait for the thread.
        let (_, rx) = sync_channel(1);
        drop(std::mem::replace(&mut self.samples, rx));
        if let Some(handle) = self.handle.take() {
            let _ = handle.join();
        }
    }
}
