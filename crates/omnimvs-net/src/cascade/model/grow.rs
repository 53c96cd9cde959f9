//! Growth of a trained cascade: each `with_*` method switches one option of the
//! configuration on and adds the weights it needs so that the network answers as before (or
//! nearly) until training moves them; [`GROWABLE`] says which fields of a saved network's
//! configuration may differ from the one it is loaded into, and how
//! ([`crate::weights::load_cascade_grown`]).

use burn::module::Param;
use burn::nn::conv::Conv2d;
use burn::tensor::{Tensor, TensorData};

use super::CascadeNet;
use super::upsample::UPSAMPLE_TAPS;
use crate::config::CascadeParams;
use crate::error::NetError;
use crate::tensor::read_values;

/// How a field of [`CascadeParams`] may differ between a saved network and the
/// configuration it is loaded into ([`GROWABLE`]).
#[derive(Clone, Copy, Debug)]
pub enum GrowRule {
    /// Any value: only training reads it, or no weight depends on it.
    Any,
    /// Any value while the saved network has what the function accepts, else unchanged.
    AnyWhile(fn(&CascadeParams) -> bool),
    /// A flag (the function reads it) that may switch on, not off.
    SwitchOn(fn(&CascadeParams) -> bool),
    /// A count (the function reads it) that may grow, not shrink.
    Grow(fn(&CascadeParams) -> usize),
    /// A count (the function reads it) that may shrink, not grow.
    Shrink(fn(&CascadeParams) -> usize),
    /// Whatever the function accepts of the saved and the asked-for parameters.
    Check(fn(&CascadeParams, &CascadeParams) -> bool),
}

impl GrowRule {
    /// Whether a saved network's value is replaced by the asked-for one when the two are
    /// compared: always but for [`GrowRule::AnyWhile`], whose condition `saved` must meet.
    pub fn may_differ(self, saved: &CascadeParams) -> bool {
        match self {
            GrowRule::AnyWhile(allowed) => allowed(saved),
            _ => true,
        }
    }

    /// Whether the asked-for value may follow the saved one.
    pub fn allows(self, saved: &CascadeParams, asked: &CascadeParams) -> bool {
        match self {
            GrowRule::Any | GrowRule::AnyWhile(_) => true,
            GrowRule::SwitchOn(flag) => !flag(saved) || flag(asked),
            GrowRule::Grow(count) => count(saved) <= count(asked),
            GrowRule::Shrink(count) => count(asked) <= count(saved),
            GrowRule::Check(check) => check(saved, asked),
        }
    }

    /// How the value may differ, in words.
    pub fn describe(self) -> &'static str {
        match self {
            GrowRule::Any => "may take any value",
            GrowRule::AnyWhile(_) => "may be chosen only while the saved network allows it",
            GrowRule::SwitchOn(_) => "may switch on, not off",
            GrowRule::Grow(_) => "may grow, not shrink",
            GrowRule::Shrink(_) => "may shrink, not grow",
            GrowRule::Check(_) => "may change only as its growth allows",
        }
    }
}

/// Where the weights of a growable field's asked-for value come from when a saved network
/// is loaded into another configuration.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GrowWeights {
    /// The network is built as asked; tensors the file lacks keep their starting values.
    Built,
    /// The network is built as saved and a `with_*` growth adds what the asked-for value
    /// needs after loading.
    Grown,
}

/// One field of [`CascadeParams`] that may differ between a saved network and the
/// configuration it is loaded into.
#[derive(Clone, Copy, Debug)]
pub struct Growable {
    /// The field's name in the configuration file.
    pub name: &'static str,
    /// Copies the field from the second parameters into the first.
    pub copy: fn(&mut CascadeParams, &CascadeParams),
    /// How it may differ.
    pub rule: GrowRule,
    /// Where its weights come from.
    pub weights: GrowWeights,
}

/// One [`Growable`] per `field[index]: rule, weights` line; the rules `any`, `switch_on`,
/// `grow` and `shrink` read the field itself, `any_while(f)` and `check(f)` take a function.
macro_rules! growable {
    (@rule $f:ident $([$i:literal])?, any) => { GrowRule::Any };
    (@rule $f:ident $([$i:literal])?, switch_on) => { GrowRule::SwitchOn(|p| p.$f) };
    (@rule $f:ident $([$i:literal])?, grow) => { GrowRule::Grow(|p| p.$f$([$i])?) };
    (@rule $f:ident $([$i:literal])?, shrink) => { GrowRule::Shrink(|p| p.$f$([$i])?) };
    (@rule $f:ident $([$i:literal])?, any_while($c:expr)) => { GrowRule::AnyWhile($c) };
    (@rule $f:ident $([$i:literal])?, check($c:expr)) => { GrowRule::Check($c) };
    ($($f:ident $([$i:literal])?: $rule:ident $(($c:expr))?, $weights:ident;)*) => {
        &[$(Growable {
            name: concat!(stringify!($f) $(, "[", stringify!($i), "]")?),
            copy: |to, from| to.$f$([$i])? = from.$f$([$i])?,
            rule: growable!(@rule $f $([$i])?, $rule $(($c))?),
            weights: GrowWeights::$weights,
        }),*]
    };
}

/// The fields of [`CascadeParams`] that may differ between a saved network and the
/// configuration it is loaded into ([`crate::weights::load_cascade_grown`]), with how; every
/// other field must be equal. A new option that a trained network can grow into is one line
/// here (and, when its weights are [`GrowWeights::Grown`], one step of the growth).
pub const GROWABLE: &[Growable] = growable! {
    // Only training reads these.
    loss_weights: any, Built;
    coarse_distribution_weight: any, Built;
    refine_distribution_weight: any, Built;
    sky_loss_weight: any, Built;
    // New modules that start where the network answers as before (or nearly).
    context_pairs: grow, Built;
    stage_gates: switch_on, Built;
    convex_upsampling: switch_on, Built;
    // The full grid's selector may be left out of the file's network or new.
    convex_upsampling_full: any, Built;
    // New input channels with zero weights (`CascadeNet::with_zncc_cue`,
    // `with_coarse_cue_sgm`).
    zncc_cue: switch_on, Grown;
    coarse_cue_sgm: switch_on, Grown;
    // No weight depends on these: the refinement's hypothesis spacing, the grid and depths of
    // the coarse cue.
    stage_intervals: any, Built;
    coarse_cue_oversample: any, Built;
    coarse_cue_depths: any, Built;
    // The stride-8 features may widen (`CascadeFeatures::widen8`).
    feature_channels[2]: grow, Grown;
    // The coarse stage may be resampled to other spheres (`CascadeNet::with_coarse_spheres`).
    coarse_spheres: any, Grown;
};

impl CascadeNet {
    /// The network with the photometric cue switched on (`zncc_cue`): the first convolution
    /// of every stage gets the cue's input channels (one per hypothesis, after the existing
    /// ones) with zero weights, so it answers exactly as before until training moves them.
    /// A network that has the cue already is returned as it is.
    #[must_use]
    pub fn with_zncc_cue(mut self) -> Self {
        if self.config.cascade.zncc_cue {
            return self;
        }
        let p = &self.config.cascade;
        let ks = [
            p.coarse_spheres,
            p.stage_hypotheses[0],
            p.stage_hypotheses[1],
        ];
        append_zero_inputs(self.coarse.input_conv(), ks[0]);
        let mut firsts = vec![
            (&mut self.mid.convs[0], ks[1]),
            (&mut self.fine.convs[0], ks[2]),
        ];
        for selector in [&mut self.up_mid, &mut self.up_fine].into_iter().flatten() {
            firsts.push((&mut selector.hidden, UPSAMPLE_TAPS));
        }
        for (first, k) in firsts {
            append_zero_inputs(&mut first.conv, k);
        }
        self.config.cascade.zncc_cue = true;
        self
    }

    /// The network with the coarse stage's aggregated cue switched on (`coarse_cue_sgm`; the
    /// network must have `zncc_cue`): the coarse stage's first convolution gets one input
    /// channel per sphere, after the existing ones, with zero weights, so that it answers
    /// exactly as before until training moves them. A network that has it is returned as it is.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when the network has no `zncc_cue`.
    pub fn with_coarse_cue_sgm(mut self) -> Result<Self, NetError> {
        let mut config = self.config.clone();
        if config.cascade.coarse_cue_sgm {
            return Ok(self);
        }
        config.cascade.coarse_cue_sgm = true;
        config.validate()?;
        append_zero_inputs(self.coarse.input_conv(), config.cascade.coarse_spheres);
        self.config = config;
        Ok(self)
    }

    /// The network with its stride-8 features widened to `c8` channels (see
    /// [`super::CascadeFeatures::widen8`]): it answers as before but for a small perturbation of
    /// the coarse correlation, and the coarse stage can learn from the new channels.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when `c8` is narrower than the network's stride-8 width, not
    /// a multiple of its coarse groups, or the widened configuration is not valid.
    pub fn with_coarse_feature_channels(mut self, c8: usize) -> Result<Self, NetError> {
        let mut config = self.config.clone();
        config.cascade.feature_channels[2] = c8;
        config.validate()?;
        let device = self.features.out8.conv.weight.val().device();
        self.features = self
            .features
            .widen8(c8, config.cascade.groups[2], &device)?;
        self.config = config;
        Ok(self)
    }

    /// The network with its coarse stage over `spheres` spheres (`coarse_spheres`), from a
    /// trained one: every weight is kept but the coarse stage's first convolution, which
    /// reads each evidence channel per sphere, and its scoring convolution, which writes one
    /// score per sphere. Those are resampled along the spheres ([`sphere_resampling`]): the
    /// new first convolution gives the old one's output for evidence that varies linearly over
    /// inverse depth, and each new score is the old scores interpolated at the new sphere's
    /// inverse depth. A starting point for training, not an answer.
    ///
    /// # Errors
    /// [`NetError::InvalidConfig`] when the configuration with them is not valid.
    pub fn with_coarse_spheres(mut self, spheres: usize) -> Result<Self, NetError> {
        let mut config = self.config.clone();
        let old = config.cascade.coarse_spheres;
        config.cascade.coarse_spheres = spheres;
        config.validate()?;
        if spheres != old {
            let n = config.num_invdepth;
            let conv = self.coarse.input_conv();
            conv.weight = Param::from_tensor(resample_axis(
                conv.weight.val(),
                1,
                &sphere_resampling(old, spheres, n, true),
                spheres,
            )?);
            let out = &mut self.coarse.out.conv;
            let to_new = sphere_resampling(old, spheres, n, false);
            out.weight = Param::from_tensor(resample_axis(out.weight.val(), 0, &to_new, spheres)?);
            if let Some(bias) = out.bias.take() {
                let bias = bias.val().reshape([old, 1, 1, 1]);
                let bias = resample_axis(bias, 0, &to_new, spheres)?;
                out.bias = Some(Param::from_tensor(bias.reshape([spheres])));
            }
        }
        self.config = config;
        Ok(self)
    }
}

/// The matrix that carries a per-sphere quantity from `from` coarse spheres to `to`
/// ([`crate::cascade::sampler::coarse_indices`] over `N = num_invdepth`), row-major `[to, from]` when
/// `transpose` is false: each new sphere's value interpolated linearly between the two old
/// spheres around its inverse depth (scores). With `transpose`, `[from, to]`'s transpose laid
/// out as `[to, from]` too: the weight that a new sphere's evidence takes over from each old
/// sphere's, so that `sum_old w_old e_old = sum_new w_new e_new` whenever the old evidence is
/// the new one interpolated linearly (first-layer weights).
pub fn sphere_resampling(from: usize, to: usize, num_invdepth: usize, transpose: bool) -> Vec<f32> {
    let interpolate = |at: &[f64], grid: &[f64]| -> Vec<f32> {
        // Rows: positions `at`; columns: the `grid` spheres.
        let spacing = crate::cascade::sampler::coarse_spacing(grid.len(), num_invdepth);
        let mut m = vec![0f32; at.len() * grid.len()];
        for (r, &x) in at.iter().enumerate() {
            let u = (x / spacing).clamp(0.0, (grid.len() - 1) as f64);
            let i0 = (u.floor() as usize).min(grid.len() - 1);
            let i1 = (i0 + 1).min(grid.len() - 1);
            let f = (u - i0 as f64) as f32;
            m[r * grid.len() + i0] += 1.0 - f;
            m[r * grid.len() + i1] += f;
        }
        m
    };
    let old = crate::cascade::sampler::coarse_indices(from, num_invdepth);
    let new = crate::cascade::sampler::coarse_indices(to, num_invdepth);
    if !transpose {
        return interpolate(&new, &old);
    }
    // Old positions from new spheres, `[from, to]`, transposed to `[to, from]`.
    let m = interpolate(&old, &new);
    let mut t = vec![0f32; to * from];
    for i in 0..from {
        for j in 0..to {
            t[j * from + i] = m[i * to + j];
        }
    }
    t
}

/// `weight` (`[O, I, kh, kw]`) with the sphere axis inside `axis` (0 or 1; that axis is
/// `groups x from` with the sphere fastest, as [`super::stages::fold_volume`] lays a volume out) carried to
/// `to` spheres by `matrix` (`[to, from]`, [`sphere_resampling`]).
///
/// # Errors
/// [`NetError`] when the weights cannot be read back from the device.
fn resample_axis(
    weight: Tensor<4>,
    axis: usize,
    matrix: &[f32],
    to: usize,
) -> Result<Tensor<4>, NetError> {
    let dims = weight.dims();
    let device = weight.device();
    let values = read_values(weight, "coarse stage weights")?;
    let from = matrix.len() / to;
    let groups = dims[axis] / from;
    let mut out_dims = dims;
    out_dims[axis] = groups * to;
    // Row-major strides of `dims` and of the output.
    let inner: usize = dims[axis + 1..].iter().product();
    let outer: usize = dims[..axis].iter().product();
    let mut out = vec![0f32; outer * groups * to * inner];
    for o in 0..outer {
        for g in 0..groups {
            for j in 0..to {
                let dst = ((o * groups + g) * to + j) * inner;
                for i in 0..from {
                    let m = matrix[j * from + i];
                    if m == 0.0 {
                        continue;
                    }
                    let src = ((o * groups + g) * from + i) * inner;
                    for e in 0..inner {
                        out[dst + e] += m * values[src + e];
                    }
                }
            }
        }
    }
    Ok(Tensor::from_data(TensorData::new(out, out_dims), &device))
}

/// `first` reading `k` more input channels, after its own, with zero weights: the network
/// answers as before until training moves them.
fn append_zero_inputs(first: &mut Conv2d, k: usize) {
    let weight = first.weight.val(); // [C_out, C_in, 3, 3]
    let [c_out, _, kh, kw] = weight.dims();
    let zeros = Tensor::zeros([c_out, k, kh, kw], &weight.device());
    let widened = Tensor::cat(vec![weight, zeros], 1).detach(); // a leaf again
    first.weight = Param::from_tensor(widened);
}
