//! The train/test split a generated dataset states in its `config.yaml`, so that the reference
//! implementation (hyu-cvlab/omnimvs-pytorch) trains and tests on it as it is.
//!
//! The reference's `Dataset` knows the published sets' splits by the dataset's name and takes
//! any other dataset's from the `dataset:` section of its `config.yaml` (`train_idx`,
//! `test_idx`, `gt_phi`, `dtype: gt`). A generated set follows the published set of its kind
//! frame by frame: frame `k` of a `things` set is a test frame when frame `k` of OmniThings is
//! (4097-5120), of a `house` set when frame `k` of OmniHouse is (2049-2560); every other frame
//! is a training frame. A set of the published size therefore has the published split, and a
//! smaller one (frames 1-1000, say) is all training frames, as the same frames of the
//! published set are.

use std::ops::RangeInclusive;

use omnimvs_data::{FrameRange, Split};

use crate::SceneKind;

/// OmniThings' test frames (train 1-4096 and 5121-10240).
pub const THINGS_TEST_FRAMES: RangeInclusive<u32> = 4097..=5120;
/// OmniHouse's test frames (train 1-2048).
pub const HOUSE_TEST_FRAMES: RangeInclusive<u32> = 2049..=2560;

/// The split of the frames `frames` of a generated dataset of `kind`, ground truth covering
/// `gt_phi_deg` degrees of latitude either side of the equator.
pub fn published_split(kind: SceneKind, frames: &FrameRange, gt_phi_deg: f64) -> Split {
    let test = match kind {
        SceneKind::Things => Some(THINGS_TEST_FRAMES),
        SceneKind::House => Some(HOUSE_TEST_FRAMES),
        // A custom scene cannot fill a dataset; no test frames if it ever does.
        SceneKind::Custom => None,
    };
    let (test_idx, train): (Vec<u32>, Vec<u32>) = frames
        .indices()
        .into_iter()
        .partition(|f| test.as_ref().is_some_and(|t| t.contains(f)));
    Split {
        train,
        test: test_idx,
        gt_phi_deg: Some(gt_phi_deg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn published_sizes_give_the_published_splits() {
        let things = published_split(SceneKind::Things, &FrameRange::inclusive(1, 10240), 90.0);
        assert_eq!(things.test, (4097..=5120).collect::<Vec<_>>());
        assert_eq!(things.train.len(), 4096 + 5120);
        assert_eq!((things.train[4095], things.train[4096]), (4096, 5121));
        let house = published_split(SceneKind::House, &FrameRange::inclusive(1, 2560), 90.0);
        assert_eq!(house.train, (1..=2048).collect::<Vec<_>>());
        assert_eq!(house.test, (2049..=2560).collect::<Vec<_>>());
    }

    #[test]
    fn a_small_set_is_split_as_the_same_frames_of_the_published_set() {
        let small = published_split(SceneKind::House, &FrameRange::inclusive(2001, 2100), 90.0);
        assert_eq!(small.train, (2001..=2048).collect::<Vec<_>>());
        assert_eq!(small.test, (2049..=2100).collect::<Vec<_>>());
        let first = published_split(SceneKind::Things, &FrameRange::inclusive(1, 4), 90.0);
        assert_eq!((first.train, first.test), (vec![1, 2, 3, 4], vec![]));
    }
}
