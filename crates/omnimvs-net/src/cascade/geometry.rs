//! The geometry of a cascade forward pass: the taps of each stage on the device, built from
//! the per-pixel sampler of a rig, and the forward pass that moves from one stage to the next
//! (each stage's estimate is read back to build the next stage's hypotheses, which carry no
//! gradient, as in CasMVSNet).

use std::ops::Range;
use std::time::Instant;

use burn::tensor::activation::softmax;
use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_camera::Rig;
use omnimvs_core::interp::BilinearTap;
use omnimvs_sweep::{EquirectGrid, InvDepthHypotheses, resample_map};

use super::model::{CascadeNet, StageOutput, UPSAMPLE_TAPS, bilinear_prior, upsampling_candidates};
use super::photo::{ImagePyramid, aggregated_cue};
use super::sampler::{coarse_indices, hypotheses_around};
use crate::config::NetConfig;
use crate::error::NetError;
use crate::model::SweepTaps;
use crate::pixel::PixelSampler;
use crate::taps::{SweepGrid, grid_taps};
use crate::tensor::{hypothesis_tensor, read_values};
use rayon::prelude::*;

/// One stage's sampling positions on the device: every camera's taps, the hypotheses, and
/// how many cameras (and camera pairs) see each sample.
#[derive(Clone, Debug)]
pub struct StageTaps {
    /// Taps of every camera into its feature map.
    pub cameras: Vec<SweepTaps>,
    /// Hypothesis index (`N` units) of every sample `[1, K, H, W]`.
    pub hypotheses: Tensor<4>,
    /// Share of the cameras that see each sample (bilinear weight sum) `[1, 1, K, H, W]`.
    pub visibility: Tensor<5>,
    /// Number of camera pairs that see each sample `[1, 1, K, H, W]`.
    pub pair_count: Tensor<5>,
    /// The previous stage's estimate on this stage's grid `[1, H, W]` (`N` units), around
    /// which a refinement stage's hypotheses lie; `None` for the coarse stage.
    pub center: Option<Tensor<3>>,
    /// The taps on the host, for the inference-only correlation kernel
    /// ([`super::host::correlation`]); `cameras` is then empty. `None`: the device taps.
    pub host: Option<HostTaps>,
    /// The photometric cue at the samples `[1, 1, K, H, W]` ([`super::photo`]) of a
    /// refinement stage of a network with `zncc_cue`; `None` otherwise (the coarse stage's
    /// taps serve every frame, its cue is made per frame by [`CascadeGeometry::coarse_cue`]).
    pub cue: Option<Tensor<5>>,
}

/// A stage's taps on the host: what the host correlation kernel reads (no gradient).
#[derive(Clone, Debug)]
pub struct HostTaps {
    /// Taps of every camera into its feature map, flat over `[K, H, W]`.
    pub cameras: Vec<Vec<BilinearTap>>,
    /// Size `[rows, cols]` of the feature maps the taps index into.
    pub feature_size: [usize; 2],
    /// Number of camera pairs that see each sample, flat over `[K, H, W]`.
    pub pair_count: Vec<f32>,
    /// Share of the cameras that see each sample, flat over `[K, H, W]`.
    pub visibility: Vec<f32>,
}

impl StageTaps {
    /// Taps of `grids` (one per camera, `K` "spheres" each) into feature maps of
    /// `feature_size`, with the hypotheses `index` (`[K, H * W]`); on the host when `host`
    /// (inference on a CPU backend, see [`HostTaps`]), else on `device`.
    ///
    /// # Errors
    /// [`NetError::Shape`] when there is no camera or the grids disagree in size.
    pub fn new(
        grids: &[SweepGrid],
        index: Vec<f32>,
        feature_size: [usize; 2],
        host: bool,
        device: &Device,
    ) -> Result<Self, NetError> {
        let Some(first) = grids.first() else {
            return Err(NetError::Shape {
                what: "cameras of a cascade stage".into(),
                expected: vec![1],
                actual: vec![0],
            });
        };
        let (k, h, w) = (first.num_spheres, first.height, first.width);
        let samples = k * h * w;
        if index.len() != samples || grids.iter().any(|g| g.coords.len() != 2 * samples) {
            return Err(NetError::Shape {
                what: "cascade stage grids".into(),
                expected: vec![k, h, w],
                actual: vec![index.len()],
            });
        }
        let camera_taps: Vec<Vec<BilinearTap>> = grids
            .iter()
            .map(|grid| grid_taps(grid, feature_size[0], feature_size[1]))
            .collect();
        // The share of each sample's taps inside the feature maps, summed over the cameras
        // in their order, and the sum of its squares (in parallel over the samples).
        let mut count = vec![0f32; samples];
        let mut count_sq = vec![0f32; samples];
        count
            .par_iter_mut()
            .zip(count_sq.par_iter_mut())
            .enumerate()
            .for_each(|(s, (c, c2))| {
                for taps in &camera_taps {
                    let seen: f32 = taps[s].weight.iter().sum();
                    *c += seen;
                    *c2 += seen * seen;
                }
            });
        let (cameras, host_cameras) = if host {
            (Vec::new(), camera_taps)
        } else {
            let cameras = camera_taps
                .iter()
                .zip(grids)
                .map(|(taps, grid)| SweepTaps::from_taps(taps, grid, feature_size, device))
                .collect();
            (cameras, Vec::new())
        };
        let pairs: Vec<f32> = count
            .iter()
            .zip(&count_sq)
            .map(|(c, c2)| (c * c - c2) / 2.0)
            .collect();
        let share = 1.0 / grids.len() as f32;
        let visibility: Vec<f32> = count.iter().map(|c| c * share).collect();
        let host = host.then(|| HostTaps {
            cameras: host_cameras,
            feature_size,
            pair_count: pairs.clone(),
            visibility: visibility.clone(),
        });
        let volume =
            |data: Vec<f32>| Tensor::<5>::from_data(TensorData::new(data, [1, 1, k, h, w]), device);
        Ok(Self {
            cameras,
            hypotheses: hypothesis_tensor(index, k, h, w, device),
            visibility: volume(visibility),
            pair_count: volume(pairs),
            center: None,
            host,
            cue: None,
        })
    }

    /// Number of cameras the taps sample.
    pub fn num_cameras(&self) -> usize {
        match &self.host {
            Some(host) => host.cameras.len(),
            None => self.cameras.len(),
        }
    }

    /// Number of hypotheses `K`.
    pub fn num_hypotheses(&self) -> usize {
        self.hypotheses.dims()[1]
    }

    /// Rows of the stage's grid.
    pub fn height(&self) -> usize {
        self.hypotheses.dims()[2]
    }

    /// Columns of the stage's grid.
    pub fn width(&self) -> usize {
        self.hypotheses.dims()[3]
    }
}

/// Everything a cascade forward pass needs about one rig (one rotation of it, in training):
/// the coarse stage's fixed taps and the per-pixel samplers of the two refinement grids.
#[derive(Clone, Debug)]
pub struct CascadeGeometry {
    /// The coarse stage's taps (fixed spheres).
    pub coarse: StageTaps,
    /// Samplers of the coarse, half- and full-resolution grids.
    pub samplers: [PixelSampler; 3],
    /// The `N` hypotheses.
    pub hypotheses: InvDepthHypotheses,
    /// The network configuration it was built for.
    pub config: NetConfig,
    /// Device of the taps.
    pub device: Device,
    /// Whether the stages correlate on the host (inference on a CPU backend, no gradient:
    /// [`CascadeGeometry::with_host_correlation`]) or through device tensors (training, GPUs).
    pub host_correlation: bool,
    /// The photometric cue's sample positions for the coarse stage, one grid per camera,
    /// when the network has the cue (`zncc_cue`; empty otherwise): the coarse stage's own
    /// samples, or with `coarse_cue_oversample` 2 those of the half-resolution grid at the
    /// same spheres.
    pub coarse_grids: Vec<SweepGrid>,
    /// The inverse depth (index units) of each plane of `coarse_grids`
    /// ([`coarse_cue_spheres`]), which the aggregated cue (`coarse_cue_sgm`) orders them by.
    pub coarse_cue_depths: Vec<f64>,
}

impl CascadeGeometry {
    /// The geometry of `rig` for `config` (a cascade configuration) on `device`.
    ///
    /// # Errors
    /// [`NetError`] for a rig whose camera count differs from the configuration's or an
    /// invalid grid.
    pub fn new(
        rig: &Rig,
        config: &NetConfig,
        hypotheses: &InvDepthHypotheses,
        device: &Device,
    ) -> Result<Self, NetError> {
        Self::with_host_correlation(rig, config, hypotheses, device, false)
    }

    /// [`CascadeGeometry::new`], with every stage's correlation in one host kernel over the
    /// taps when `host_correlation` ([`super::host::correlation`]: the same values, no
    /// gradient, a fraction of the memory traffic of the tensor ops). For inference on CPU
    /// backends; training needs the tensor path (`false`).
    ///
    /// # Errors
    /// As [`CascadeGeometry::new`].
    pub fn with_host_correlation(
        rig: &Rig,
        config: &NetConfig,
        hypotheses: &InvDepthHypotheses,
        device: &Device,
        host_correlation: bool,
    ) -> Result<Self, NetError> {
        config.validate()?;
        config.check_cameras(rig.len(), "the rig")?;
        let grids = config
            .cascade_sizes()
            .map(|[h, w]| EquirectGrid::new(h, w, config.phi_deg));
        let [g0, g1, g2] = grids;
        let [s0, s1, s2] = [g0?, g1?, g2?].map(|g| PixelSampler::new(rig, &g, hypotheses));
        let samplers = [s0?, s1?, s2?];
        let spheres = coarse_indices(config.cascade.coarse_spheres, config.num_invdepth);
        let coarse_grids = samplers[0].sphere_grids(&spheres)?;
        let plane = samplers[0].grid().len();
        let index: Vec<f32> = spheres
            .iter()
            .flat_map(|&n| std::iter::repeat_n(n as f32, plane))
            .collect();
        let feature_sizes = config.cascade_feature_sizes();
        let coarse = StageTaps::new(
            &coarse_grids,
            index,
            feature_sizes[2],
            host_correlation,
            device,
        )?;
        let p = &config.cascade;
        let cue_spheres = coarse_cue_spheres(&spheres, p.coarse_cue_depths, config.num_invdepth);
        let cue_grids = match (p.zncc_cue, p.coarse_cue_oversample, p.coarse_cue_depths) {
            (false, _, _) => Vec::new(),
            (true, 1, 1) => coarse_grids,
            (true, 1, _) => samplers[0].sphere_grids(&cue_spheres)?,
            // The half-resolution grid's samples at the coarse spheres (or around them).
            (true, _, _) => samplers[1].sphere_grids(&cue_spheres)?,
        };
        Ok(Self {
            coarse,
            samplers,
            hypotheses: *hypotheses,
            config: config.clone(),
            device: device.clone(),
            host_correlation,
            coarse_grids: cue_grids,
            coarse_cue_depths: cue_spheres,
        })
    }

    /// The photometric cue of the coarse stage for one frame's `images`, `[1, C, K, H, W]`
    /// with `C` 1, or 2 with the aggregated cue (`coarse_cue_sgm`,
    /// [`super::photo::aggregated_cue`]) after the ZNCC one; `None` when the network has none.
    ///
    /// # Errors
    /// [`NetError::Shape`] when the images are not one per camera of the rig.
    pub fn coarse_cue(&self, images: Option<&ImagePyramid>) -> Result<Option<Tensor<5>>, NetError> {
        let Some(pyramid) = images else {
            return Ok(None);
        };
        let p = &self.config.cascade;
        let (factor, depths) = (p.coarse_cue_oversample, p.coarse_cue_depths);
        // Matched on its grid (images of the matching level: the quarter-size ones for the
        // coarse grid itself, the half-size ones for the half grid), each coarse pixel the mean
        // of its factor x factor block (itself for factor 1); then each sphere the best of its
        // depths. `zncc` refuses an empty set of grids, so there is a first one after it.
        let level = (2 - factor.trailing_zeros()) as usize;
        let fine = pyramid.zncc(level, &self.coarse_grids)?;
        let first = &self.coarse_grids[0];
        let (planes, h, w) = (first.num_spheres, first.height, first.width);
        let (ch, cw) = (h / factor, w / factor);
        let scale = 1.0 / (factor * factor) as f32;
        let mut pooled = vec![0f32; planes * ch * cw];
        for (plane, out) in fine
            .chunks_exact(h * w)
            .zip(pooled.chunks_exact_mut(ch * cw))
        {
            for (r, row) in plane.chunks_exact(w).enumerate() {
                let dst = &mut out[(r / factor) * cw..(r / factor + 1) * cw];
                for (c, value) in row.iter().enumerate() {
                    dst[c / factor] += value * scale;
                }
            }
        }
        let k = planes / depths;
        let plane = ch * cw;
        let mut coarse = pooled[..k * plane].to_vec();
        for d in 1..depths {
            let other = &pooled[d * k * plane..(d + 1) * k * plane];
            for (best, value) in coarse.iter_mut().zip(other) {
                *best = best.max(*value);
            }
        }
        let mut channels = 1;
        if p.coarse_cue_sgm {
            coarse.extend(aggregated_cue(
                &pooled,
                &self.coarse_cue_depths,
                k,
                [ch, cw],
            )?);
            channels = 2;
        }
        Ok(Some(Tensor::from_data(
            TensorData::new(coarse, [1, channels, k, ch, cw]),
            &self.device,
        )))
    }

    /// The taps of refinement stage `stage` (1: half, 2: full resolution) around `previous`,
    /// an index map (`N` units) on the previous stage's whole grid, for the stage's columns
    /// `cols` (all of them, or a training window); with the frame's `images`, the photometric
    /// cue at the taps' samples too.
    ///
    /// # Errors
    /// [`NetError::Shape`] for a map of another size or a window outside the grid.
    pub fn refine_taps(
        &self,
        stage: usize,
        previous: &[f32],
        cols: Range<usize>,
        images: Option<&ImagePyramid>,
    ) -> Result<StageTaps, NetError> {
        let from = self.samplers[stage - 1].grid();
        if previous.len() != from.len() {
            return Err(NetError::Shape {
                what: "previous stage's index map".into(),
                expected: vec![from.height, from.width],
                actual: vec![previous.len()],
            });
        }
        let sampler = &self.samplers[stage];
        let center = crop_columns(
            &resample_map(previous, from, sampler.grid()),
            sampler.grid(),
            &cols,
        )?;
        self.taps_around(stage, center, cols, images)
    }

    /// The taps of refinement stage `stage` around `center`, an index map (`N` units) already
    /// on the stage's grid, its columns `cols` only (row-major, `rows x cols.len()`).
    ///
    /// # Errors
    /// [`NetError::Shape`] for a map of another size or a window outside the grid.
    pub fn taps_around(
        &self,
        stage: usize,
        center: Vec<f32>,
        cols: Range<usize>,
        images: Option<&ImagePyramid>,
    ) -> Result<StageTaps, NetError> {
        let sampler = &self.samplers[stage];
        let expected = sampler.grid().height * cols.len();
        if center.len() != expected {
            return Err(NetError::Shape {
                what: "centres of a refinement stage's hypotheses".into(),
                expected: vec![sampler.grid().height, cols.len()],
                actual: vec![center.len()],
            });
        }
        let p = &self.config.cascade;
        let k = p.stage_hypotheses[stage - 1];
        let index = hypotheses_around(
            &center,
            k,
            p.stage_intervals[stage - 1],
            self.config.num_invdepth,
        );
        let mut taps = self.taps_for(stage, index, k, cols.clone(), images)?;
        let [h, w] = [sampler.grid().height, cols.len()];
        taps.center = Some(Tensor::<3>::from_data(
            TensorData::new(center, [1, h, w]),
            &self.device,
        ));
        Ok(taps)
    }

    /// The taps of refinement stage `stage` at `k` given inverse-depth indices per pixel
    /// (`index[j * pixels + pixel]`, `N` units) over its columns `cols`, without a centre:
    /// the candidates of the learnt upsampling, say.
    ///
    /// # Errors
    /// [`NetError::Shape`] for indices of another size or a window outside the grid.
    pub fn taps_for(
        &self,
        stage: usize,
        index: Vec<f32>,
        k: usize,
        cols: Range<usize>,
        images: Option<&ImagePyramid>,
    ) -> Result<StageTaps, NetError> {
        let sampler = &self.samplers[stage];
        let grids = sampler.grids_window(&index, k, cols)?;
        // Stage 1 reads the stride-4 features, stage 2 the stride-2 ones.
        let feature_size = self.config.cascade_feature_sizes()[2 - stage];
        let mut taps = StageTaps::new(
            &grids,
            index,
            feature_size,
            self.host_correlation,
            &self.device,
        )?;
        // Stage 1 samples the half-size images, stage 2 the inputs themselves.
        taps.cue = images
            .map(|pyramid| pyramid.zncc_tensor(2 - stage, &grids, &self.device))
            .transpose()?;
        Ok(taps)
    }
}

/// A window of longitudes for training on part of the panorama (the paper's grid is a
/// circle; a window cuts the refinement stages' cost in proportion), in columns of the
/// full-resolution grid. The coarse stage always sees the whole panorama.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ColumnWindow {
    /// First column (full resolution, even).
    pub start: usize,
    /// Number of columns (full resolution, even).
    pub width: usize,
}

impl ColumnWindow {
    /// The window's columns on a grid `factor` times coarser (2 for the half-resolution
    /// stage).
    pub fn scaled(&self, factor: usize) -> Range<usize> {
        self.start / factor..(self.start + self.width) / factor
    }

    /// Checks that the window fits a full-resolution grid of `width` columns and halves
    /// exactly.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] naming what is wrong.
    pub fn check(&self, width: usize) -> Result<(), NetError> {
        if self.width < 2
            || !self.start.is_multiple_of(2)
            || !self.width.is_multiple_of(2)
            || self.start + self.width > width
        {
            return Err(NetError::InvalidConfig {
                field: "column_window",
                message: format!(
                    "columns {}..{} must be an even start and an even width (at least 2) inside \
                     the {width} columns of the output",
                    self.start,
                    self.start + self.width
                ),
            });
        }
        Ok(())
    }
}

/// The columns `cols` of a row-major map on `grid`.
///
/// # Errors
/// [`NetError::Shape`] for columns outside the grid.
pub fn crop_columns(
    map: &[f32],
    grid: &EquirectGrid,
    cols: &Range<usize>,
) -> Result<Vec<f32>, NetError> {
    if cols.end > grid.width || cols.is_empty() || map.len() != grid.len() {
        return Err(NetError::Shape {
            what: "column window of a map".into(),
            expected: vec![grid.height, grid.width],
            actual: vec![map.len(), cols.start, cols.end],
        });
    }
    Ok(map
        .chunks_exact(grid.width)
        .flat_map(|row| row[cols.clone()].iter().copied())
        .collect())
}

/// The inverse depths (index units) the coarse cue is matched at: with `depths` 1 the coarse
/// spheres; otherwise `depths` blocks of them, block `d` every sphere offset by a multiple of
/// `spacing / depths` within `0..=N-1` (offsets 0, -1, +1, -2, +2 times that, so the first
/// `K` planes are the spheres themselves).
pub fn coarse_cue_spheres(spheres: &[f64], depths: usize, num_invdepth: usize) -> Vec<f64> {
    if depths <= 1 || spheres.len() < 2 {
        return spheres.to_vec();
    }
    let spacing = spheres[1] - spheres[0];
    let half = (depths - 1) / 2;
    let last = (num_invdepth - 1) as f64;
    let offsets = std::iter::once(0.0).chain((1..=half).flat_map(|j| {
        let o = j as f64 * spacing / depths as f64;
        [-o, o]
    }));
    offsets
        .flat_map(|o| spheres.iter().map(move |&n| (n + o).clamp(0.0, last)))
        .collect()
}

/// Smallest batch of images the feature pyramid trains on (see
/// [`CascadeNet::forward_window`]).
pub const MIN_TRAINING_BATCH: usize = 5;

/// Wall time of each stage of a cascade forward pass in seconds (measured only when asked,
/// see [`CascadeNet::forward_timed`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CascadeTimings {
    /// Feature pyramids of all cameras.
    pub features: f64,
    /// Coarse cost volume, regularisation and soft argmax.
    pub coarse: f64,
    /// Half-resolution hypotheses (host) and stage.
    pub mid: f64,
    /// Full-resolution hypotheses (host) and stage.
    pub fine: f64,
    /// Whole forward pass.
    pub total: f64,
}

/// How [`CascadeNet::forward_seeded`] turns its two half-resolution runs into one answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SeedChoice {
    /// One soft argmax over both runs' hypotheses together (their gates unused).
    Joint,
    /// Per pixel, the run whose distribution has the higher peak.
    Peak,
    /// Per pixel, the run with the larger log-sum-exp of its scores.
    Mass,
}

/// `log(sum(exp(scores)))` over the hypotheses of `[B, K, H, W]` scores: `[B, H, W]`.
fn logsumexp(scores: Tensor<4>) -> Tensor<3> {
    let max = scores.clone().max_dim(1); // [B, 1, H, W]
    ((scores - max.clone()).exp().sum_dim(1).log() + max).squeeze_dim(1)
}

/// The three stages' results: coarse, half and full resolution.
#[derive(Clone, Debug)]
pub struct CascadeOutput {
    /// Coarse, half- and full-resolution stages.
    pub stages: [StageOutput; 3],
    /// With learnt upsampling (`convex_upsampling`): the half- and full-resolution stages'
    /// centres as the heads made them, `[1, H, W]` over the stage's columns (the training
    /// window's), differentiable in the heads' weights; `None` where the centres were
    /// upsampled bilinearly.
    pub upsampled: [Option<Tensor<3>>; 2],
}

impl CascadeNet {
    /// Forward pass over every camera's image `[B, 1, H_I, W_I]` (rig order), differentiable
    /// with respect to the weights within each stage.
    ///
    /// # Errors
    /// [`NetError`] for inputs that do not fit the network or the geometry.
    pub fn forward(
        &self,
        images: &[Tensor<4>],
        geometry: &CascadeGeometry,
    ) -> Result<CascadeOutput, NetError> {
        self.forward_timed(images, geometry, false)
            .map(|(out, _)| out)
    }

    /// [`CascadeNet::forward`], with each stage's wall time when `timed` (which waits for the
    /// device after every stage).
    ///
    /// # Errors
    /// See [`CascadeNet::forward`].
    pub fn forward_timed(
        &self,
        images: &[Tensor<4>],
        geometry: &CascadeGeometry,
        timed: bool,
    ) -> Result<(CascadeOutput, CascadeTimings), NetError> {
        self.forward_window(images, geometry, None, timed, false)
    }

    /// [`CascadeNet::forward_timed`] with the refinement stages on a window of longitudes
    /// only (`None`: the whole panorama); their outputs then cover the window's columns.
    ///
    /// All cameras go through the feature pyramid as one batch. With `training`, a batch of
    /// fewer than [`MIN_TRAINING_BATCH`] images is padded with copies of the first one (their
    /// features are dropped): burn-flex computes a convolution's weight gradient as a
    /// convolution whose input channels are the batch, and below 5 of them, with at most 16
    /// output channels, it takes a direct path with the whole output map as the kernel, 2-3
    /// times slower per image than with 5 (the `conv_grad_bench` study,
    /// `research/study-programs.md`).
    ///
    /// # Errors
    /// See [`CascadeNet::forward`]; a window that does not fit the grid.
    pub fn forward_window(
        &self,
        images: &[Tensor<4>],
        geometry: &CascadeGeometry,
        window: Option<ColumnWindow>,
        timed: bool,
        training: bool,
    ) -> Result<(CascadeOutput, CascadeTimings), NetError> {
        self.forward_centred(
            images,
            geometry,
            window,
            timed,
            training,
            None::<fn(&[f32]) -> _>,
        )
    }

    /// [`CascadeNet::forward`] with the refinement stages centred where `centres` says: it
    /// gets the coarse stage's index map (`N` units, on the coarse grid, row-major) and
    /// returns the map, same grid, around which the half-resolution stage places its
    /// hypotheses. What a caller can learn with it: how far the refinement stages carry
    /// another method's answer (a classical seed such as ZNCC+SGM's, resampled to the coarse
    /// grid), or an oracle's. The coarse stage's own output stays in the result.
    ///
    /// # Errors
    /// See [`CascadeNet::forward`]; what `centres` returns, and a map of another size.
    pub fn forward_with_centres(
        &self,
        images: &[Tensor<4>],
        geometry: &CascadeGeometry,
        centres: impl FnOnce(&[f32]) -> Result<Vec<f32>, NetError>,
    ) -> Result<CascadeOutput, NetError> {
        self.forward_centred(images, geometry, None, false, false, Some(centres))
            .map(|(out, _)| out)
    }

    /// [`CascadeNet::forward`] with the half-resolution stage run twice, with the same
    /// weights: around the coarse stage's answer and around `seed` (an index map in `N` units
    /// on the coarse grid, another method's answer); `choice` says how the two become the
    /// centres of the full-resolution stage. The result's half-resolution stage is the run
    /// around the coarse answer when `choice` picks per pixel. Both stages' centres are
    /// upsampled bilinearly, whether or not the network has learnt upsampling.
    ///
    /// # Errors
    /// See [`CascadeNet::forward`]; a seed of another size.
    pub fn forward_seeded(
        &self,
        images: &[Tensor<4>],
        geometry: &CascadeGeometry,
        seed: &[f32],
        choice: SeedChoice,
    ) -> Result<CascadeOutput, NetError> {
        let (levels, photo) = self.feature_levels(images, false)?;
        let coarse = self.coarse_of(&levels, photo.as_ref(), geometry)?;
        let coarse_index = read_values(coarse.index.clone(), "coarse index")?;
        let mid_grid = *geometry.samplers[1].grid();
        let cols = 0..mid_grid.width;
        let run = |centres: &[f32]| -> Result<_, NetError> {
            let taps = geometry.refine_taps(1, centres, cols.clone(), photo.as_ref())?;
            let (scores, gate) = self.refine_scores(1, &levels[1], &taps)?;
            Ok((scores, gate, taps))
        };
        let (scores_a, gate_a, taps_a) = run(&coarse_index)?;
        let (scores_b, gate_b, taps_b) = run(seed)?;
        let mid = match choice {
            SeedChoice::Joint => Self::soft_argmax(
                Tensor::cat(vec![scores_a, scores_b], 1),
                Tensor::cat(
                    vec![taps_a.hypotheses.clone(), taps_b.hypotheses.clone()],
                    1,
                ),
            ),
            SeedChoice::Peak | SeedChoice::Mass => {
                let confidence = |scores: &Tensor<4>| match choice {
                    SeedChoice::Peak => softmax(scores.clone(), 1).max_dim(1).squeeze_dim::<3>(1),
                    _ => logsumexp(scores.clone()),
                };
                let pick_a = confidence(&scores_a)
                    .greater_equal(confidence(&scores_b))
                    .float(); // [1, H, W]
                let a = Self::gated_answer(scores_a, gate_a, &taps_a)?;
                let b = Self::gated_answer(scores_b, gate_b, &taps_b)?;
                let index =
                    a.index.clone() * pick_a.clone() + b.index * pick_a.neg().add_scalar(1.0);
                StageOutput { index, ..a }
            }
        };
        let mid_index = read_values(mid.index.clone(), "half-resolution index")?;
        let fine_taps = geometry.refine_taps(
            2,
            &mid_index,
            0..geometry.samplers[2].grid().width,
            photo.as_ref(),
        )?;
        let fine = self.refine_stage(0, &levels[0], &fine_taps)?;
        Ok(CascadeOutput {
            stages: [coarse, mid, fine],
            upsampled: [None, None],
        })
    }

    /// The coarse stage alone (every camera's features, then the coarse stage and, with
    /// `zncc_cue`, its photometric cue): what training the coarse stage by itself needs, no
    /// refinement stage run. `training` pads the batch as [`CascadeNet::forward_window`].
    ///
    /// # Errors
    /// See [`CascadeNet::forward`].
    pub fn forward_coarse(
        &self,
        images: &[Tensor<4>],
        geometry: &CascadeGeometry,
        training: bool,
    ) -> Result<StageOutput, NetError> {
        let (levels, photo) = self.feature_levels(images, training)?;
        self.coarse_of(&levels, photo.as_ref(), geometry)
    }

    /// Every camera's feature pyramid (strides 2, 4, 8; one batch through the extractor,
    /// padded when `training`, see [`CascadeNet::forward_window`]) and, when the network has
    /// the photometric cue, the images' own pyramid.
    fn feature_levels(
        &self,
        images: &[Tensor<4>],
        training: bool,
    ) -> Result<([Vec<Tensor<4>>; 3], Option<ImagePyramid>), NetError> {
        self.config
            .check_cameras(images.len(), "the images of a frame")?;
        if let Some(image) = images.iter().find(|i| i.dims()[0] != 1) {
            return Err(NetError::Shape {
                what: "cascade input batch (per-pixel hypotheses are built per frame)".into(),
                expected: vec![1],
                actual: image.dims().to_vec(),
            });
        }
        let cams = images.len();
        let mut batch = images.to_vec();
        if training {
            while batch.len() < MIN_TRAINING_BATCH {
                batch.push(images[0].clone());
            }
        }
        let pyramid = self.features.forward(Tensor::cat(batch, 0)); // [B', C, h, w] x 3
        let levels = pyramid.map(|f| (0..cams).map(|c| f.clone().narrow(0, c, 1)).collect());
        let photo = if self.config.cascade.zncc_cue {
            Some(ImagePyramid::from_inputs(images)?)
        } else {
            None
        };
        Ok((levels, photo))
    }

    /// The coarse stage on the stride-8 features of `levels` (and the photometric cue).
    fn coarse_of(
        &self,
        levels: &[Vec<Tensor<4>>; 3],
        photo: Option<&ImagePyramid>,
        geometry: &CascadeGeometry,
    ) -> Result<StageOutput, NetError> {
        let cue = geometry.coarse_cue(photo)?;
        self.coarse_stage(&levels[2], &geometry.coarse, cue)
    }

    /// The taps of refinement `stage` (1: half, 2: full resolution) over its columns `cols`,
    /// centred on the upsampling of `previous`, an index map on the previous stage's whole
    /// grid: the learnt one when `learnt` and the network has it (its centres are returned
    /// beside the taps, differentiable in the selector's weights), else the bilinear one.
    #[allow(clippy::too_many_arguments)]
    fn centred_taps(
        &self,
        geometry: &CascadeGeometry,
        stage: usize,
        levels: &[Vec<Tensor<4>>; 3],
        previous: &[f32],
        cols: &Range<usize>,
        photo: Option<&ImagePyramid>,
        learnt: bool,
    ) -> Result<(StageTaps, Option<Tensor<3>>), NetError> {
        // Stage 1 reads the stride-4 features (level 1), stage 2 the stride-2 ones (level 0).
        let level = 2 - stage;
        let Some(selector) = self.selector(level).filter(|_| learnt) else {
            let taps = geometry.refine_taps(stage, previous, cols.clone(), photo)?;
            return Ok((taps, None));
        };
        let from = geometry.samplers[stage - 1].grid();
        let rows = geometry.samplers[stage].grid().height;
        // Each pixel chooses among its parent's neighbourhood, starting at the bilinear
        // upsampling.
        let candidates = upsampling_candidates(previous, [from.height, from.width], cols);
        let prior = bilinear_prior(rows, cols, &geometry.device);
        let candidate_taps =
            geometry.taps_for(stage, candidates, UPSAMPLE_TAPS, cols.clone(), photo)?;
        let up = self.select_centres(level, selector, &levels[level], &candidate_taps, prior)?;
        let centre = read_values(up.clone(), "upsampled index")?;
        let taps = geometry.taps_around(stage, centre, cols.clone(), photo)?;
        Ok((taps, Some(up)))
    }

    fn forward_centred(
        &self,
        images: &[Tensor<4>],
        geometry: &CascadeGeometry,
        window: Option<ColumnWindow>,
        timed: bool,
        training: bool,
        centres: Option<impl FnOnce(&[f32]) -> Result<Vec<f32>, NetError>>,
    ) -> Result<(CascadeOutput, CascadeTimings), NetError> {
        let [_, mid_grid, fine_grid] = geometry.samplers.each_ref().map(|s| *s.grid());
        let window = match window {
            Some(w) => {
                w.check(fine_grid.width)?;
                w
            }
            None => ColumnWindow {
                start: 0,
                width: fine_grid.width,
            },
        };
        let start = Instant::now();
        let mut last = start;
        // Seconds since the previous lap, after the device finished (only when timed).
        let mut lap = |device: &Device| -> f64 {
            if !timed {
                return 0.0;
            }
            let _ = device.sync();
            let now = Instant::now();
            let seconds = (now - last).as_secs_f64();
            last = now;
            seconds
        };
        let device = geometry.device.clone();
        let mut timings = CascadeTimings::default();
        let (levels, photo) = self.feature_levels(images, training)?;
        timings.features = lap(&device);
        let coarse = self.coarse_of(&levels, photo.as_ref(), geometry)?;
        timings.coarse = lap(&device);
        let coarse_values = read_values(coarse.index.clone(), "coarse index")?;
        let mid_cols = window.scaled(2);
        // The half stage's centres: what `centres` makes of the coarse answer, else the
        // learnt upsampling when the network has it, else the bilinear one.
        let coarse_grid = *geometry.samplers[0].grid();
        let (coarse_index, learnt) = match centres {
            Some(centres) => (centres(&coarse_values)?, false),
            None => (coarse_values, true),
        };
        let (mid_taps, up_mid) = self.centred_taps(
            geometry,
            1,
            &levels,
            &coarse_index,
            &mid_cols,
            photo.as_ref(),
            learnt,
        )?;
        let mid = self.refine_stage(1, &levels[1], &mid_taps)?;
        timings.mid = lap(&device);
        // The half-resolution estimate inside the window, the coarse one carried to the
        // half-resolution grid outside it (only the window's edges read it).
        let mut mid_index = resample_map(&coarse_index, &coarse_grid, &mid_grid);
        let mid_window = read_values(mid.index.clone(), "half-resolution index")?;
        let w = mid_cols.len();
        for (row, values) in mid_window.chunks_exact(w).enumerate() {
            let at = row * mid_grid.width + mid_cols.start;
            mid_index[at..at + w].copy_from_slice(values);
        }
        let (fine_taps, up_fine) = self.centred_taps(
            geometry,
            2,
            &levels,
            &mid_index,
            &window.scaled(1),
            photo.as_ref(),
            true,
        )?;
        let fine = self.refine_stage(0, &levels[0], &fine_taps)?;
        timings.fine = lap(&device);
        timings.total = start.elapsed().as_secs_f64();
        Ok((
            CascadeOutput {
                stages: [coarse, mid, fine],
                upsampled: [up_mid, up_fine],
            },
            timings,
        ))
    }
}
