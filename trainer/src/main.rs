//! `pvt3`: train, cross-validate, evaluate and inspect PVT³ tactile texture classifiers.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use pvt3_models::prune::{PruneSpec, Scope};
use pvt3_models::{Architecture, Classifier, Config};
use pvt3_trainer::anytime;
use pvt3_trainer::bench::train_speed;
use pvt3_trainer::checkpoint::{self, BakedFile};
use pvt3_trainer::cv::{self, cross_validate};
use pvt3_trainer::data::{Dataset, TEST_FOLD};
use pvt3_trainer::evaluate::{evaluate, Samples};
use pvt3_trainer::info::report;
use pvt3_trainer::options::TrainOptions;
use pvt3_trainer::prune::{prune_and_fine_tune, PruneStage};
use pvt3_trainer::train::{train, RunSpec};

#[derive(Parser)]
#[command(name = "pvt3", version, about = "PVT³ tactile texture classification: train, cross-validate, evaluate, inspect")]
struct Cli {
    /// CPU threads for training and evaluation (default: all cores). One run splits each batch's
    /// sequences over them (two threads: 1.5-1.7x one); `cv --jobs N` uses the cores best, one
    /// fold per thread. The result is the same bits on any count.
    #[arg(long, global = true)]
    threads: Option<usize>,
    #[command(subcommand)]
    command: Command,
}

/// Which data and which model.
#[derive(clap::Args)]
struct ModelArgs {
    /// Data set: an .npz file (x, y, optional fold) or a directory of x.npy, y.npy, fold.npy.
    #[arg(long, default_value = "data/icub20.npz")]
    data: PathBuf,
    /// Network: PVT³, or one of the paper's baselines (RAEC as published: add `--lr 5e-4
    /// --weight-decay 0`). Takes the `vit-`/`raec-` variant of the sensor preset; only PVT³ can
    /// be pruned and exported.
    #[arg(long = "model", value_name = "MODEL", value_enum, conflicts_with = "config")]
    architecture: Option<Architecture>,
    /// Model preset (icub20, biotac20, gelsight, each also as vit-NAME and raec-NAME); by default
    /// the one whose input fits the data.
    #[arg(long, conflicts_with = "config")]
    preset: Option<String>,
    /// Model configuration as JSON (see `pvt3 info --json`).
    #[arg(long)]
    config: Option<PathBuf>,
    /// Override one configuration field, e.g. `--set tubelet=5 --set dim=32` (repeatable).
    #[arg(long = "set", value_name = "FIELD=VALUE")]
    overrides: Vec<String>,
    /// Class names, one per line (default: class_0, class_1, …).
    #[arg(long)]
    class_names: Option<PathBuf>,
    /// Stop after this many epochs (per run), leaving the work to be continued with --resume.
    #[arg(long)]
    pause_after: Option<usize>,
    #[command(flatten)]
    options: TrainOptions,
}

/// Pruning after training (the paper's schedule: train, prune, fine-tune).
#[derive(clap::Args)]
struct PruneArgs {
    /// Prune this percentage of channels (attention q/k/v channels and FFN units) by mask score.
    #[arg(long)]
    prune_channels: Option<f64>,
    /// Prune this percentage of frames (temporal tokens) by mask score.
    #[arg(long)]
    prune_frames: Option<f64>,
    /// Persistent random pruning (the PVT³ report's "random pruning"): this percentage of every
    /// weight matrix's entries set to zero at random after training, then fine-tuned with them
    /// held at zero. A regulariser: the matrices stay dense, the model no smaller.
    #[arg(long)]
    prune_weights: Option<f64>,
    /// How --prune-channels shares the pruning among the masks.
    #[arg(long, value_enum, default_value_t = Scope::Local)]
    prune_scope: Scope,
    /// Epochs of fine-tuning after pruning, pruned entries held at zero.
    #[arg(long, default_value_t = 30)]
    fine_tune_epochs: usize,
    /// Peak learning rate of the fine-tuning.
    #[arg(long, default_value_t = 5e-4)]
    fine_tune_lr: f64,
}

impl PruneArgs {
    fn stage(&self) -> Option<PruneStage> {
        if self.prune_channels.is_none() && self.prune_frames.is_none() && self.prune_weights.is_none() {
            return None;
        }
        Some(PruneStage {
            spec: PruneSpec {
                channels: self.prune_channels.unwrap_or(0.0),
                frames: self.prune_frames.unwrap_or(0.0),
                scope: self.prune_scope,
                weights: self.prune_weights.unwrap_or(0.0),
            },
            epochs: self.fine_tune_epochs,
            lr: self.fine_tune_lr,
        })
    }
}

#[derive(Subcommand)]
enum Command {
    /// Train on one split: fold K validates (epoch selection), fold 4 tests, the rest trains.
    Train {
        #[command(flatten)]
        model: ModelArgs,
        /// Validation fold (0..3).
        #[arg(long, default_value_t = 0)]
        fold: usize,
        /// Run directory (checkpoint in OUT/model, resume state in OUT/last, metrics.jsonl).
        #[arg(long, short, default_value = "runs/train")]
        out: PathBuf,
        /// Continue the interrupted run in OUT.
        #[arg(long)]
        resume: bool,
        /// With --prune-channels/--prune-frames: prune the trained model and fine-tune it into OUT/pruned.
        #[command(flatten)]
        prune: PruneArgs,
        /// Finally bake the model (the pruned one, if pruning was asked for) and export it as ONNX.
        #[arg(long, value_name = "FILE.onnx")]
        export: Option<PathBuf>,
    },
    /// The published protocol: 4-fold cross-validation, test on fold 4, mean ± std over seeds.
    Cv {
        #[command(flatten)]
        model: ModelArgs,
        /// Seeds to repeat the four folds with, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "0")]
        seeds: Vec<u64>,
        #[arg(long, short, default_value = "runs/cv")]
        out: PathBuf,
        /// Continue: finished folds are kept, an interrupted one resumes.
        #[arg(long)]
        resume: bool,
        /// Folds trained side by side (each on one thread).
        #[arg(long, default_value_t = 1)]
        jobs: usize,
        /// With --prune-channels/--prune-frames: every fold is also pruned and fine-tuned
        /// (OUT/seed*/fold*/pruned), and both results are reported.
        #[command(flatten)]
        prune: PruneArgs,
        /// Train this one run alone, `seed=S,fold=K` (one job of a job array, e.g.
        /// bench/slurm/cv.sbatch, writing into the shared OUT), then report every finished run
        /// there. Instead of --seeds.
        #[arg(long, value_parser = parse_only, conflicts_with = "seeds")]
        only: Option<(u64, usize)>,
        /// Train nothing: report the finished runs under this directory (cv.json and the table),
        /// whoever trained them. Runs still training are listed, not counted.
        #[arg(long, value_name = "OUT", conflicts_with_all = ["only", "resume"])]
        report: Option<PathBuf>,
    },
    /// Prune a trained run by its mask scores, then fine-tune it with the pruned entries held at zero.
    Prune {
        /// The trained run (or checkpoint) directory.
        run: PathBuf,
        /// Data set (default: the one the run was trained on).
        #[arg(long)]
        data: Option<PathBuf>,
        #[arg(long, short, default_value = "runs/pruned")]
        out: PathBuf,
        #[arg(long)]
        resume: bool,
        #[command(flatten)]
        prune: PruneArgs,
    },
    /// Write a model as one ONNX file (opset 17): raw frames in, normalisation and kept-frame
    /// selection inside, logits and probabilities out.
    Export {
        /// A run or checkpoint directory (baked on the way), or a file written by `pvt3 bake`.
        model: PathBuf,
        #[arg(long, short, default_value = "model.onnx")]
        out: PathBuf,
    },
    /// Bake a (pruned) checkpoint into a smaller dense model: pruned channels and frames removed.
    Bake {
        /// The run (or checkpoint) directory.
        run: PathBuf,
        /// Output file (JSON: the baked weights, normalisation, class names, provenance).
        #[arg(long, short, default_value = "baked.json")]
        out: PathBuf,
    },
    /// Accuracy of a checkpoint on a data set (by default its test fold, or all samples).
    Eval {
        /// Checkpoint directory (or a run directory holding model/).
        checkpoint: PathBuf,
        /// The data set; by default the one the checkpoint was trained on.
        #[arg(long)]
        data: Option<PathBuf>,
        /// Which samples: a fold number, or `all`.
        #[arg(long, default_value = "4")]
        fold: String,
        /// Provisional answers (PVT³): accuracy from the first 10 %, 20 % … of each touch, and
        /// what the checkpoint's stopping rule (calibrated on its validation fold) does here.
        #[arg(long)]
        anytime: bool,
        /// With --anytime: print one JSON object instead of the table.
        #[arg(long, requires = "anytime")]
        json: bool,
    },
    /// Benchmarks (see docs/training-speed.md).
    #[command(subcommand)]
    Bench(Bench),
    /// Parameters, multiply-adds and tensor shapes of a preset, a JSON config or a checkpoint.
    Info {
        /// A preset name, a config .json, or a checkpoint directory.
        #[arg(default_value = "icub20")]
        model: String,
        /// Print the configuration as JSON instead.
        #[arg(long)]
        json: bool,
    },
}

/// Process settings, before any other thread starts.
/// - Memory: candle allocates fresh buffers for every op, and glibc hands large ones back to the
///   kernel on free, so training spent a quarter of its time in page faults zeroing new pages.
///   Keeping freed memory in the heap makes the next step reuse it.
/// - SIGPIPE back to its default, so that `pvt3 info | head` ends quietly instead of panicking.
fn set_up_process() {
    // SAFETY: both only adjust process-wide settings, and no other thread exists yet.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 32 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 1 << 30);
        libc::mallopt(libc::M_TOP_PAD, 64 << 20);
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

#[derive(Subcommand)]
enum Bench {
    /// Training throughput of a preset in candle on random inputs, as one JSON line.
    Train {
        #[arg(long, default_value = "icub20")]
        preset: String,
        /// Timed optimiser steps (after two untimed warm-up steps).
        #[arg(long, default_value_t = 20)]
        steps: usize,
        /// Run the model composed of candle ops instead of its fused ops (each transformer block,
        /// the embedding), to measure what the fusion gains (the same function).
        #[arg(long)]
        composed: bool,
        #[command(flatten)]
        options: TrainOptions,
    },
    /// Numerical stress of the robot runtime: the exported model's f32 logits against the baked
    /// f64 reference on extreme inputs and folded weights; prints a markdown table (docs/benchmarks.md).
    Stress {
        /// A run or checkpoint directory, or a file from `pvt3 bake`.
        model: PathBuf,
        /// Random windows per case.
        #[arg(long, default_value_t = 8)]
        windows: usize,
    },
}

fn main() -> Result<()> {
    set_up_process();
    let cli = Cli::parse();
    let jobs = match &cli.command {
        Command::Cv { jobs, .. } => *jobs,
        _ => 1,
    };
    // candle reads the thread count from RAYON_NUM_THREADS; it must be set before its first use.
    let threads = cli.threads.or((jobs > 1).then_some(1));
    if let Some(t) = threads {
        std::env::set_var("RAYON_NUM_THREADS", t.to_string());
    }
    match cli.command {
        Command::Train { model, fold, out, resume, prune, export } => {
            let prepared = prepare(&model)?;
            if prune.stage().is_some() || export.is_some() {
                prepared.config.require_pvt3("pruning and export")?;
            }
            let bar = ProgressBar::new(0).with_style(bar_style());
            bar.set_prefix(format!("fold {fold}"));
            let started = Instant::now();
            let r = train(&prepared.spec(&model, fold), &out, resume, &bar)?;
            bar.finish();
            let Some(r) = r else {
                println!("paused; continue with the same command and --resume");
                return Ok(());
            };
            println!(
                "best epoch {} of {}: validation accuracy {:.4}, test accuracy {:.4} ({:.0} s); checkpoint {}",
                r.best_epoch,
                r.epochs,
                r.val_accuracy,
                r.test_accuracy,
                started.elapsed().as_secs_f64(),
                out.join("model").display()
            );
            if let Some(stage) = prune.stage() {
                let bar = ProgressBar::new(0).with_style(bar_style());
                bar.set_prefix("fine-tune");
                let pruned = out.join("pruned");
                let Some(p) = prune_and_fine_tune(&out, &prepared.data, &stage, &pruned, resume, &bar)? else {
                    println!("paused; continue with the same command and --resume");
                    return Ok(());
                };
                bar.finish();
                report_pruned(&p, &pruned)?;
            }
            if let Some(path) = export {
                let final_run = if prune.stage().is_some() { out.join("pruned") } else { out.clone() };
                export_onnx(&final_run, &path)?;
            }
        }
        Command::Prune { run, data, out, resume, prune } => {
            let stage = prune.stage().context("give --prune-channels, --prune-frames and/or --prune-weights")?;
            let (_, meta) = checkpoint::load_meta(&run)?;
            let data_path = data.unwrap_or_else(|| PathBuf::from(&meta.provenance.data));
            let dataset = Dataset::load(&data_path, meta.provenance.seed)?;
            let bar = ProgressBar::new(0).with_style(bar_style());
            bar.set_prefix("fine-tune");
            if let Some(p) = prune_and_fine_tune(&run, &dataset, &stage, &out, resume, &bar)? {
                bar.finish();
                report_pruned(&p, &out)?;
            }
        }
        Command::Bake { run, out } => {
            let file = BakedFile::from_checkpoint(&run)?;
            checkpoint::write_json_atomically(&out, &file)?;
            println!(
                "baked {}: {} → {} parameters, {} → {} multiply-adds per sample, {} of {} temporal tokens kept",
                out.display(),
                file.baked.config.parameter_count() + file.baked.config.time_tokens(),
                file.baked.parameter_count(),
                file.baked.config.mult_adds(),
                file.baked.mult_adds(),
                file.baked.kept_tokens.len(),
                file.baked.config.time_tokens()
            );
        }
        Command::Cv { model, seeds, out, resume, jobs, prune, only, report } => {
            let started = Instant::now();
            let (s, out) = match report {
                Some(dir) => (cv::report(&dir)?, dir),
                None => {
                    let prepared = prepare(&model)?;
                    if prune.stage().is_some() {
                        prepared.config.require_pvt3("pruning")?;
                    }
                    let multi = MultiProgress::new();
                    let spec = prepared.spec(&model, 0);
                    let stage = prune.stage();
                    let s = match only {
                        Some(one) => match cross_validate(&spec, stage.as_ref(), &[one], &out, resume, 1, &multi, &bar_style())? {
                            Some(_) => Some(cv::report(&out)?),
                            None => None,
                        },
                        None => cross_validate(&spec, stage.as_ref(), &cv::protocol(&seeds), &out, resume, jobs, &multi, &bar_style())?,
                    };
                    let Some(s) = s else {
                        println!("paused; continue with the same command and --resume");
                        return Ok(());
                    };
                    (s, out)
                }
            };
            for dir in &s.unfinished {
                println!("not finished, not counted: {dir}");
            }
            println!("{:>6} {:>5} {:>6} {:>8} {:>8} {:>8} {:>12}", "seed", "fold", "epoch", "val", "test", "seconds", "pruned test");
            for (i, r) in s.runs.iter().enumerate() {
                let pruned = s.pruned_runs.get(i).map_or(String::new(), |p| format!("{:.4}", p.test_accuracy));
                println!(
                    "{:>6} {:>5} {:>6} {:>8.4} {:>8.4} {:>8.0} {:>12}",
                    r.seed, r.val_fold, r.best_epoch, r.val_accuracy, r.test_accuracy, r.wall_seconds, pruned
                );
            }
            if let (Some(m), Some(sd)) = (s.pruned_mean_test_accuracy, s.pruned_std_test_accuracy) {
                let interval =
                    s.pruned_ci95_test_accuracy.map_or(String::new(), |[lo, hi]| format!(", 95 % confidence interval [{lo:.4}, {hi:.4}]"));
                println!("pruned and fine-tuned: mean test accuracy {m:.4} ± {sd:.4} over {} runs{interval}", s.pruned_runs.len());
            }
            println!(
                "mean test accuracy {:.4} ± {:.4} over {} runs (wall {:.0} s); summary {}",
                s.mean_test_accuracy,
                s.std_test_accuracy,
                s.runs.len(),
                started.elapsed().as_secs_f64(),
                out.join("cv.json").display()
            );
            if let Some([lo, hi]) = s.ci95_test_accuracy {
                let means: Vec<String> = s.seed_means.iter().map(|m| format!("{m:.4}")).collect();
                println!(
                    "95 % confidence interval of the mean [{lo:.4}, {hi:.4}] (Student's t over the seeds' means {})",
                    means.join(", ")
                );
            }
        }
        Command::Eval { checkpoint, data, fold, anytime, json } => eval(&checkpoint, data.as_deref(), &fold, anytime, json)?,
        Command::Export { model, out } => export_onnx(&model, &out)?,
        Command::Bench(Bench::Train { preset, steps, composed, options }) => {
            pvt3_models::transformer::use_composed_ops(composed);
            let mut speed = train_speed(&Config::preset(&preset)?, &options, 2, steps)?;
            if composed {
                speed.framework = "candle, composed ops";
            }
            println!("{}", serde_json::to_string(&speed)?);
        }
        Command::Bench(Bench::Stress { model, windows }) => {
            let file = BakedFile::load(&model).with_context(|| format!("loading {}", model.display()))?;
            let scratch = std::env::temp_dir().join(format!("pvt3-stress-{}", std::process::id()));
            std::fs::create_dir_all(&scratch)?;
            let rows = pvt3_trainer::stress::stress(&file, windows, false, &scratch);
            std::fs::remove_dir_all(&scratch)?;
            print!("{}", pvt3_trainer::stress::table(&rows?));
        }
        Command::Info { model, json } => {
            // A PVT³ checkpoint is read once: its configuration, and its size after baking.
            let cfg = resolve_config(&model)?;
            let baked = match Path::new(&model).is_dir() && cfg.model == Architecture::Pvt3 {
                true => Some(BakedFile::from_checkpoint(Path::new(&model))?.baked),
                false => None,
            };
            if json {
                println!("{}", serde_json::to_string_pretty(&cfg)?);
            } else {
                print!("{}", report(&cfg)?);
                if let Some(b) = baked {
                    println!("\nafter baking  {}", b.size_summary());
                }
            }
        }
    }
    Ok(())
}

/// Bakes (if needed) and exports `model` to `out`.
fn export_onnx(model: &Path, out: &Path) -> Result<()> {
    let file = BakedFile::load(model)?;
    let onnx = pvt3_export::export(&file.baked, &file.normalization, &file.metadata())
        .with_context(|| format!("exporting {}", model.display()))?;
    pvt3_export::write(&onnx, out)?;
    println!("wrote {}: {}", out.display(), file.baked.size_summary());
    Ok(())
}

fn report_pruned(r: &pvt3_trainer::train::RunResult, out: &Path) -> Result<()> {
    let baked = BakedFile::from_checkpoint(out)?.baked;
    println!(
        "pruned and fine-tuned: best epoch {} of {}, validation {:.4}, test {:.4}; baked: {}; checkpoint {}",
        r.best_epoch,
        r.epochs,
        r.val_accuracy,
        r.test_accuracy,
        baked.size_summary(),
        out.join("model").display()
    );
    Ok(())
}

fn bar_style() -> ProgressStyle {
    ProgressStyle::with_template("{prefix:>14} [{elapsed_precise}] {bar:30} {percent:>3}% eta {eta} {msg}").expect("a valid template")
}

/// A preset name, a JSON file, or a checkpoint directory.
fn resolve_config(model: &str) -> Result<Config> {
    let path = Path::new(model);
    if path.is_dir() {
        return Ok(checkpoint::load_meta(path)?.1.config);
    }
    if path.is_file() {
        let text = std::fs::read_to_string(path).with_context(|| format!("reading {model}"))?;
        return serde_json::from_str(&text).with_context(|| format!("{model} is not a model configuration"));
    }
    Ok(Config::preset(model)?)
}

/// A loaded data set with the model configuration and class names for it.
struct Prepared {
    data: Dataset,
    config: Config,
    classes: Vec<String>,
}

impl Prepared {
    fn spec(&self, args: &ModelArgs, val_fold: usize) -> RunSpec<'_> {
        RunSpec {
            data: &self.data,
            config: self.config.clone(),
            val_fold,
            options: args.options.clone(),
            classes: self.classes.clone(),
            pause_after: args.pause_after,
            start: None,
            pruning: None,
        }
    }
}

/// Loads the data set and builds the model configuration for it.
fn prepare(args: &ModelArgs) -> Result<Prepared> {
    let data = Dataset::load(&args.data, args.options.seed)?;
    // `--model vit` turns preset `icub20` into `vit-icub20`.
    let architecture = args.architecture.unwrap_or_default();
    let preset = |name: &str| match architecture {
        Architecture::Pvt3 => Config::preset(name),
        model => Config::preset(&format!("{}-{name}", model.name())),
    };
    let mut cfg = match (&args.preset, &args.config) {
        (Some(p), _) => preset(p)?,
        (None, Some(path)) => resolve_config(&path.display().to_string())?,
        (None, None) => match pvt3_models::config::PRESETS
            .iter()
            .map(|p| preset(p).expect("known preset"))
            .find(|c| c.sample_shape() == data.sample_shape)
        {
            Some(cfg) => cfg,
            None => {
                let shape = data.sample_shape.iter().map(|d| d.to_string()).collect::<Vec<_>>().join(" × ");
                let derived = Config::for_sensor(&data.sample_shape)
                    .with_context(|| format!("samples of shape {shape}: expected [height, width, (channels,) frames]"))?;
                eprintln!(
                    "no preset takes samples of {shape}: derived the BioTac layout, one token per {} frames of all {} values of a frame ({} temporal tokens); `pvt3 info --json` and --config FILE to choose otherwise",
                    derived.tubelet,
                    derived.height * derived.width * derived.channels,
                    derived.time_tokens()
                );
                derived.for_model(architecture)
            }
        },
    };
    cfg.classes = data.classes();
    cfg = apply_overrides(cfg, &args.overrides)?;
    cfg.validate()?;
    let prefix = args.options.prefix_training;
    if !(0.0..=1.0).contains(&prefix) {
        bail!("--prefix-training {prefix}: a probability, from 0 to 1");
    }
    if prefix > 0.0 {
        cfg.require_pvt3("--prefix-training")?;
    }
    let classes = match &args.class_names {
        Some(path) => {
            let text = std::fs::read_to_string(path).with_context(|| format!("reading class names from {}", path.display()))?;
            let names: Vec<String> = text.lines().map(str::trim).filter(|l| !l.is_empty()).map(String::from).collect();
            if names.len() != cfg.classes {
                bail!("{} names {} classes, the data has {}", path.display(), names.len(), cfg.classes);
            }
            names
        }
        None => (0..cfg.classes).map(|k| format!("class_{k}")).collect(),
    };
    if !data.folds_from_file {
        eprintln!("note: {} has no fold array; stratified folds were drawn with seed {}", data.path.display(), args.options.seed);
    }
    Ok(Prepared { data, config: cfg, classes })
}

fn apply_overrides(cfg: Config, overrides: &[String]) -> Result<Config> {
    let mut value = serde_json::to_value(&cfg)?;
    for o in overrides {
        let (key, raw) = o.split_once('=').with_context(|| format!("--set {o}: expected FIELD=VALUE"))?;
        let fields = value.as_object_mut().expect("a config is a JSON object");
        if !fields.contains_key(key) {
            let known: Vec<&String> = fields.keys().collect();
            bail!("--set {o}: unknown field `{key}`; the fields are {known:?}");
        }
        let parsed = serde_json::from_str(raw).with_context(|| format!("--set {o}: `{raw}` is not a number"))?;
        fields.insert(key.to_string(), parsed);
    }
    serde_json::from_value(value).context("the overridden configuration does not parse")
}

fn eval(checkpoint_path: &Path, data_path: Option<&Path>, fold: &str, anytime: bool, json: bool) -> Result<()> {
    let (meta, model, _) = checkpoint::load(checkpoint_path)?;
    let own = PathBuf::from(&meta.provenance.data);
    let data_path = data_path.unwrap_or(&own);
    let data = Dataset::load(data_path, meta.provenance.seed).with_context(|| format!("loading {}", data_path.display()))?;
    data.check_fits(&meta.config)?;
    let indices: Vec<usize> = if fold == "all" {
        (0..data.len()).collect()
    } else {
        let k: usize = fold.parse().with_context(|| format!("--fold {fold}: expected a fold number or `all`"))?;
        (0..data.len()).filter(|&i| data.folds[i] == k).collect()
    };
    if indices.is_empty() {
        bail!("fold {fold} of {} holds no samples", data_path.display());
    }
    let samples = Samples::new(&data, &indices, &meta.normalization);
    if anytime {
        return eval_anytime(&meta, &model, &data, &samples, fold, json);
    }
    let e = evaluate(&model, &samples)?;
    println!("{} samples (fold {fold}): accuracy {:.4}, loss {:.4}", samples.len(), e.accuracy, e.loss);
    if let (true, Some(test)) = (fold.parse::<usize>().ok() == Some(TEST_FOLD), meta.provenance.test_accuracy) {
        println!("(the checkpoint's own record: test accuracy {test:.4})");
    }
    println!("{:<24} {:>8} {:>8}", "class", "samples", "accuracy");
    for (c, name) in meta.classes.iter().enumerate() {
        let rows: Vec<usize> = (0..samples.len()).filter(|&r| samples.labels[r] as usize == c).collect();
        if rows.is_empty() {
            continue;
        }
        let ok = rows.iter().filter(|&&r| e.predictions[r] as usize == c).count();
        println!("{:<24} {:>8} {:>8.3}", name, rows.len(), ok as f64 / rows.len() as f64);
    }
    Ok(())
}

/// `pvt3 eval --anytime`: accuracy against the share of the touch, and the stopping rule
/// calibrated on the checkpoint's own validation fold (what training records, and the exported
/// file carries) applied to `samples`.
fn eval_anytime(meta: &checkpoint::Meta, model: &Classifier, data: &Dataset, samples: &Samples, fold: &str, json: bool) -> Result<()> {
    let pvt3 = model.pvt3("pvt3 eval --anytime")?;
    let prefixes = anytime::prefixes(pvt3, samples)?;
    // The rule training recorded; a run from before there was one is calibrated here the same way.
    let calibrated = match &meta.provenance.stopping {
        Some(recorded) => recorded.clone(),
        None => {
            let val = Samples::new(data, &data.split(meta.provenance.val_fold)?.val, &meta.normalization);
            anytime::prefixes(pvt3, &val)?.calibrate()
        }
    };
    let here = prefixes.stop_by(calibrated.rule);
    let t = prefixes.tokens;
    let curve: Vec<(f64, usize, f64)> = (1..=10)
        .map(|tenth| {
            let k = (tenth * t).div_ceil(10).max(1);
            (tenth as f64 / 10.0, k, prefixes.accuracy_at(k))
        })
        .collect();
    if json {
        let curve: Vec<_> = curve.iter().map(|(share, k, acc)| serde_json::json!({"share": share, "tokens": k, "accuracy": acc})).collect();
        let out = serde_json::json!({
            "samples": samples.len(), "fold": fold, "tokens": t, "curve": curve,
            "calibrated": calibrated, "stopping": here,
        });
        println!("{out}");
        return Ok(());
    }
    println!("provisional answers on {} samples (fold {fold}), {t} temporal tokens per touch", samples.len());
    println!("{:>8} {:>7} {:>9}", "touch", "tokens", "accuracy");
    for (share, k, acc) in &curve {
        println!("{:>7.0}% {k:>7} {acc:>9.4}", share * 100.0);
    }
    let rule = calibrated.rule;
    println!(
        "stopping rule: top probability ≥ {:.4} with {} answers in a row agreeing (validation fold {}: accuracy {:.4} against {:.4} for the whole touch, {:.0} % of the touch used)",
        rule.top_probability,
        rule.agreeing,
        meta.provenance.val_fold,
        calibrated.accuracy,
        calibrated.full_accuracy,
        calibrated.mean_share * 100.0
    );
    println!(
        "here: accuracy {:.4} against {:.4} for the whole touch, {:.1} % of the touch used on average",
        here.accuracy,
        here.full_accuracy,
        here.mean_share * 100.0
    );
    Ok(())
}

/// `--only seed=S,fold=K`.
fn parse_only(text: &str) -> std::result::Result<(u64, usize), String> {
    let mut seed_fold = (None, None);
    for part in text.split(',') {
        match part.trim().split_once('=') {
            Some(("seed", v)) => seed_fold.0 = v.parse::<u64>().ok(),
            Some(("fold", v)) => seed_fold.1 = v.parse::<usize>().ok().filter(|k| *k < TEST_FOLD),
            _ => return Err(format!("`{part}`: expected seed=S,fold=K")),
        }
    }
    match seed_fold {
        (Some(s), Some(k)) => Ok((s, k)),
        _ => Err(format!("`{text}`: expected seed=S,fold=K with a validation fold from 0 to {}", TEST_FOLD - 1)),
    }
}
