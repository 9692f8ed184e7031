//! [`Classifier`]: an exported model, its metadata, and a plan per batch size.

use std::collections::HashMap;
use std::panic::AssertUnwindSafe;
use std::path::Path;
use std::sync::{Arc, Mutex};

use tract_core::prelude::*;
use tract_core::runtime::RunOptions;
use tract_linalg::multithread::Executor;

use pvt3_format::{
    Budget, Header, FRAME_WEIGHTS, HEAD_FEATURES, HEAD_FRAMES, INPUT, LOGITS, PROBABILITIES, SPECTRAL_LOGITS, TOKEN_BIAS, TOKEN_ENCODINGS,
    TOKEN_FRAMES, TOKEN_INDEX,
};

use crate::error::{catch_panic, tract_error};
use crate::kernels::Kernels;
use crate::plan::Plan;
use crate::stages::{Head, Stages};
use crate::{Error, Result};
use pvt3_format::onnx::GraphProto;

/// The values one run of a plan may hold in its largest tensor (1 MiB of f32): a batch runs in
/// runs of as many windows as fit ([`Classifier::windows_per_run`]). Between 2¹⁷ and 2²⁰ the
/// shipped files ran alike, within this machine's noise, and each faster than whole batches of 32
/// (docs/results.md, "Batches in cache-sized runs").
const RUN_VALUES: usize = 1 << 18;

/// The answer for one window.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// Index of the most probable class.
    pub class: usize,
    /// Its name, from the model's metadata.
    pub label: String,
    /// Every class's probability, in the classes' order.
    pub probabilities: Vec<f32>,
}

/// An exported model, ready to classify: loaded from a file or bytes, its metadata read, its
/// plans built per batch size on first use (or by [`Classifier::prepare`]).
///
/// ```no_run
/// let classifier = pvt3_runtime::Classifier::load("model.onnx")?;
/// let window = vec![0.0f32; classifier.sample_shape().iter().product()];
/// let answer = classifier.classify(&window)?;
/// println!("{} ({:.3})", answer.label, answer.probabilities[answer.class]);
/// # Ok::<(), pvt3_runtime::Error>(())
/// ```
pub struct Classifier {
    graph: GraphProto,
    header: Header,
    /// The file's metadata, key and value, in the file's order.
    metadata: Vec<(String, String)>,
    sample_shape: Vec<usize>,
    /// What the file may make the runtime hold ([`pvt3_format::check_sizes`]): every tensor a
    /// plan computes is held to it before the plan is built.
    budget: Budget,
    plans: Mutex<HashMap<usize, Arc<Plan>>>,
    stages: Mutex<Option<Arc<Stages>>>,
    threads: usize,
    /// How plans choose their matrix-product kernels ([`crate::tune_kernels`]).
    kernels: Kernels,
    pub(crate) path: String,
}

/// The prediction for one row of probabilities.
pub(crate) fn prediction(classes: &[String], probabilities: &[f32]) -> Prediction {
    let class = pvt3_format::top_class(probabilities).0;
    Prediction { class, label: classes[class].clone(), probabilities: probabilities.to_vec() }
}

impl Classifier {
    /// Loads an `.onnx` written by `pvt3 export` (see [`Classifier::from_bytes`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let name = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|source| Error::Io { path: name.clone(), source })?;
        Self::from_bytes(&bytes, &name)
    }

    /// A model from the bytes of an `.onnx` file written by `pvt3 export`, named `name` in
    /// errors. The file's integrity digest is checked first (0.07 ms for the iCub model here,
    /// docs/deploy.md): a file altered or damaged after export, or one without a digest, is refused
    /// before anything parses it.
    pub fn from_bytes(bytes: &[u8], name: &str) -> Result<Self> {
        let name = name.to_string();
        pvt3_format::verify(bytes).map_err(|reason| Error::Corrupted { path: name.clone(), reason })?;
        let model = crate::onnx::decode(bytes).map_err(|reason| Error::NotOnnx { path: name.clone(), reason })?;
        let metadata: Vec<(String, String)> = model.metadata_props.into_iter().map(|e| (e.key, e.value)).collect();
        let entries = metadata.iter().map(|(k, v)| (k.as_str(), v.as_str()));
        let header = Header::parse(entries).map_err(|reason| Error::NotPvt3 { path: name.clone(), reason })?;
        // Every size the file declares, before anything that size is allocated.
        let graph = model.graph.unwrap_or_default();
        let budget = pvt3_format::check_sizes(&graph, &header, bytes.len())
            .map_err(|e| Error::NotOnnx { path: name.clone(), reason: e.to_string() })?;
        let sample_shape = header.sample_shape();
        let plans = Mutex::new(HashMap::new());
        let stages = Mutex::new(None);
        let kernels = Kernels::default();
        Ok(Self { graph, header, metadata, sample_shape, budget, plans, stages, threads: 1, kernels, path: name })
    }

    /// Runs on `threads` threads from now on (default 1; small models rarely gain from more).
    /// More than one needs the `threads` feature (on by default); without it, building a plan
    /// fails with [`Error::NoThreads`].
    pub fn with_threads(mut self, threads: usize) -> Self {
        self.set_threads(threads);
        self
    }

    /// [`Classifier::with_threads`] in place.
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads.max(1);
        self.forget_plans();
    }

    /// How each plan chooses its matrix-product kernels from now on ([`Kernels`]; by default
    /// [`Kernels::Fixed`], which gives the same outputs, bit for bit, at every load).
    pub fn with_kernels(mut self, kernels: Kernels) -> Self {
        self.set_kernels(kernels);
        self
    }

    /// [`Classifier::with_kernels`] in place.
    pub fn set_kernels(&mut self, kernels: Kernels) {
        self.kernels = kernels;
        self.forget_plans();
    }

    /// Drops the plans built so far, so that the next call builds them with the new settings.
    fn forget_plans(&mut self) {
        self.plans.get_mut().unwrap_or_else(|p| p.into_inner()).clear();
        *self.stages.get_mut().unwrap_or_else(|p| p.into_inner()) = None;
    }

    /// The class names, in the outputs' order.
    pub fn classes(&self) -> &[String] {
        &self.header.classes
    }

    /// The file's metadata, key and value, in the file's order: the `pvt3.` keys
    /// ([`pvt3_format::keys`]; `pvt3.provenance` holds how the model was trained and, for a
    /// `pvt3 final` file, the accuracy its cross-validation expects) and any other the file has.
    pub fn metadata(&self) -> &[(String, String)] {
        &self.metadata
    }

    /// The value of the metadata `key`, if the file has it.
    pub fn metadata_value(&self, key: &str) -> Option<&str> {
        self.metadata.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }

    /// One window: `[height, width, (channels,) frames]`.
    pub fn sample_shape(&self) -> &[usize] {
        &self.sample_shape
    }

    /// Frames per temporal token (the spatial stage encodes them together).
    pub fn tubelet(&self) -> usize {
        self.header.dims.tubelet
    }

    /// Width of a token's encoding (what the spatial stage hands the temporal one).
    pub(crate) fn dim(&self) -> usize {
        self.header.dims.dim
    }

    /// The stopping rule of provisional answers ([`crate::Peek::stop`]), calibrated by the
    /// trainer; `None` when the file has none.
    pub fn stop_rule(&self) -> Option<pvt3_format::StopRule> {
        self.header.stop_rule
    }

    /// How the model reads a touch (resampled to one speed, scaled to one force), if its training
    /// touches were brought to it; `None`: frames as the sensor records them.
    pub fn reading(&self) -> Option<crate::Reading> {
        self.header.reading
    }

    /// How a camera's 8-bit frames become the model's (`pvt3.camera`: crop, size, grey, less
    /// the touch's first frame), for a model trained on camera frames `pvt3 import` read from
    /// videos or images; `None`: frames are given as the model reads them.
    pub fn camera(&self) -> Option<crate::Camera> {
        self.header.camera
    }

    /// One of the camera's frames as [`crate::Session::push_camera_frame`] takes it, `[height,
    /// width, channels]`: the recorded frame for a model with a [`Self::camera`], one model frame
    /// otherwise.
    pub fn camera_frame_shape(&self) -> [usize; 3] {
        let d = &self.header.dims;
        self.header.camera.map_or([d.height, d.width, d.channels], |camera| camera.recorded)
    }

    /// Bytes in one of the camera's frames: [`Self::camera_frame_shape`]'s product.
    pub fn camera_frame_len(&self) -> usize {
        self.camera_frame_shape().iter().product()
    }

    /// A touch as the robot recorded it, in the sample layout (`[height, width, (channels,) n]`,
    /// any number `n` of frames), at the speed and force it commanded: the frames this model
    /// reads ([`crate::read_touch`], as the training's import read its touches). Windows of them
    /// are then classified, or streamed into a session, as any frames. A model without a
    /// reading returns the frames as they are.
    pub fn read_touch(&self, frames: &[f32], touch: crate::Touch) -> Result<Vec<f32>> {
        Ok(crate::read_touch(frames, self.frame_len(), &self.header.reading.unwrap_or_default(), touch)?)
    }

    /// The frames of a window the model reads; the others were pruned.
    pub fn kept_frames(&self) -> &[usize] {
        &self.header.kept_frames
    }

    fn sample_len(&self) -> usize {
        self.sample_shape.iter().product()
    }

    /// Values in one frame: the sample's axes but the last (frames).
    pub(crate) fn frame_len(&self) -> usize {
        self.sample_shape[..self.sample_shape.len() - 1].iter().product()
    }

    /// Whether the file's graph computes a tensor of this name (a seam).
    pub(crate) fn has_tensor(&self, name: &str) -> bool {
        self.graph.node.iter().any(|n| n.output.iter().any(|o| o == name))
    }

    /// The part of the graph from `sources` (tensor names with fixed facts) to `outputs`, as a
    /// tract model of `windows` windows: the whole model, or one streaming stage of it (one).
    pub(crate) fn wire(&self, sources: &[(&str, TypedFact)], outputs: &[&str], windows: usize) -> Result<TypedModel> {
        let wire = || crate::wire::typed_model(&self.graph, sources, outputs, self.budget, windows);
        catch_panic(AssertUnwindSafe(wire))?.map_err(|reason| Error::NotOnnx { path: self.path.clone(), reason })
    }

    /// `model` optimised, its kernels chosen, and made runnable on the caller's threads;
    /// `index_bounds` bounds the model's index inputs ([`crate::plan::optimised`]).
    pub(crate) fn optimise(&self, model: TypedModel, index_bounds: &[(&str, usize)]) -> Result<Plan> {
        let executor = match self.threads {
            1 => Executor::SingleThread,
            #[cfg(feature = "threads")]
            n => Executor::multithread(n),
            #[cfg(not(feature = "threads"))]
            n => return Err(Error::NoThreads { asked: n }),
        };
        let outputs = Plan::output_names(&model);
        let build = || {
            let mut model = crate::plan::optimised(model, index_bounds)?;
            crate::kernels::tune(&mut model, self.threads, self.kernels)?;
            model.into_runnable_with_options(&RunOptions { executor: Some(executor), ..Default::default() })
        };
        let plan = catch_panic(AssertUnwindSafe(build))?;
        plan.map(|plan| Plan::new(plan, outputs)).map_err(|e| Error::NotOnnx { path: self.path.clone(), reason: format!("{e:#}") })
    }

    /// Whether the file can be streamed (sessions, provisional answers): not a model whose
    /// spectral head reads the whole window (one exported before the head streamed, without
    /// `FRAME_WEIGHTS`: `Error::WholeWindowOnly`).
    pub fn streams(&self) -> bool {
        !self.has_tensor(SPECTRAL_LOGITS) || self.has_tensor(FRAME_WEIGHTS)
    }

    /// Builds now what the first call at each batch size of `batches`, and with `streaming` the
    /// first session, would otherwise build: tract's optimisation of each plan, tens of
    /// milliseconds (docs/deploy.md). A robot calls this at start-up, so that its first touch
    /// costs what every other touch costs. A batch larger than one run ([`Self::windows_per_run`])
    /// gets the plans of its runs.
    pub fn prepare(&self, batches: &[usize], streaming: bool) -> Result<()> {
        for &batch in batches {
            if batch == 0 {
                return Err(Error::EmptyBatch);
            }
            let per_run = self.windows_per_run()?;
            self.plan(batch.min(per_run))?;
            if batch > per_run && batch % per_run != 0 {
                self.plan(batch % per_run)?;
            }
        }
        if streaming {
            self.stages()?;
        }
        Ok(())
    }

    /// The tract model that the plan for `batch` windows is built from, before tract optimises
    /// it: for profiling (`bench/tools/src/bin/profile.rs`).
    pub fn tract_model(&self, batch: usize) -> Result<TypedModel> {
        self.wire(&[(INPUT, f32::fact(self.batch_shape(batch)))], &[LOGITS, PROBABILITIES], batch)
    }

    /// `[batch, height, width, (channels,) frames]`
    fn batch_shape(&self, batch: usize) -> Vec<usize> {
        std::iter::once(batch).chain(self.sample_shape.iter().copied()).collect()
    }

    /// The optimised plan for `batch` windows, built on first use.
    pub(crate) fn plan(&self, batch: usize) -> Result<Arc<Plan>> {
        let mut plans = self.plans.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(p) = plans.get(&batch) {
            return Ok(p.clone());
        }
        let plan = Arc::new(self.optimise(self.tract_model(batch)?, &[])?);
        plans.insert(batch, plan.clone());
        Ok(plan)
    }

    /// The spatial and temporal stages for streaming, built on first use.
    pub(crate) fn stages(&self) -> Result<Arc<Stages>> {
        let mut stages = self.stages.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(s) = stages.as_ref() {
            return Ok(s.clone());
        }
        let s = Arc::new(self.build_stages()?);
        *stages = Some(s.clone());
        Ok(s)
    }

    /// The spatial and temporal stages of this file, cut at its seam.
    fn build_stages(&self) -> Result<Stages> {
        if !self.streams() {
            return Err(Error::WholeWindowOnly);
        }
        let frames = *self.sample_shape().last().expect("a sample has a frame axis");
        let tubelet = self.tubelet();
        let mut kept_index = crate::heap::zeros(frames / tubelet, "the window's tokens")?;
        for (kk, f) in self.kept_frames().iter().step_by(tubelet).enumerate() {
            kept_index[f / tubelet] = Some(kk);
        }
        let kept = self.kept_frames().len() / tubelet;
        let frame = &self.sample_shape()[..self.sample_shape().len() - 1];
        let token_shape = vec![1, tubelet, frame[0], frame[1], frame.get(2).copied().unwrap_or(1)];
        let spatial = [(TOKEN_FRAMES, f32::fact(&token_shape)), (TOKEN_INDEX, i64::fact([1]))];
        let prefixes = self.has_tensor(TOKEN_BIAS);
        let mut temporal = vec![(TOKEN_ENCODINGS, f32::fact([kept, self.dim()]))];
        if prefixes {
            temporal.push((TOKEN_BIAS, f32::fact([1, 1, 1, kept_index.len() + 1])));
        }
        let head = self.has_tensor(FRAME_WEIGHTS).then(|| self.head(frames, &token_shape)).transpose()?;
        if let Some(head) = &head {
            temporal.push((head.input(), f32::fact(head.shape())));
        }
        Ok(Stages {
            // A session feeds the spatial stage the index of a kept token: below `kept`.
            spatial: self.optimise(self.wire(&spatial, &[TOKEN_ENCODINGS], 1)?, &[(TOKEN_INDEX, kept)])?,
            temporal: self.optimise(self.wire(&temporal, &[PROBABILITIES], 1)?, &[])?,
            prefixes,
            head,
            stop_rule: self.stop_rule(),
            camera: self.camera(),
            kept_index,
            token_shape,
            dim: self.dim(),
            classes: self.classes().to_vec(),
        })
    }

    /// What the streaming spectral head's temporal stage reads: each frame's features, computed
    /// frame by frame, where the file has the seams (`HEAD_FEATURES`); else the window so far.
    fn head(&self, frames: usize, token_shape: &[usize]) -> Result<Head> {
        if !self.has_tensor(HEAD_FEATURES) {
            return Ok(Head::Window(self.batch_shape(1)));
        }
        let frame = [&[1], &token_shape[2..]].concat();
        let model = self.wire(&[(HEAD_FRAMES, f32::fact(&frame))], &[HEAD_FEATURES], 1)?;
        let row =
            model.output_outlets().and_then(|o| model.outlet_fact(o[0])).ok().and_then(|f| f.shape.as_concrete().map(<[usize]>::to_vec));
        let row = row.filter(|r| r.first() == Some(&1)).ok_or_else(|| Error::NotOnnx {
            path: self.path.clone(),
            reason: format!("{HEAD_FEATURES} of one frame has no fixed shape [1, …]"),
        })?;
        let shape = [&[frames], &row[1..]].concat();
        Ok(Head::Features { plan: self.optimise(model, &[])?, shape })
    }

    fn validate(&self, frames: &[f32], batch: usize) -> Result<()> {
        if batch == 0 {
            return Err(Error::EmptyBatch);
        }
        let expected = batch.checked_mul(self.sample_len()).ok_or(Error::BatchTooLarge { batch })?;
        if frames.len() != expected {
            let sample = self.sample_shape.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" × ");
            return Err(Error::InputLength { got: frames.len(), expected, batch, sample });
        }
        if let Some((index, value)) = frames.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(Error::NonFinite { index, value: *value });
        }
        Ok(())
    }

    /// Logits and probabilities `[batch × classes]` each, for `batch` windows back to back: run
    /// [`Self::windows_per_run`] windows at a time.
    pub fn run(&self, frames: &[f32], batch: usize) -> Result<(Vec<f32>, Vec<f32>)> {
        self.validate(frames, batch)?;
        let per_run = self.windows_per_run()?;
        if batch <= per_run {
            return self.run_plan(frames, batch);
        }
        let (mut logits, mut probabilities) = (vec![], vec![]);
        for part in frames.chunks(per_run * self.sample_len()) {
            let (l, p) = self.run_plan(part, part.len() / self.sample_len())?;
            logits.extend(l);
            probabilities.extend(p);
        }
        Ok((logits, probabilities))
    }

    /// How many windows one run of a plan takes: as many as keep the plan's largest tensor within
    /// 2¹⁸ values (1 MiB, `RUN_VALUES`), at least one. tract runs each op over the whole batch,
    /// so a batch whose tensors outgrow the caches runs slower per window than its windows
    /// apart, as the camera model's spatial attention did (docs/results.md, "Batches in
    /// cache-sized runs").
    pub fn windows_per_run(&self) -> Result<usize> {
        let per_window = self.plan(1)?.largest_tensor().max(1);
        Ok((RUN_VALUES / per_window).max(1))
    }

    /// Logits and probabilities for `batch` windows in one run of the plan for `batch`.
    fn run_plan(&self, frames: &[f32], batch: usize) -> Result<(Vec<f32>, Vec<f32>)> {
        let input = Tensor::from_shape(&self.batch_shape(batch), frames).map_err(tract_error)?;
        let plan = self.plan(batch)?;
        let outputs = plan.run(tvec!(input.into()))?;
        let len = batch.checked_mul(self.classes().len()).ok_or(Error::BatchTooLarge { batch })?;
        Ok((plan.output(&outputs, 0, len)?, plan.output(&outputs, 1, len)?))
    }

    /// Classifies `batch` windows laid out back to back.
    pub fn classify_batch(&self, frames: &[f32], batch: usize) -> Result<Vec<Prediction>> {
        let (_, probabilities) = self.run(frames, batch)?;
        Ok(probabilities.chunks(self.classes().len()).map(|p| prediction(self.classes(), p)).collect())
    }

    /// Classifies one window.
    pub fn classify(&self, frames: &[f32]) -> Result<Prediction> {
        Ok(self.classify_batch(frames, 1)?.remove(0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A batch runs in runs of `windows_per_run` (6 windows for the shipped iCub file, so 14 run
    /// as 6, 6 and 2; one for the camera's), as `prepare` built them: no plan is built at the
    /// call, and each window's logits are its own, run alone, within 1e-5 of the largest. (Small
    /// batches: the aarch64 tests run this under qemu.)
    #[test]
    fn a_batch_runs_in_the_runs_prepare_built_and_answers_as_its_windows_alone() {
        let shipped = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shipped");
        for (file, per_run, batch) in [("icub20.onnx", 6, 14), ("physiclear.onnx", 1, 3)] {
            let c = Classifier::load(shipped.join(file)).unwrap();
            assert_eq!(c.windows_per_run().unwrap(), per_run, "{file}");
            c.prepare(&[batch], false).unwrap();
            let built = |c: &Classifier| {
                let mut sizes: Vec<usize> = c.plans.lock().unwrap().keys().copied().collect();
                sizes.sort();
                sizes
            };
            let prepared = built(&c);
            let len = c.sample_len();
            let frames: Vec<f32> = (0..batch * len).map(|i| ((i * 7919) % 1000) as f32 / 100.0).collect();
            let (logits, _) = c.run(&frames, batch).unwrap();
            assert_eq!(built(&c), prepared, "{file}: the call built no plan");
            let classes = c.classes().len();
            for (w, window) in frames.chunks(len).enumerate() {
                let (alone, _) = c.run(window, 1).unwrap();
                let largest = alone.iter().fold(0f32, |m, v| m.max(v.abs()));
                for (a, b) in alone.iter().zip(&logits[w * classes..(w + 1) * classes]) {
                    assert!((a - b).abs() <= 1e-5 * largest, "{file}, window {w}: {a} alone, {b} in the batch");
                }
            }
        }
    }
}
