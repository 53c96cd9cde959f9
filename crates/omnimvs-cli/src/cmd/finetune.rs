//! `omnimvs finetune`: the bundled network specialised to one rig, in one resumable command.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use omnimvs_camera::FrameChoice;
use omnimvs_core::fs::write_atomic;
use omnimvs_data::FrameRange;
use omnimvs_eval::metrics::Metrics;
use omnimvs_eval::output::{write_json, write_text};
use omnimvs_net::bundled::{BundledModel, PickChoice};
use omnimvs_net::weights::read_config;
use omnimvs_net::{Backend, CascadeNet};
use omnimvs_synth::{Difficulty, SceneKind, Shard, SynthOptions};
use omnimvs_train::{Optimizer, PhotometricAugment, Selection, TrainConfig, Trainer};
use serde::{Deserialize, Serialize};

use crate::args::{BACKEND_HELP, Method, Preset, RigArg, Size, parse_backend};
use crate::dataset::DatasetOpener;
use crate::weights::Weights;

/// Specialise the bundled network to your rig: render data, fine-tune, report before/after.
///
/// Renders synthetic training data through the rig (`things` and `house` scenes, standard
/// and hard: flat and dark textures, per-camera gain, gamma, vignetting, blur and noise) and
/// two held-out sets of other seeds; scores the bundled network and ZNCC+SGM on the held-out
/// sets; fine-tunes the bundled network on the training data with a progress bar (Adam, the
/// learning rate dropping tenfold for the last third of the epochs, batch-norm statistics
/// frozen, small rig rotations, camera permutation and per-camera photometric augmentation);
/// then scores the fine-tuned weights on the same held-out frames and prints both tables.
///
/// RUN gets `finetune.json` (the options), `data/` (the rendered sets), `init/` (the bundled
/// weights it starts from), `train/` (the training run, as `omnimvs train` writes it),
/// `before/` and `after/` (`eval.json` and `eval.md` per held-out set), `report.md` and
/// `report.json`, and `model.safetensors` with its `.json`: the weights of the epoch with the
/// lowest validation MAE (the bundled weights if no epoch beat them), for `omnimvs infer
/// --weights RUN/model.safetensors`. Stopped at any moment, the same command (or `omnimvs
/// finetune --out RUN`) goes on where it stopped: finished frames, evaluations and epochs are
/// kept. `--epochs` may raise the total of a finished run.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The rig, as `synth --rig` takes it: a reference config.yaml, a Basalt
    /// calibration.json, a Kalibr camchain.yaml, `sunny` or `random:SEED`. Needed for a new
    /// run; a run folder remembers it. `--min-depth` and `--rig-frame` apply as in `synth`.
    #[arg(long, value_parser = RigArg::parse)]
    pub rig: Option<RigArg>,
    /// Run folder: a new one, or the folder of a run to continue.
    #[arg(long)]
    pub out: PathBuf,
    /// Training frames of each of the four training sets (things and house, standard and
    /// hard); the last tenth of them validates each epoch.
    #[arg(long)]
    pub frames: Option<u32>,
    /// Held-out frames of each of the two held-out sets (things and house).
    #[arg(long)]
    pub test_frames: Option<u32>,
    /// Epochs (may be raised when continuing a run).
    #[arg(long)]
    pub epochs: Option<usize>,
    /// Training steps per epoch at most (one frame each; an epoch is every training frame
    /// once).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Learning rate of the first two thirds of the epochs (then a tenth of it).
    #[arg(long)]
    pub lr: Option<f64>,
    /// Seed of the rendered scenes, the shuffling and the augmentation.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Render every camera's images at HxW instead of the rig's own size (the intrinsics are
    /// rescaled): quicker rendering and training, for a trial.
    #[arg(long)]
    pub size: Option<Size>,
    #[arg(long, value_parser = parse_backend, help = BACKEND_HELP)]
    pub backend: Option<Backend>,
}

/// What a run folder's `finetune.json` records: the options a continued run must keep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Plan {
    /// The rig as given, a file made absolute.
    rig: String,
    /// `calibration` or `fitted`.
    rig_frame: String,
    /// The sweep's minimum depth instead of the rig file's, metres.
    min_depth_m: Option<f64>,
    frames: u32,
    test_frames: u32,
    epochs: usize,
    steps: usize,
    lr: f64,
    seed: u64,
    /// `HxW` the images are rendered at; `None`: the rig's own sizes.
    size: Option<String>,
}

/// The defaults: on two CPU cores, 40 minutes for the compact four-camera example rig.
const FRAMES: u32 = 24;
const TEST_FRAMES: u32 = 5;
const EPOCHS: usize = 4;
const STEPS: usize = 150;
const LR: f64 = 3e-5;
const SEED: u64 = 1;
/// Validation frames per epoch at most.
const VAL_FRAMES: usize = 8;
/// The refinement stages' training window, in output columns: a quarter of the panorama, as
/// in the bundled network's own fine-tuning.
const COLUMN_WINDOW: usize = 160;

const PLAN_FILE: &str = "finetune.json";
/// The held-out sets' names in `data/`, `before/` and `after/`.
const TEST_SETS: [(&str, SceneKind); 2] = [
    ("test-things", SceneKind::Things),
    ("test-house", SceneKind::House),
];
const TRAIN_SETS: [(&str, SceneKind, Difficulty); 4] = [
    ("train-things", SceneKind::Things, Difficulty::Standard),
    ("train-house", SceneKind::House, Difficulty::Standard),
    ("train-things-hard", SceneKind::Things, Difficulty::Hard),
    ("train-house-hard", SceneKind::House, Difficulty::Hard),
];

impl Plan {
    /// The plan of a new run from the command line.
    fn new(args: &Args, rig: &RigArg, datasets: &DatasetOpener) -> Result<Self> {
        let options = datasets.options();
        Ok(Self {
            rig: rig_text(rig)?,
            rig_frame: options.frame.name().into(),
            min_depth_m: options.min_depth_m,
            frames: args.frames.unwrap_or(FRAMES),
            test_frames: args.test_frames.unwrap_or(TEST_FRAMES),
            epochs: args.epochs.unwrap_or(EPOCHS),
            steps: args.steps.unwrap_or(STEPS),
            lr: args.lr.unwrap_or(LR),
            seed: args.seed.unwrap_or(SEED),
            size: args.size.map(|s| s.to_string()),
        })
    }

    /// Checks the plan's values: frames and steps that a run can take.
    fn check(&self, path: &Path) -> Result<()> {
        let bad = |field: &str, expected: &str| {
            anyhow::anyhow!("{}: field `{field}`: expected {expected}", path.display())
        };
        if self.frames < 2 {
            return Err(bad("frames", "at least 2 training frames per set"));
        }
        if self.test_frames < 1 {
            return Err(bad("test_frames", "at least 1 held-out frame per set"));
        }
        if self.epochs < 1 || self.steps < 1 {
            return Err(bad("epochs, steps", "at least one epoch of one step"));
        }
        if !(self.lr.is_finite() && self.lr > 0.0) {
            return Err(bad("lr", "a positive learning rate"));
        }
        Ok(())
    }

    /// The rig and its options, as the plan states them.
    fn rig_source(&self) -> Result<omnimvs_synth::rig::RigSource> {
        let rig = RigArg::parse(&self.rig).map_err(anyhow::Error::msg)?;
        let frame = if self.rig_frame == FrameChoice::Fitted.name() {
            FrameChoice::Fitted
        } else {
            FrameChoice::Calibration
        };
        let mut source = rig
            .load(self.min_depth_m, frame)
            .with_context(|| format!("--rig {}", self.rig))?;
        if let Some(size) = &self.size {
            let size: Size = size.parse().map_err(anyhow::Error::msg)?;
            let (h, w) = (u32::try_from(size.height)?, u32::try_from(size.width)?);
            source = source.resized(h, w).context("--size")?;
        }
        Ok(source)
    }
}

/// `--rig` as the plan keeps it: a file as an absolute path, so that the run continues from
/// another folder.
fn rig_text(rig: &RigArg) -> Result<String> {
    Ok(match rig {
        RigArg::Config(path) => std::fs::canonicalize(path)
            .with_context(|| format!("--rig {}: reading the rig file", path.display()))?
            .to_string_lossy()
            .into_owned(),
        other => other.to_string(),
    })
}

/// The plan of the run in `out`, and whether it is new: a new one from the command line (not
/// written yet), or the stored one, checked against what the command line states.
fn plan(args: &Args, datasets: &DatasetOpener) -> Result<(Plan, bool)> {
    let path = args.out.join(PLAN_FILE);
    if !path.exists() {
        let Some(rig) = &args.rig else {
            bail!(
                "--rig is needed: {} holds no fine-tuning run to continue",
                args.out.display()
            );
        };
        let plan = Plan::new(args, rig, datasets)?;
        plan.check(&path)?;
        return Ok((plan, true));
    }
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    let mut stored: Plan = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: expected the options of a fine-tuning run",
            path.display()
        )
    })?;
    stored.check(&path)?;
    let options = datasets.options();
    let mut differs = Vec::new();
    if let Some(rig) = &args.rig
        && rig_text(rig)? != stored.rig
    {
        differs.push(format!("--rig (the run's: {})", stored.rig));
    }
    // `--rig-frame calibration` is the default and cannot be told from no option.
    if options.frame != FrameChoice::Calibration && options.frame.name() != stored.rig_frame {
        differs.push(format!("--rig-frame (the run's: {})", stored.rig_frame));
    }
    if options.min_depth_m.is_some() && options.min_depth_m != stored.min_depth_m {
        differs.push(format!("--min-depth (the run's: {:?})", stored.min_depth_m));
    }
    // Each option as given and as the run keeps it.
    let kept = [
        (
            "--frames",
            args.frames.map(|v| v.to_string()),
            stored.frames.to_string(),
        ),
        (
            "--test-frames",
            args.test_frames.map(|v| v.to_string()),
            stored.test_frames.to_string(),
        ),
        (
            "--steps",
            args.steps.map(|v| v.to_string()),
            stored.steps.to_string(),
        ),
        (
            "--lr",
            args.lr.map(|v| v.to_string()),
            stored.lr.to_string(),
        ),
        (
            "--seed",
            args.seed.map(|v| v.to_string()),
            stored.seed.to_string(),
        ),
        (
            "--size",
            args.size.map(|v| v.to_string()),
            stored
                .size
                .clone()
                .unwrap_or_else(|| "the rig's own".into()),
        ),
    ];
    for (flag, given, kept) in kept {
        if given.is_some_and(|given| given != kept) {
            differs.push(format!("{flag} (the run's: {kept})"));
        }
    }
    if !differs.is_empty() {
        bail!(
            "{} continues a run with other options: {}; leave them out to continue it, or \
             choose a new --out",
            path.display(),
            differs.join(", ")
        );
    }
    if let Some(epochs) = args.epochs
        && epochs != stored.epochs
    {
        if epochs < 1 {
            bail!("--epochs: expected at least 1");
        }
        stored.epochs = epochs;
        write_json(&path, &stored, true)?;
    }
    Ok((stored, false))
}

pub fn run(args: &Args, datasets: &DatasetOpener) -> Result<()> {
    let started = Instant::now();
    let (plan, new) = plan(args, datasets)?;
    let out = &args.out;
    let backend = match args.backend {
        Some(backend) => backend,
        None => crate::cmd::train::backend_of_run(&out.join("train"))?,
    };
    // Read before a new run's folder is made: a rig that cannot be read leaves none behind.
    let source = plan.rig_source()?;
    if new {
        std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
        write_json(&out.join(PLAN_FILE), &plan, true)?;
    }
    outln!(
        "fine-tuning the bundled network for {} ({} cameras) in {} on {backend}",
        plan.rig,
        source.rig.len(),
        out.display()
    );

    // 1. The data: four training sets and two held-out sets, of seeds apart.
    let data = out.join("data");
    let mut train_sets = Vec::new();
    for (k, (name, kind, difficulty)) in TRAIN_SETS.into_iter().enumerate() {
        let dir = data.join(name);
        let options = SynthOptions {
            difficulty,
            ..SynthOptions::new(kind, set_seed(plan.seed, k))
        };
        crate::cmd::synth::render(
            &dir,
            &source,
            &options,
            FrameRange::inclusive(1, plan.frames),
            Shard::ALL,
        )?;
        train_sets.push(dir);
    }
    for (k, (name, kind)) in TEST_SETS.into_iter().enumerate() {
        let options = SynthOptions::new(kind, set_seed(plan.seed, 50 + k));
        crate::cmd::synth::render(
            &data.join(name),
            &source,
            &options,
            FrameRange::inclusive(1, plan.test_frames),
            Shard::ALL,
        )?;
    }

    // 2. The bundled network as a file to start from.
    let init = write_bundled(&out.join("init"))?;

    // 3. The held-out figures before.
    let test_range = FrameRange::inclusive(1, plan.test_frames);
    let opener = DatasetOpener::default();
    for (name, _) in TEST_SETS {
        let dir = out.join("before").join(name);
        if !dir.join("eval.json").exists() {
            outln!("held-out {name}, before: the bundled network and ZNCC+SGM");
            evaluate(
                &opener,
                &data.join(name),
                test_range,
                &[Method::Net, Method::Sgm],
                Weights::Bundled(BundledModel::DEFAULT),
                PickChoice::Auto,
                backend,
                &dir,
            )?;
        }
    }

    // 4. Fine-tuning.
    let run_dir = out.join("train");
    let device = backend.device()?;
    let mut trainer = if run_dir.join("train_config.json").exists() {
        Trainer::<CascadeNet>::resume(&run_dir, Some(plan.epochs), &device)
            .with_context(|| format!("resuming {}", run_dir.display()))?
    } else {
        let config = train_config(&plan, train_sets, &init)?;
        Trainer::<CascadeNet>::create(config, &run_dir, &device)
            .with_context(|| format!("starting a run in {}", run_dir.display()))?
    };
    crate::cmd::train::record_backend(&run_dir, backend)?;
    crate::cmd::train::print_run(&trainer, backend);
    crate::cmd::train::run_epochs(&mut trainer, None)?;
    let best_epoch = trainer.state.best.map_or(0, |(epoch, _)| epoch);
    drop(trainer);

    // 5. The weights that answer best on validation, and the held-out figures after.
    let model = out.join("model.safetensors");
    copy_weights(&run_dir.join("best.safetensors"), &model)?;
    let after = out.join("after");
    let stamp = after.join("weights.txt");
    let stamp_text = format!("epoch {best_epoch}\n");
    if std::fs::read_to_string(&stamp).ok().as_deref() != Some(stamp_text.as_str()) {
        for (name, _) in TEST_SETS {
            outln!("held-out {name}, after: the fine-tuned network (epoch {best_epoch})");
            evaluate(
                &opener,
                &data.join(name),
                test_range,
                &[Method::Net],
                Weights::File(model.clone()),
                PickChoice::Off,
                backend,
                &after.join(name),
            )?;
        }
        write_text(&stamp, &stamp_text)?;
    }

    // 6. The report.
    let report = Report::read(out, &plan, best_epoch)?;
    let table = report.markdown();
    out!("{table}");
    write_json(&out.join("report.json"), &report, true)?;
    let md = out.join("report.md");
    write_text(&md, &table)?;
    outln!(
        "done in {:.0} s; weights {} (omnimvs infer DATASET --weights {}); report {}",
        started.elapsed().as_secs_f64(),
        model.display(),
        model.display(),
        md.display()
    );
    Ok(())
}

/// The scene seed of the `k`-th rendered set of a run of seed `seed`: training sets from
/// `100 seed`, held-out sets from `100 seed + 50`, so that no held-out scene is a training one.
fn set_seed(seed: u64, k: usize) -> u64 {
    seed.wrapping_mul(100).wrapping_add(k as u64)
}

/// Writes the bundled network's weights and configuration into `dir` (once) and returns the
/// weights' path.
fn write_bundled(dir: &Path) -> Result<PathBuf> {
    let model = BundledModel::DEFAULT;
    let weights = dir.join(format!("omnimvs-{}.safetensors", model.name()));
    let config = weights.with_extension("json");
    if !weights.exists() || !config.exists() {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        write_atomic(&config, model.config_json().as_bytes())
            .with_context(|| format!("writing {}", config.display()))?;
        write_atomic(&weights, model.bytes())
            .with_context(|| format!("writing {}", weights.display()))?;
    }
    Ok(weights)
}

/// Copies weights `from` (with its `.json`) to `to` (with its `.json`), each atomically.
fn copy_weights(from: &Path, to: &Path) -> Result<()> {
    for (from, to) in [
        (from.to_path_buf(), to.to_path_buf()),
        (from.with_extension("json"), to.with_extension("json")),
    ] {
        let bytes = std::fs::read(&from).with_context(|| format!("reading {}", from.display()))?;
        write_atomic(&to, &bytes).with_context(|| format!("writing {}", to.display()))?;
    }
    Ok(())
}

/// The training run of `plan` on `data`, from the bundled weights at `init`.
fn train_config(plan: &Plan, data: Vec<PathBuf>, init: &Path) -> Result<TrainConfig> {
    let net = read_config(&init.with_extension("json"))?;
    Ok(TrainConfig {
        net,
        data,
        epochs: plan.epochs,
        lr: plan.lr,
        lr_low: plan.lr / 10.0,
        optimizer: Optimizer::Adam,
        seed: plan.seed,
        max_steps_per_epoch: Some(plan.steps),
        max_val_frames: Some(VAL_FRAMES),
        init: Some(init.to_path_buf()),
        column_window: Some(COLUMN_WINDOW),
        photometric: Some(PhotometricAugment::default()),
        frozen_norm_stats: true,
        select_by: Selection::Reference,
        ..TrainConfig::default()
    })
}

/// Scores `methods` (the network with `weights` and `pick`) on `frames` of the dataset at
/// `data` at the paper's grid, and writes `eval.json` and `eval.md` into `out`.
#[allow(clippy::too_many_arguments)]
fn evaluate(
    opener: &DatasetOpener,
    data: &Path,
    frames: FrameRange,
    methods: &[Method],
    weights: Weights,
    pick: PickChoice,
    backend: Backend,
    out: &Path,
) -> Result<()> {
    let ds = opener.open(data)?;
    let frames = crate::cmd::eval::frames_with_truth(&ds, frames)?;
    let spec = ds.sweep_spec(160, 640, 45.0, 192)?;
    let rows = crate::cmd::eval::rows(
        &ds,
        methods,
        &[weights],
        &pick,
        Preset::Cascade,
        None,
        None,
        &backend,
        spec,
    )?;
    let report = crate::cmd::eval::evaluate(&ds, &frames, spec, rows, None)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    report.write(out)?;
    Ok(())
}

/// One row of the report: a method's means on one held-out set.
#[derive(Debug, Serialize, Deserialize)]
struct Row {
    set: String,
    method: String,
    /// The reference protocol (sky not scored).
    metrics: Metrics,
    /// Sky scored as index 0.
    metrics_with_sky: Metrics,
}

/// What `eval.json` gives the report.
#[derive(Deserialize)]
struct EvalFile {
    methods: Vec<EvalMethod>,
}

#[derive(Deserialize)]
struct EvalMethod {
    method: String,
    metrics: Metrics,
    metrics_with_sky: Metrics,
}

/// The before/after table (`report.json`, `report.md`).
#[derive(Debug, Serialize)]
struct Report {
    rig: String,
    test_frames: u32,
    /// The epoch whose weights are `model.safetensors` (0: the bundled weights).
    best_epoch: usize,
    rows: Vec<Row>,
}

impl Report {
    fn read(out: &Path, plan: &Plan, best_epoch: usize) -> Result<Self> {
        let mut rows = Vec::new();
        for (set, _) in TEST_SETS {
            for (stage, net) in [("before", "the bundled network"), ("after", "fine-tuned")] {
                let path = out.join(stage).join(set).join("eval.json");
                let text = std::fs::read_to_string(&path)
                    .with_context(|| format!("reading {}", path.display()))?;
                let file: EvalFile = serde_json::from_str(&text).with_context(|| {
                    format!("{}: expected an `omnimvs eval` report", path.display())
                })?;
                for m in file.methods {
                    rows.push(Row {
                        set: set.trim_start_matches("test-").into(),
                        method: if m.method == "net" {
                            net.into()
                        } else {
                            m.method
                        },
                        metrics: m.metrics,
                        metrics_with_sky: m.metrics_with_sky,
                    });
                }
            }
        }
        Ok(Self {
            rig: plan.rig.clone(),
            test_frames: plan.test_frames,
            best_epoch,
            rows,
        })
    }

    /// The table, with a line saying what it scores.
    fn markdown(&self) -> String {
        let mut text = format!(
            "Held-out frames 1-{} of each set, rig {}, at 160x640, N = 192, reference protocol \
             (the last column scores sky as index 0). Fine-tuned weights: {}.\n\n\
             | set | method | >1 % | >3 % | >5 % | MAE | RMS | MAE, sky scored |\n\
             |---|---|---:|---:|---:|---:|---:|---:|\n",
            self.test_frames,
            self.rig,
            if self.best_epoch == 0 {
                "none beat the bundled network on validation, so they are the bundled weights"
                    .to_string()
            } else {
                format!("epoch {}", self.best_epoch)
            }
        );
        for r in &self.rows {
            let m = &r.metrics;
            text.push_str(&format!(
                "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |\n",
                r.set,
                r.method,
                m.over1_pct,
                m.over3_pct,
                m.over5_pct,
                m.mae,
                m.rms,
                r.metrics_with_sky.mae
            ));
        }
        text
    }
}
