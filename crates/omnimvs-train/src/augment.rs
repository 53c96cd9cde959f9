//! Rotation augmentation (paper, section 5.1): the rig frame is rotated by a small angle and
//! the ground truth is rotated to match.
//!
//! We sample the rotation from a fixed set drawn once from the seed (the identity first) and
//! precompute the sweep tables of every rotated rig when training starts, instead of
//! rebuilding a table per step: the tables are the expensive part and a handful of
//! rotations already decouples the network from one exact layout.

use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};
use omnimvs_camera::Rig;
#[cfg(doc)]
use omnimvs_data::gt::ground_truth_index;
use omnimvs_data::gt::{GroundTruth, InvDepthMap, sample_ground_truth};
use omnimvs_net::taps::SweepGrid;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, LookupTable, SphereSet};

use crate::error::TrainError;
use crate::rng::SplitMix64;

/// Small rotations `new_rig_from_rig`; index 0 is the identity.
#[derive(Clone, Debug, PartialEq)]
pub struct RotationSet {
    /// The rotations.
    pub rotations: Vec<Rotation3<f64>>,
}

impl RotationSet {
    /// The identity and `count - 1` rotations about uniformly random axes by angles uniform
    /// in `[0, max_deg]`, drawn from `seed`.
    pub fn new(count: usize, max_deg: f64, seed: u64) -> Self {
        let mut rng = SplitMix64::new(seed ^ 0x726f_7461_7465);
        let mut rotations = vec![Rotation3::identity()];
        while rotations.len() < count.max(1) {
            let axis = Vector3::new(
                rng.next_f64() * 2.0 - 1.0,
                rng.next_f64() * 2.0 - 1.0,
                rng.next_f64() * 2.0 - 1.0,
            );
            let norm = axis.norm();
            if !(0.1..=1.0).contains(&norm) {
                continue; // rejection sampling: uniform directions
            }
            let angle = rng.next_f64() * max_deg.to_radians();
            rotations.push(Rotation3::new(axis / norm * angle));
        }
        Self { rotations }
    }

    /// Number of rotations.
    pub fn len(&self) -> usize {
        self.rotations.len()
    }

    /// Whether the set is empty (never for a set built by [`RotationSet::new`]).
    pub fn is_empty(&self) -> bool {
        self.rotations.is_empty()
    }
}

/// The rig expressed in the rotated frame: `new_rig_from_cam = rotation * rig_from_cam`.
pub fn rotate_rig(rig: &Rig, new_rig_from_rig: &Rotation3<f64>) -> Rig {
    let rotation = Isometry3::from_parts(
        Translation3::identity(),
        UnitQuaternion::from_rotation_matrix(new_rig_from_rig),
    );
    let mut rotated = rig.clone();
    for camera in &mut rotated.cameras {
        camera.rig_from_cam = rotation * camera.rig_from_cam;
    }
    rotated
}

/// The network's sweep grids (every other sphere) of `rig` seen in the rotated frame, one
/// per camera.
///
/// # Errors
/// [`TrainError`] when the table cannot be built or split.
pub fn rotated_grids(
    rig: &Rig,
    rotation: &Rotation3<f64>,
    grid: &EquirectGrid,
    hypotheses: &InvDepthHypotheses,
) -> Result<Vec<SweepGrid>, TrainError> {
    let rotated = rotate_rig(rig, rotation);
    let table = LookupTable::build(&rotated, grid, hypotheses, SphereSet::EveryOther)?;
    Ok(SweepGrid::split_table(
        &table.data,
        rig.len(),
        table.num_spheres(),
        grid.height,
        grid.width,
    )?)
}

/// Ground truth on the output `grid` of the rig frame rotated by `new_rig_from_rig`: the
/// reference invalid rule of [`ground_truth_index`] applied to `map` (an equirectangular
/// inverse-depth map of the original frame, any size, `+-180 height / width` degrees) at its
/// own resolution, then each output ray `d` takes the nearest sample along `R^T d`
/// ([`sample_ground_truth`], the sampling evaluation uses too). Rays that leave `map`'s
/// latitude range are invalid.
///
/// # Errors
/// [`TrainError::Data`] for a degenerate map size.
pub fn resample_ground_truth(
    map: &InvDepthMap,
    grid: &EquirectGrid,
    new_rig_from_rig: &Rotation3<f64>,
    hypotheses: &InvDepthHypotheses,
) -> Result<GroundTruth, TrainError> {
    Ok(sample_ground_truth(
        map,
        hypotheses,
        grid,
        &new_rig_from_rig.inverse(),
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp_map(width: usize, height: usize) -> InvDepthMap {
        // Inverse depth grows with the column: a rotation about the vertical axis shifts it.
        let data = (0..height)
            .flat_map(|_| (0..width).map(move |c| 0.05 + 0.5 * c as f32 / width as f32))
            .collect();
        InvDepthMap {
            width,
            height,
            data,
        }
    }

    #[test]
    fn identity_resampling_subsamples_and_rotation_shifts_columns() {
        let hyps = InvDepthHypotheses::new(64, 0.5).unwrap();
        let map = ramp_map(640, 320);
        let grid = EquirectGrid::new(32, 128, 45.0).unwrap();
        let gt = resample_ground_truth(&map, &grid, &Rotation3::identity(), &hyps).unwrap();
        assert_eq!((gt.width, gt.height, gt.index.len()), (128, 32, 128 * 32));
        assert!(gt.valid.iter().all(|&v| v));
        // Same column of the output as column 5 * c of the source.
        let at = |gt: &GroundTruth, r: usize, c: usize| gt.index[r * 128 + c];
        let expected = hyps.index(f64::from(map.data[5 * 40])) as f32;
        assert!((at(&gt, 10, 40) - expected).abs() < 1e-4);
        // Rotating about the vertical (y) axis by one output column (2.8125 degrees) moves
        // the ground truth by one column, in one direction or the other.
        let yaw = Rotation3::new(Vector3::new(0.0, 360.0f64.to_radians() / 128.0, 0.0));
        let rotated = resample_ground_truth(&map, &grid, &yaw, &hyps).unwrap();
        let shifted = [39, 41]
            .iter()
            .any(|&c| (at(&rotated, 10, 40) - at(&gt, 10, c)).abs() < 1e-4);
        assert!(
            shifted,
            "{} vs {} / {}",
            at(&rotated, 10, 40),
            at(&gt, 10, 39),
            at(&gt, 10, 41)
        );
    }

    #[test]
    fn rotation_set_is_seeded_and_small() {
        let a = RotationSet::new(6, 5.0, 3);
        assert_eq!(a, RotationSet::new(6, 5.0, 3));
        assert_eq!(a.len(), 6);
        assert_eq!(a.rotations[0], Rotation3::identity());
        for r in &a.rotations {
            assert!(r.angle().to_degrees() <= 5.0 + 1e-9);
        }
        assert_ne!(a.rotations[1], a.rotations[2]);
    }
}
