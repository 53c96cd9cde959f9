//! Weights: our own files (safetensors + the configuration JSON beside them) and the import
//! of PyTorch checkpoints of the reference implementation (`{'net_state_dict': ..., 'CH': ..}`).

use std::path::{Path, PathBuf};

use burn::module::Module;
use burn::store::pytorch_reader::PytorchReader;
use burn::store::{ApplyResult, ModuleSnapshot, PytorchStore, SafetensorsStore};
use burn::tensor::Device;
use serde::Deserialize;

use crate::cascade::CascadeNet;
use crate::cascade::model::{GROWABLE, GrowWeights};
use crate::config::{Family, Layout, NetConfig};
use crate::error::NetError;
use crate::model::OmniMvsNet;

/// Top-level key of the reference checkpoints holding the state dict.
pub const STATE_DICT_KEY: &str = "net_state_dict";

/// State-dict key present only in the published layout (the 18th feature convolution).
const PUBLISHED_ONLY_KEY: &str = "feature_layers.layers.17.conv.weight";

/// Fusion weight `[2 CH, cams * CH, 3, 3, 3]`, which gives the number of cameras.
const FUSION_WEIGHT_KEY: &str = "cost_computes.fusion.conv.weight";

/// The configuration file written beside a weight file: `model.safetensors` ->
/// `model.json`.
pub fn config_path(weights: &Path) -> PathBuf {
    weights.with_extension("json")
}

fn weights_error(path: &Path, message: impl Into<String>) -> NetError {
    NetError::Weights {
        path: path.to_path_buf(),
        message: message.into(),
    }
}

/// Fails unless every parameter of the model was found and applied. Extra entries are
/// allowed only for PyTorch's `num_batches_tracked` counters.
fn check_applied(path: &Path, result: &ApplyResult) -> Result<(), NetError> {
    if !result.errors.is_empty() {
        let errors: Vec<String> = result.errors.iter().map(|e| e.to_string()).collect();
        return Err(weights_error(
            path,
            format!("cannot apply tensors: {}", errors.join("; ")),
        ));
    }
    if !result.missing.is_empty() {
        let missing: Vec<&str> = result.missing.iter().map(|(p, _)| p.as_str()).collect();
        return Err(weights_error(
            path,
            format!("missing tensors: {}", missing.join(", ")),
        ));
    }
    let unused: Vec<&str> = result
        .unused
        .iter()
        .map(String::as_str)
        .filter(|p| !p.ends_with("num_batches_tracked"))
        .collect();
    if !unused.is_empty() {
        return Err(weights_error(
            path,
            format!("tensors the network does not have: {}", unused.join(", ")),
        ));
    }
    Ok(())
}

/// Writes `net`'s parameters to `path` (safetensors) and its configuration to
/// [`config_path`]`(path)`.
///
/// # Errors
/// [`NetError::Io`] or [`NetError::Weights`] when a file cannot be written.
pub fn save(net: &OmniMvsNet, path: &Path) -> Result<(), NetError> {
    save_module(net, &net.config, path)
}

/// Writes the parameters of any of our networks to `path` (safetensors) and `config` to
/// [`config_path`]`(path)` (atomically).
///
/// # Errors
/// [`NetError::Io`] or [`NetError::Weights`] when a file cannot be written.
pub fn save_module<M: Module>(net: &M, config: &NetConfig, path: &Path) -> Result<(), NetError> {
    save_with_config(net, config, path)
}

/// Writes the parameters of `net` to `path` (safetensors) and any serialisable `config` to
/// [`config_path`]`(path)` (atomically): the one writer of our weight files, whatever the
/// network's configuration type.
///
/// # Errors
/// [`NetError::Io`], [`NetError::Json`] or [`NetError::Weights`] when a file cannot be
/// written.
pub fn save_with_config<M: Module, C: serde::Serialize>(
    net: &M,
    config: &C,
    path: &Path,
) -> Result<(), NetError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| NetError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    }
    let json_path = config_path(path);
    let json = serde_json::to_string_pretty(config).map_err(|source| NetError::Json {
        path: json_path.clone(),
        source,
    })?;
    omnimvs_core::fs::write_atomic(&json_path, (json + "\n").as_bytes()).map_err(|source| {
        NetError::Io {
            path: json_path.clone(),
            source,
        }
    })?;
    // Serialised in memory, then written by the workspace's one atomic writer.
    let mut store = SafetensorsStore::from_bytes(None);
    net.save_into(&mut store)
        .map_err(|e| weights_error(path, e.to_string()))?;
    let bytes = store
        .get_bytes()
        .map_err(|e| weights_error(path, e.to_string()))?;
    omnimvs_core::fs::write_atomic(path, &bytes).map_err(|source| NetError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Applies the safetensors file `path` to `net`, every parameter required.
pub(crate) fn apply_file<M: Module>(net: M, path: &Path) -> Result<M, NetError> {
    apply_file_except(net, path, |_| false, |_| false)
}

/// [`apply_file`], where the parameters whose paths `may_miss` accepts may be absent from the
/// file (they keep their values in `net`) and the file's tensors whose paths `may_leave`
/// accepts may be left unused (a part of the file's network that `net` does not have).
fn apply_file_except<M: Module>(
    mut net: M,
    path: &Path,
    may_miss: impl Fn(&str) -> bool,
    may_leave: impl Fn(&str) -> bool,
) -> Result<M, NetError> {
    if !path.exists() {
        return Err(weights_error(path, "no such weight file"));
    }
    let mut store = SafetensorsStore::from_file(path).allow_partial(true);
    let mut result = net
        .load_from(&mut store)
        .map_err(|e| weights_error(path, e.to_string()))?;
    result.missing.retain(|(p, _)| !may_miss(p));
    result.unused.retain(|p| !may_leave(p));
    check_applied(path, &result)?;
    Ok(net)
}

/// Applies in-memory safetensors bytes to `net` (`name` labels errors).
pub(crate) fn apply_bytes<M: Module>(
    mut net: M,
    name: &Path,
    safetensors: &[u8],
) -> Result<M, NetError> {
    let mut store = SafetensorsStore::from_bytes(Some(safetensors.to_vec()));
    let result = net
        .load_from(&mut store)
        .map_err(|e| weights_error(name, e.to_string()))?;
    check_applied(name, &result)?;
    Ok(net)
}

/// Parses the configuration JSON of the weights `name` (any of our networks' configuration
/// types); errors name [`config_path`]`(name)`.
pub(crate) fn parse_config<C: serde::de::DeserializeOwned>(
    name: &Path,
    config_json: &str,
) -> Result<C, NetError> {
    serde_json::from_str(config_json).map_err(|source| NetError::Json {
        path: config_path(name),
        source,
    })
}

/// Reads a configuration JSON file of any of our networks' configuration types.
pub(crate) fn read_json<C: serde::de::DeserializeOwned>(path: &Path) -> Result<C, NetError> {
    let text = std::fs::read_to_string(path).map_err(|source| NetError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|source| NetError::Json {
        path: path.to_path_buf(),
        source,
    })
}

/// Reads a configuration JSON file.
///
/// # Errors
/// [`NetError::Io`] or [`NetError::Json`].
pub fn read_config(path: &Path) -> Result<NetConfig, NetError> {
    read_json(path)
}

/// Loads a network saved by [`save`]: the configuration beside `path`, then the weights.
///
/// # Errors
/// [`NetError`] when a file is missing, unreadable or does not fit the configuration.
pub fn load(path: &Path, device: &Device) -> Result<OmniMvsNet, NetError> {
    let config = read_config(&config_path(path))?;
    apply_file(OmniMvsNet::new(&config, device)?, path)
}

/// Loads a cascade network saved by [`save_module`].
///
/// # Errors
/// [`NetError`] when a file is missing, unreadable or not a cascade network.
pub fn load_cascade(path: &Path, device: &Device) -> Result<CascadeNet, NetError> {
    let config = read_config(&config_path(path))?;
    apply_file(CascadeNet::new(&config, device)?, path)
}

/// Loads cascade weights into a network of `config`, which may have grown from the
/// weights' own configuration (the file's JSON) as [`GROWABLE`] allows, everything else
/// equal: e.g. more context pairs at stride 8 (`context_pairs`), gated refinement stages
/// (`stage_gates`), the photometric cue (`zncc_cue`, [`CascadeNet::with_zncc_cue`]), learnt
/// upsampling (`convex_upsampling`, selectors that start near the bilinear weights), other
/// loss weights (training only). The full grid's selector alone may also be left out of the
/// file's network (`convex_upsampling_full` off: its tensors are not read). The new modules
/// keep their starting values, which leave the network's answer as it was (or nearly: the
/// gates start at 0.98), so training goes on from the loaded network.
///
/// # Errors
/// [`NetError::Weights`] when the file's network is not `config` or a part of it; see
/// [`load_cascade`].
pub fn load_cascade_grown(
    path: &Path,
    config: &NetConfig,
    device: &Device,
) -> Result<CascadeNet, NetError> {
    let saved = read_config(&config_path(path))?;
    if saved == *config {
        return load_cascade(path, device);
    }
    check_growth(path, &saved, config)?;
    let has_fine = |c: &NetConfig| c.cascade.convex_upsampling && c.cascade.convex_upsampling_full;
    // The full grid's selector may be left out (its tensors in the file unused) or new.
    let (saved_fine, fine) = (has_fine(&saved), has_fine(config));
    let old_ctx = 2 * saved.cascade.context_pairs;
    let is_new = |p: &str| {
        p.starts_with("mid.gate.")
            || p.starts_with("fine.gate.")
            || (!saved.cascade.convex_upsampling && p.starts_with("up_mid."))
            || (!saved_fine && p.starts_with("up_fine."))
            || p.strip_prefix("features.ctx8.")
                .and_then(|rest| rest.split('.').next())
                .and_then(|i| i.parse::<usize>().ok())
                .is_some_and(|i| i >= old_ctx)
    };
    // What a growth step adds weights for is loaded into the network as saved, then grown
    // (e.g. the cue widens the first convolution of every stage with zero weights).
    let mut as_saved = config.clone();
    for field in GROWABLE.iter().filter(|f| f.weights == GrowWeights::Grown) {
        (field.copy)(&mut as_saved.cascade, &saved.cascade);
    }
    let dropped = |p: &str| saved_fine && !fine && p.starts_with("up_fine.");
    let net = apply_file_except(CascadeNet::new(&as_saved, device)?, path, is_new, dropped)?;
    grow_loaded(net, config)
}

/// Fails unless the network of the weights `path`, saved with `saved`, may be loaded into
/// one of `config`: every field equal but those of [`GROWABLE`], which may differ as their
/// rules allow.
fn check_growth(path: &Path, saved: &NetConfig, config: &NetConfig) -> Result<(), NetError> {
    let refuse = |why: String| {
        weights_error(
            path,
            format!(
                "the network of these weights is neither the one asked for nor a part of it: \
                 {why}"
            ),
        )
    };
    if let Some(field) = GROWABLE
        .iter()
        .find(|f| !f.rule.allows(&saved.cascade, &config.cascade))
    {
        return Err(refuse(format!(
            "`{}` {}",
            field.name,
            field.rule.describe()
        )));
    }
    let mut shrunk = config.clone();
    for field in GROWABLE
        .iter()
        .filter(|f| f.rule.may_differ(&saved.cascade))
    {
        (field.copy)(&mut shrunk.cascade, &saved.cascade);
    }
    if shrunk != *saved {
        let may: Vec<String> = GROWABLE
            .iter()
            .map(|f| format!("`{}` {}", f.name, f.rule.describe()))
            .collect();
        return Err(refuse(format!(
            "only these may differ: {}; everything else must be equal",
            may.join(", ")
        )));
    }
    Ok(())
}

/// `net`, loaded as saved for the fields whose weights are [`GrowWeights::Grown`], grown into
/// `config` one `with_*` step at a time.
fn grow_loaded(net: CascadeNet, config: &NetConfig) -> Result<CascadeNet, NetError> {
    let p = &config.cascade;
    let net = if p.zncc_cue { net.with_zncc_cue() } else { net };
    let net = if p.coarse_cue_sgm {
        net.with_coarse_cue_sgm()?
    } else {
        net
    };
    let net = net.with_coarse_feature_channels(p.feature_channels[2])?;
    // Everything asked for but the saved spheres by now; the resampling keeps what it has
    // where they are the same.
    net.with_coarse_spheres(p.coarse_spheres)
}

/// Loads a network from in-memory files: the configuration JSON and the safetensors bytes
/// (e.g. a model bundled into a binary with `include_bytes!`). `name` labels errors.
///
/// # Errors
/// [`NetError`] when the configuration or the weights do not parse or do not match.
pub fn load_bytes(
    name: &Path,
    config_json: &str,
    safetensors: &[u8],
    device: &Device,
) -> Result<OmniMvsNet, NetError> {
    let config = parse_config(name, config_json)?;
    apply_bytes(OmniMvsNet::new(&config, device)?, name, safetensors)
}

/// A network of either family, as weight files hold them.
#[derive(Debug)]
pub enum AnyNet {
    /// The paper's network.
    OmniMvs(Box<OmniMvsNet>),
    /// The coarse-to-fine network.
    Cascade(Box<CascadeNet>),
}

impl AnyNet {
    /// The network's configuration.
    pub fn config(&self) -> &NetConfig {
        match self {
            AnyNet::OmniMvs(net) => &net.config,
            AnyNet::Cascade(net) => &net.config,
        }
    }

    /// Feeds the network images of `[rows, cols]` from now on (the images are resized to it).
    /// Both families are fully convolutional and sample their features at normalised image
    /// positions, so any size runs; the reference runs its checkpoints at each camera's
    /// native size, and a model answers best at the size it was trained at.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] for a size the network cannot take.
    pub fn set_input_size(&mut self, [rows, cols]: [usize; 2]) -> Result<(), NetError> {
        let config = match self {
            AnyNet::OmniMvs(net) => &mut net.config,
            AnyNet::Cascade(net) => &mut net.config,
        };
        let mut changed = config.clone();
        changed.input_height = rows;
        changed.input_width = cols;
        changed.validate()?;
        *config = changed;
        Ok(())
    }
}

/// The image size `[rows, cols]` that every camera of `rig` shares: the size a network takes
/// at `infer --input-size native` (our networks take one input size for all cameras). Every
/// camera's size, in rig order, when they differ or there is no camera.
///
/// # Errors
/// The cameras' sizes, when they are not all the same.
pub fn common_image_size(rig: &omnimvs_camera::Rig) -> Result<[usize; 2], Vec<[usize; 2]>> {
    let sizes: Vec<[usize; 2]> = rig
        .cameras
        .iter()
        .map(|c| [c.model.height() as usize, c.model.width() as usize])
        .collect();
    match sizes.first() {
        Some(&first) if sizes.iter().all(|s| *s == first) => Ok(first),
        _ => Err(sizes),
    }
}

/// Loads in-memory files of either family (the configuration's `family` decides).
///
/// # Errors
/// See [`load_bytes`].
pub fn load_any_bytes(
    name: &Path,
    config_json: &str,
    safetensors: &[u8],
    device: &Device,
) -> Result<AnyNet, NetError> {
    let config: NetConfig = parse_config(name, config_json)?;
    Ok(match config.family {
        Family::OmniMvs => AnyNet::OmniMvs(Box::new(apply_bytes(
            OmniMvsNet::new(&config, device)?,
            name,
            safetensors,
        )?)),
        Family::Cascade => AnyNet::Cascade(Box::new(apply_bytes(
            CascadeNet::new(&config, device)?,
            name,
            safetensors,
        )?)),
    })
}

/// Loads weights of either family and either format: a reference `.pt` checkpoint (the
/// paper's network, sizes from `base`) or our safetensors file (family and sizes from its
/// JSON).
///
/// # Errors
/// See [`load_any`] and [`load_cascade`].
pub fn load_family(path: &Path, base: &NetConfig, device: &Device) -> Result<AnyNet, NetError> {
    let is_pytorch = matches!(
        path.extension().and_then(|e| e.to_str()),
        Some("pt" | "pth" | "tar")
    );
    if !is_pytorch && read_config(&config_path(path))?.family == Family::Cascade {
        return Ok(AnyNet::Cascade(Box::new(load_cascade(path, device)?)));
    }
    Ok(AnyNet::OmniMvs(Box::new(load_any(path, base, device)?)))
}

/// What a reference checkpoint says about the network it holds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CheckpointInfo {
    /// `CH`.
    pub channels: usize,
    /// Number of cameras (input channels of the fusion divided by `CH`).
    pub num_cameras: usize,
    /// ICCV or published layout (presence of the 18th feature convolution).
    pub layout: Layout,
}

#[derive(Deserialize)]
struct CheckpointMeta {
    #[serde(rename = "CH")]
    ch: Option<usize>,
}

/// Reads `CH`, the number of cameras and the layout of a reference checkpoint.
///
/// # Errors
/// [`NetError::Weights`] when the file is not a PyTorch checkpoint with a
/// `net_state_dict`.
pub fn inspect_pytorch(path: &Path) -> Result<CheckpointInfo, NetError> {
    let reader = PytorchReader::with_top_level_key(path, STATE_DICT_KEY)
        .map_err(|e| weights_error(path, format!("not a reference checkpoint: {e}")))?;
    let fusion = reader.get(FUSION_WEIGHT_KEY).ok_or_else(|| {
        weights_error(path, format!("no `{FUSION_WEIGHT_KEY}` in the state dict"))
    })?;
    let shape = fusion.shape().to_vec();
    let meta: Option<CheckpointMeta> = PytorchReader::load_config(path, None).ok();
    let channels = match meta.and_then(|m| m.ch) {
        Some(ch) => ch,
        None if shape.len() == 5 => shape[0] / 2,
        None => 0,
    };
    if shape.len() != 5 || channels == 0 || shape[0] != 2 * channels || shape[1] % channels != 0 {
        return Err(weights_error(
            path,
            format!(
                "`{FUSION_WEIGHT_KEY}` has shape {shape:?}, expected [2 CH, cams * CH, 3, 3, 3] with CH = {channels}"
            ),
        ));
    }
    let layout = if reader.get(PUBLISHED_ONLY_KEY).is_some() {
        Layout::Published
    } else {
        Layout::Iccv
    };
    Ok(CheckpointInfo {
        channels,
        num_cameras: shape[1] / channels,
        layout,
    })
}

/// Imports a reference PyTorch checkpoint. `CH`, the cameras and the layout come from the
/// checkpoint; the other sizes (which the weights do not fix) from `base`.
///
/// # Errors
/// [`NetError`] when the file cannot be read or does not match the layout.
pub fn import_pytorch(
    path: &Path,
    base: &NetConfig,
    device: &Device,
) -> Result<OmniMvsNet, NetError> {
    let info = inspect_pytorch(path)?;
    let config = NetConfig {
        channels: info.channels,
        num_cameras: info.num_cameras,
        layout: info.layout,
        ..base.clone()
    };
    let mut net = OmniMvsNet::new(&config, device)?;
    let mut store = PytorchStore::from_file(path)
        .with_top_level_key(STATE_DICT_KEY)
        .map_indices_contiguous(false);
    let result = net
        .load_from(&mut store)
        .map_err(|e| weights_error(path, e.to_string()))?;
    check_applied(path, &result)?;
    Ok(net)
}

/// Loads weights of either kind: a `.pt`/`.pth` reference checkpoint (sizes from `base`)
/// or our safetensors file (sizes from its JSON).
///
/// # Errors
/// See [`import_pytorch`] and [`load`].
pub fn load_any(path: &Path, base: &NetConfig, device: &Device) -> Result<OmniMvsNet, NetError> {
    match path.extension().and_then(|e| e.to_str()) {
        Some("pt" | "pth" | "tar") => import_pytorch(path, base, device),
        _ => load(path, device),
    }
}
