//! The whole method for one rig and output grid: normalise the images,
//! match (warp + ZNCC), aggregate (SGM), pick (WTA + parabola).

use std::sync::{Arc, Mutex, MutexGuard, PoisonError};
use std::time::{Duration, Instant};

use omnimvs_camera::{Rig, ValidityMask};
use omnimvs_core::GrayImage;
use omnimvs_sweep::SphereProjector;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses};
use serde::Serialize;

use crate::learned::{FeatureExtractor, feature_cost_volume};
use crate::sweepnet::{SweepCostHead, sweep_cost_volume};
use crate::{
    AggregatedVolume, CameraView, CostVolume, IndexMap, Matcher, SgmParams, StereoError,
    aggregate_in, winner_take_all,
};

/// Wall-clock time of each stage of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StageTimings {
    /// Normalising the gray images.
    pub prepare_s: f64,
    /// Projecting and sampling the images on all spheres (with a learned cost: the
    /// network's feature maps).
    pub warp_s: f64,
    /// Window sums, ZNCC, writing the cost volume.
    pub cost_s: f64,
    /// SGM over all paths.
    pub aggregation_s: f64,
    /// Winner-take-all, refinement, confidence.
    pub wta_s: f64,
    /// Everything.
    pub total_s: f64,
}

/// The result of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoResult {
    /// Fractional hypothesis index and confidence per output pixel.
    pub index: IndexMap,
    /// Inverse depth (1/m) per output pixel, row-major.
    pub inv_depth: Vec<f32>,
    pub timings: StageTimings,
}

/// Spherical-sweep ZNCC + SGM for one rig, output grid and hypotheses. The
/// per-rig preparation (projection tables) is done once in [`Self::new`].
#[derive(Debug, Clone)]
pub struct SphericalStereo {
    pub grid: EquirectGrid,
    pub hypotheses: InvDepthHypotheses,
    pub params: SgmParams,
    /// `(width, height)` of each camera's images.
    pub camera_sizes: Vec<(usize, usize)>,
    projectors: Vec<SphereProjector>,
    /// The learned matching cost; ZNCC when absent.
    learned: Option<LearnedCost>,
    /// Volume buffers kept from one frame to the next.
    buffers: Recycled,
}

/// Buffers of 16-bit volumes kept from one frame to the next: a fresh volume (39 MB at
/// 160x640x192) costs every frame its page faults and, when freed, its unmapping, several
/// times the cost of clearing a kept one. Clones of a [`SphericalStereo`] share them.
#[derive(Debug, Clone, Default)]
struct Recycled(Arc<Mutex<Vec<Vec<u16>>>>);

impl Recycled {
    /// Buffers kept at most: the cost volume and the aggregated one.
    const KEPT: usize = 2;

    fn lock(&self) -> MutexGuard<'_, Vec<Vec<u16>>> {
        // A panic elsewhere cannot leave a list of buffers half changed.
        self.0.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// A kept buffer (any content), or an empty one.
    fn take(&self) -> Vec<u16> {
        self.lock().pop().unwrap_or_default()
    }

    /// Keeps `buffer` for a later frame.
    fn give(&self, buffer: Vec<u16>) {
        let mut kept = self.lock();
        if kept.len() < Self::KEPT {
            kept.push(buffer);
        }
    }
}

/// A learned matching cost in place of ZNCC.
#[derive(Debug, Clone)]
pub enum LearnedCost {
    /// MC-CNN style: per-camera feature maps compared by cosine similarity.
    Features(Arc<dyn FeatureExtractor>),
    /// SweepNet style: a network on the warped images' windows of every sphere.
    Sweep(Arc<dyn SweepCostHead>),
}

impl LearnedCost {
    /// The method's name in reports.
    pub fn method_name(&self) -> &str {
        match self {
            Self::Features(f) => f.method_name(),
            Self::Sweep(h) => h.method_name(),
        }
    }
}

impl SphericalStereo {
    /// # Errors
    /// [`StereoError::TooFewCameras`] for a rig of fewer than two cameras,
    /// [`StereoError::NDepth`] for an odd number of hypotheses or fewer than
    /// two, [`StereoError::Penalties`] for `P2 < P1` and other bad penalties,
    /// [`StereoError::Volume`] for a grid narrower than the patch.
    pub fn new(
        rig: &Rig,
        grid: EquirectGrid,
        hypotheses: InvDepthHypotheses,
        params: SgmParams,
    ) -> Result<Self, StereoError> {
        if rig.len() < 2 {
            return Err(StereoError::TooFewCameras { found: rig.len() });
        }
        if hypotheses.count < 2 || !hypotheses.count.is_multiple_of(2) {
            return Err(StereoError::NDepth {
                found: hypotheses.count,
            });
        }
        params.validate()?;
        if grid.width <= params.patch || grid.height < 2 {
            return Err(StereoError::Volume(format!(
                "grid {}x{}: expected a width larger than the patch size {}",
                grid.height, grid.width, params.patch
            )));
        }
        let projectors = rig
            .cameras
            .iter()
            .enumerate()
            .map(|(i, c)| SphereProjector::new(c, i + 1, &grid))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            grid,
            hypotheses,
            params,
            camera_sizes: rig
                .cameras
                .iter()
                .map(|c| (c.model.width() as usize, c.model.height() as usize))
                .collect(),
            projectors,
            learned: None,
            buffers: Recycled::default(),
        })
    }

    /// The same method with a learned matching cost: `extractor`'s feature maps compared by
    /// cosine similarity instead of ZNCC (`None`: ZNCC).
    pub fn with_features(self, extractor: Option<Arc<dyn FeatureExtractor>>) -> Self {
        self.with_learned_cost(extractor.map(LearnedCost::Features))
    }

    /// The same method with a learned matching cost (`None`: ZNCC).
    pub fn with_learned_cost(mut self, learned: Option<LearnedCost>) -> Self {
        self.learned = learned;
        self
    }

    /// The learned matching cost, if any.
    pub fn learned_cost(&self) -> Option<&LearnedCost> {
        self.learned.as_ref()
    }

    /// Checks the images (and masks) against the rig and prepares them.
    fn views(
        &self,
        images: &[GrayImage],
        masks: Option<&[ValidityMask]>,
    ) -> Result<Vec<CameraView>, StereoError> {
        let ncam = self.camera_sizes.len();
        if images.len() != ncam {
            return Err(StereoError::CountMismatch {
                what: "images",
                expected: ncam,
                found: images.len(),
            });
        }
        if let Some(m) = masks
            && m.len() != ncam
        {
            return Err(StereoError::CountMismatch {
                what: "validity masks",
                expected: ncam,
                found: m.len(),
            });
        }
        for (i, (img, &(w, h))) in images.iter().zip(&self.camera_sizes).enumerate() {
            if img.width != w || img.height != h || img.data.len() != w * h {
                return Err(StereoError::SizeMismatch {
                    camera: i + 1,
                    what: "image",
                    found_w: img.width,
                    found_h: img.height,
                    want_w: w,
                    want_h: h,
                });
            }
        }
        use rayon::prelude::*;
        images
            .par_iter()
            .enumerate()
            .map(|(i, img)| CameraView::new(img, masks.map(|m| &m[i]), i + 1))
            .collect()
    }

    /// The cost volume of one frame (ZNCC or the learned cost) and the warp / cost times.
    ///
    /// # Errors
    /// As [`Self::compute`].
    pub fn cost_volume(
        &self,
        images: &[GrayImage],
        masks: Option<&[ValidityMask]>,
    ) -> Result<(CostVolume, StageTimings), StereoError> {
        let t0 = Instant::now();
        let views = self.views(images, masks)?;
        let prepare = t0.elapsed();
        // `warp`: the sampling of the images, or with a feature network the network itself.
        let (volume, warp, cost) = match &self.learned {
            Some(LearnedCost::Sweep(head)) => {
                let (volume, t) = sweep_cost_volume(
                    &self.grid,
                    &self.projectors,
                    &views,
                    head.as_ref(),
                    &self.hypotheses,
                    self.params.sweep,
                )?;
                (volume, t.warp, t.cost)
            }
            Some(LearnedCost::Features(extractor)) => {
                let t1 = Instant::now();
                let maps = extractor.features(images)?;
                let network = t1.elapsed();
                let (volume, t) = feature_cost_volume(
                    &self.grid,
                    &self.projectors,
                    &views,
                    &maps,
                    &self.hypotheses,
                    self.params.sweep,
                )?;
                (volume, network, t.cost)
            }
            None => {
                let matcher = Matcher {
                    grid: self.grid,
                    projectors: &self.projectors,
                    views: &views,
                    radius: self.params.patch / 2,
                };
                let (volume, t) = matcher.cost_volume_in(
                    &self.hypotheses,
                    self.params.sweep,
                    self.buffers.take(),
                )?;
                (volume, t.warp, t.cost)
            }
        };
        Ok((
            volume,
            StageTimings {
                prepare_s: prepare.as_secs_f64(),
                warp_s: warp.as_secs_f64(),
                cost_s: cost.as_secs_f64(),
                ..StageTimings::default()
            },
        ))
    }

    /// SGM and WTA on a cost volume.
    ///
    /// # Errors
    /// [`StereoError::Volume`] for a volume of another size.
    pub fn aggregate(
        &self,
        cost: &CostVolume,
    ) -> Result<(AggregatedVolume, Duration), StereoError> {
        let (g, n) = (&self.grid, self.hypotheses.count);
        if (cost.height, cost.width, cost.ndepth) != (g.height, g.width, n) {
            return Err(StereoError::Volume(format!(
                "volume {}x{}x{}: expected {}x{}x{n}",
                cost.height, cost.width, cost.ndepth, g.height, g.width
            )));
        }
        aggregate_in(cost, &self.params, self.buffers.take())
    }

    /// Inverse depth, index and confidence of one frame.
    ///
    /// `images` are the gray images of every camera (any intensity range;
    /// they are normalised over their valid pixels), `masks` the optional
    /// validity masks (pixels marked invalid are never sampled).
    ///
    /// # Errors
    /// [`StereoError::CountMismatch`] for a wrong number of images or masks,
    /// [`StereoError::SizeMismatch`] for an image or mask whose size differs
    /// from its camera's.
    pub fn compute(
        &self,
        images: &[GrayImage],
        masks: Option<&[ValidityMask]>,
    ) -> Result<StereoResult, StereoError> {
        let start = Instant::now();
        let (cost, mut timings) = self.cost_volume(images, masks)?;
        let (agg, aggregation) = self.aggregate(&cost)?;
        self.buffers.give(cost.data);
        let t = Instant::now();
        let mut index = winner_take_all(&agg);
        self.buffers.give(agg.data);
        if self.params.min_confidence > 0.0 {
            crate::filter::invalidate_below(&mut index, self.params.min_confidence);
        }
        if self.params.median > 1 {
            index.index = crate::filter::median_filter(&index, self.params.median);
        }
        let inv_depth = index
            .index
            .iter()
            .map(|&n| self.hypotheses.inv_depth(f64::from(n)) as f32)
            .collect();
        timings.wta_s = t.elapsed().as_secs_f64();
        timings.aggregation_s = aggregation.as_secs_f64();
        timings.total_s = start.elapsed().as_secs_f64();
        Ok(StereoResult {
            index,
            inv_depth,
            timings,
        })
    }
}
