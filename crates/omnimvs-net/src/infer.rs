//! Inference on a dataset: lookup table from the cache, input preparation (normalisation,
//! resizing to the network input), forward pass, inverse depth and entropy maps.

use burn::tensor::{Device, Tensor, TensorData};
use omnimvs_camera::ValidityMask;
use omnimvs_core::GrayImage;
use omnimvs_core::interp::resize_align_corners;
use omnimvs_data::image_io::normalize_for_network;
use omnimvs_data::{Dataset, DepthEstimate, NoTimings, StageObserver};
use omnimvs_sweep::{
    CacheStatus, EquirectGrid, InvDepthHypotheses, LutCache, SphereSet, SweepSpec,
};
use rayon::prelude::*;

pub use crate::backend::device_from_name;
use crate::config::NetConfig;
use crate::error::NetError;
use crate::model::{OmniMvsNet, SweepInput, SweepTaps};
use crate::taps::SweepGrid;
use crate::tensor::read_values;

/// A network ready to run on the frames of one rig.
pub struct Inference {
    /// The network (batch norms possibly folded).
    net: OmniMvsNet,
    /// Lookup table of every camera for the network's output grid.
    grids: Vec<SweepGrid>,
    /// The output grid and the dataset's `N` inverse-depth hypotheses.
    spec: SweepSpec,
    /// Validity mask of every camera, at the dataset's image size.
    masks: Vec<ValidityMask>,
    /// Camera concatenation order.
    order: Vec<usize>,
    /// Device the network runs on.
    device: Device,
    /// The lookup tables as taps on the device, when the sweep runs there (GPU backends).
    device_taps: Option<Vec<SweepTaps>>,
}

impl Inference {
    /// The method's name in estimates.
    pub const NAME: &'static str = "OmniMVS";

    /// Prepares `net` for `dataset`: checks the camera count, loads or builds the lookup
    /// table in `cache` (the network sweeps every other sphere) and reads the masks.
    ///
    /// # Errors
    /// [`NetError`] when the rig does not match the network or the table cannot be built.
    pub fn new(
        net: OmniMvsNet,
        dataset: &Dataset,
        cache: &LutCache,
        device: Device,
    ) -> Result<(Self, CacheStatus), NetError> {
        let config = net.config.clone();
        let spec = sweep_spec(&config, dataset)?;
        let (lut, status) = cache.load_or_build(
            &dataset.rig,
            &spec.grid,
            &spec.hypotheses,
            SphereSet::EveryOther,
        )?;
        let grids = SweepGrid::split_table(
            &lut.data,
            config.num_cameras,
            config.num_spheres(),
            config.out_height,
            config.out_width,
        )?;
        let masks = dataset.masks()?;
        let order = net.identity_order();
        Ok((
            Self {
                net,
                grids,
                spec,
                masks,
                order,
                device,
                device_taps: None,
            },
            status,
        ))
    }

    /// The network.
    pub fn net(&self) -> &OmniMvsNet {
        &self.net
    }

    /// The output grid and the dataset's hypotheses.
    pub fn spec(&self) -> &SweepSpec {
        &self.spec
    }

    /// Validity masks of the cameras at the dataset's image size.
    pub fn masks(&self) -> &[ValidityMask] {
        &self.masks
    }

    /// The camera concatenation order.
    pub fn order(&self) -> &[usize] {
        &self.order
    }

    /// Sets the camera concatenation order.
    ///
    /// # Errors
    /// [`NetError::CameraOrder`] for an order that is not a permutation of the cameras.
    pub fn set_order(&mut self, order: &[usize]) -> Result<(), NetError> {
        self.net.check_order(order)?;
        self.order = order.to_vec();
        Ok(())
    }

    /// Runs the sweep on the device from now on (for GPU backends: the host kernel would copy
    /// every camera's features to host memory and back).
    pub fn sweep_on_device(&mut self) {
        let size = self.net.config.feature_size();
        self.device_taps = Some(SweepTaps::for_grids(&self.grids, size, &self.device));
    }

    /// Network inputs `[1, 1, H_I, W_I]`: each gray image normalised over its valid pixels,
    /// then resized to the network's input size.
    ///
    /// # Errors
    /// [`NetError`] for a wrong number of images or a mask of another size.
    pub fn input_tensors(&self, images: &[GrayImage]) -> Result<Vec<Tensor<4>>, NetError> {
        input_tensors(&self.net.config, images, &self.masks, &self.device)
    }

    /// Runs the network on one frame's gray images (camera order of the rig), stages not
    /// measured.
    ///
    /// # Errors
    /// [`NetError`] for inconsistent inputs.
    pub fn run(&self, images: &[GrayImage]) -> Result<DepthEstimate, NetError> {
        self.run_observed(images, &mut NoTimings)
    }

    /// [`Self::run`], each stage's time given to `observer` when it wants them (the device
    /// is then waited for after every stage).
    ///
    /// # Errors
    /// [`NetError`] for inconsistent inputs.
    pub fn run_observed(
        &self,
        images: &[GrayImage],
        observer: &mut dyn StageObserver,
    ) -> Result<DepthEstimate, NetError> {
        let inputs = self.input_tensors(images)?;
        let sweep = match &self.device_taps {
            Some(taps) => SweepInput::Device(taps),
            None => SweepInput::Host(&self.grids),
        };
        let (out, t) =
            self.net
                .infer_with(&inputs, sweep, &self.order, observer.wants_timings())?;
        observer.stages(&[
            ("features", t.features),
            ("sweep", t.sweep),
            ("fusion", t.fusion),
            ("fusion_finish", t.fusion_finish),
            ("cost", t.cost),
            ("softargmin", t.softargmin),
            ("total", t.total),
        ]);
        entropy_estimate(self.spec, Self::NAME, out.entropy(), out.index, t.total)
    }
}

/// A network's estimate on `spec`, read from its entropy and index maps `[1, H, W]`, that took
/// `seconds`.
///
/// # Errors
/// [`NetError::Shape`] when a map cannot be read as `f32`.
pub(crate) fn entropy_estimate(
    spec: SweepSpec,
    method: &str,
    entropy: Tensor<3>,
    index: Tensor<3>,
    seconds: f64,
) -> Result<DepthEstimate, NetError> {
    let entropy = read_values(entropy, "entropy map")?;
    let index = read_values(index, "index map")?;
    Ok(DepthEstimate::with_entropy(
        spec, method, index, entropy, seconds,
    ))
}

/// Checks that `dataset`'s rig has the network's number of cameras and returns the network's
/// sweep: its output grid and the dataset's `N` inverse-depth hypotheses.
///
/// # Errors
/// [`NetError::Shape`] for another number of cameras; [`NetError`] for an invalid grid or
/// minimum depth.
pub fn sweep_spec(config: &NetConfig, dataset: &Dataset) -> Result<SweepSpec, NetError> {
    config.check_cameras(
        dataset.rig.len(),
        format!("the rig of {}", dataset.config_path.display()),
    )?;
    Ok(dataset.sweep_spec(
        config.out_height,
        config.out_width,
        config.phi_deg,
        config.num_invdepth,
    )?)
}

/// [`sweep_spec`] as a grid and hypotheses (the trainer's form).
///
/// # Errors
/// As [`sweep_spec`].
pub fn sweep_geometry(
    config: &NetConfig,
    dataset: &Dataset,
) -> Result<(EquirectGrid, InvDepthHypotheses), NetError> {
    let spec = sweep_spec(config, dataset)?;
    Ok((spec.grid, spec.hypotheses))
}

/// Network inputs `[1, 1, H_I, W_I]` of a frame's gray images on `device`, for either family:
/// one image per camera of `config`, each normalised over its valid pixels (`masks`), then
/// resized to the configuration's input size.
///
/// # Errors
/// [`NetError`] for a wrong number of images or a mask of another size.
pub fn input_tensors(
    config: &NetConfig,
    images: &[GrayImage],
    masks: &[ValidityMask],
    device: &Device,
) -> Result<Vec<Tensor<4>>, NetError> {
    config.check_cameras(images.len(), "the images of a frame")?;
    let size = [config.input_height, config.input_width];
    Ok(network_inputs(images, masks, size)?
        .into_iter()
        .map(|data| Tensor::from_data(TensorData::new(data, [1, 1, size[0], size[1]]), device))
        .collect())
}

/// Network inputs of a frame's gray images (camera order of `masks`): each normalised over
/// its valid pixels, then resized to `size = [rows, cols]`, row-major.
///
/// # Errors
/// [`NetError`] for a mask of another size than its image.
pub fn network_inputs(
    images: &[GrayImage],
    masks: &[ValidityMask],
    size: [usize; 2],
) -> Result<Vec<Vec<f32>>, NetError> {
    // The cameras in parallel (two passes over each image on one thread had cost
    // about 7 ms a full-size frame with the other core idle).
    images
        .par_iter()
        .zip(masks.par_iter())
        .map(|(image, mask)| {
            let normalized = normalize_for_network(image, Some(mask))?;
            Ok(resize_align_corners(&normalized, size[1], size[0]).data)
        })
        .collect()
}
