//! The C ABI (`include/pvt3.h`): opaque classifier and streaming-session handles, status codes, and a last-error
//! message per thread. Every entry point catches panics, so none crosses into C: a panic is
//! reported as `PVT3_ERR_INTERNAL` with its message.

use std::cell::RefCell;
use std::ffi::{c_char, c_int, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::OnceLock;

use crate::{Classifier, Continuous, Error, Kernels, Prediction, Session};

/// Success.
pub const PVT3_OK: c_int = 0;
/// A pointer the call needs is null.
pub const PVT3_ERR_NULL: c_int = 1;
/// A file could not be read.
pub const PVT3_ERR_IO: c_int = 2;
/// Not a model this library runs: damaged, foreign, of another format.
pub const PVT3_ERR_MODEL: c_int = 3;
/// An argument or input the model cannot take.
pub const PVT3_ERR_INPUT: c_int = 4;
/// A fault inside the library.
pub const PVT3_ERR_INTERNAL: c_int = 5;
/// Kernels by a fixed rule: the same outputs, bit for bit, at every load ([`Kernels::Fixed`]).
pub const PVT3_KERNELS_FIXED: c_int = 0;
/// tract's own choice of kernels ([`Kernels::Tract`]).
pub const PVT3_KERNELS_TRACT: c_int = 1;
/// Kernels timed at each plan's first call ([`Kernels::Measured`]).
pub const PVT3_KERNELS_MEASURED: c_int = 2;
// The library's version (the crate's) and the file format it reads, as the header's macros say
// them (runtime/tests/c_abi.rs checks them against Cargo and `pvt3_format::FORMAT_VERSION`).
/// The library's major version.
pub const PVT3_VERSION_MAJOR: c_int = 0;
/// The library's minor version.
pub const PVT3_VERSION_MINOR: c_int = 1;
/// The library's patch version.
pub const PVT3_VERSION_PATCH: c_int = 0;
/// The major version of the file format the library reads.
pub const PVT3_FORMAT_MAJOR: c_int = 1;
/// The minor version of the file format the library reads.
pub const PVT3_FORMAT_MINOR: c_int = 1;

/// What each status code means, for `pvt3_status_text`.
const STATUS_TEXT: [&CStr; 6] = [
    c"PVT3_OK: success",
    c"PVT3_ERR_NULL: a pointer the call needs is NULL",
    c"PVT3_ERR_IO: a file could not be read",
    c"PVT3_ERR_MODEL: the file is not a model this library runs (damaged, foreign, or of another format)",
    c"PVT3_ERR_INPUT: an argument or input the model cannot take (length, value, order of calls)",
    c"PVT3_ERR_INTERNAL: a fault inside the library (please report it, with pvt3_last_error())",
];

/// What C holds: the classifier, and its class names and metadata as C strings.
pub struct Pvt3Classifier {
    classifier: Classifier,
    names: Vec<CString>,
    metadata: Vec<(CString, CString)>,
}

/// What C holds for a touch in progress.
pub struct Pvt3Session {
    session: Session,
    names: usize,
}

/// What C holds for a continuous stream.
pub struct Pvt3Continuous {
    continuous: Continuous,
    names: usize,
}

thread_local! {
    static LAST_ERROR: RefCell<CString> = RefCell::new(CString::default());
}

fn set_last_error(msg: String) {
    LAST_ERROR.with(|e| *e.borrow_mut() = c_string(&msg));
}

fn status(e: &Error) -> c_int {
    match e {
        Error::Io { .. } => PVT3_ERR_IO,
        Error::NotOnnx { .. } | Error::NotPvt3 { .. } | Error::Corrupted { .. } => PVT3_ERR_MODEL,
        Error::InputLength { .. }
        | Error::NonFinite { .. }
        | Error::EmptyBatch
        | Error::NoStride
        | Error::BatchTooLarge { .. }
        | Error::NoThreads { .. }
        | Error::Npy { .. }
        | Error::FrameLength { .. }
        | Error::TooManyFrames { .. }
        | Error::Incomplete { .. }
        | Error::NoTokenYet { .. }
        | Error::Touch(_) => PVT3_ERR_INPUT,
        Error::NoPrefixes | Error::WholeWindowOnly | Error::OutOfMemory { .. } => PVT3_ERR_MODEL,
        Error::Tract(_) => PVT3_ERR_INTERNAL,
    }
}

/// Runs `f`, turning errors and panics into a status code and a last-error message.
fn guard(f: impl FnOnce() -> std::result::Result<(), (c_int, String)>) -> c_int {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(Ok(())) => PVT3_OK,
        Ok(Err((code, msg))) => {
            set_last_error(msg);
            code
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "unknown".into());
            set_last_error(format!("internal error (panic): {what}"));
            PVT3_ERR_INTERNAL
        }
    }
}

/// Drops a handle C got from `Box::into_raw` (null is ignored), catching a panic in the drop.
///
/// # Safety
/// `p` came from `Box::into_raw` and is not used afterwards.
unsafe fn free_handle<T>(p: *mut T) {
    if !p.is_null() {
        let _ = catch_unwind(AssertUnwindSafe(|| drop(Box::from_raw(p))));
    }
}

/// Writes `size(classifier)` to `*out`: the body of every size getter.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
unsafe fn write_size(c: *const Pvt3Classifier, out: *mut usize, size: impl FnOnce(&Pvt3Classifier) -> usize) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        *out.as_mut().ok_or_else(|| null("out"))? = size(c);
        Ok(())
    })
}

/// The `len` values C passes in at `p`, or the error naming `what` if `p` is null.
///
/// # Safety
/// `p` is null or valid for `len` values, which outlive the slice.
unsafe fn values_in<'a, T>(p: *const T, len: usize, what: &str) -> Result<&'a [T], (c_int, String)> {
    if p.is_null() {
        return Err(null(what));
    }
    Ok(std::slice::from_raw_parts(p, len))
}

fn null(what: &str) -> (c_int, String) {
    (PVT3_ERR_NULL, format!("{what} is a null pointer"))
}

fn fail(e: Error) -> (c_int, String) {
    (status(&e), e.to_string())
}

/// Loads a model; on success `*out` owns a handle to free with `pvt3_classifier_free`.
///
/// # Safety
/// `path` is a NUL-terminated string or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_load(path: *const c_char, out: *mut *mut Pvt3Classifier) -> c_int {
    guard(|| {
        if path.is_null() {
            return Err(null("path"));
        }
        if out.is_null() {
            return Err(null("out"));
        }
        let path = CStr::from_ptr(path).to_str().map_err(|_| (PVT3_ERR_IO, "path is not UTF-8".to_string()))?;
        *out = handle(Classifier::load(path).map_err(fail)?);
        Ok(())
    })
}

/// A classifier as C holds it.
fn handle(classifier: Classifier) -> *mut Pvt3Classifier {
    let names = classifier.classes().iter().map(|n| c_string(n)).collect();
    let metadata = classifier.metadata().iter().map(|(k, v)| (c_string(k), c_string(v))).collect();
    Box::into_raw(Box::new(Pvt3Classifier { classifier, names, metadata }))
}

/// `text` as a C string, a NUL in it (which no file of ours writes) read as a space.
fn c_string(text: &str) -> CString {
    CString::new(text.replace('\0', " ")).expect("NULs replaced")
}

/// Loads a model from the `len` bytes of an `.onnx` file in memory (flash, a download), named
/// `name` in errors (null: "(memory)"); on success `*out` owns a handle to free with
/// `pvt3_classifier_free`. The bytes are not kept: they may be freed after the call.
///
/// # Safety
/// `bytes` holds `len` bytes or is null; `name` is a NUL-terminated string or null; `out` is
/// writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_load_bytes(
    bytes: *const u8,
    len: usize,
    name: *const c_char,
    out: *mut *mut Pvt3Classifier,
) -> c_int {
    guard(|| {
        let bytes = values_in(bytes, len, "bytes")?;
        let out = out.as_mut().ok_or_else(|| null("out"))?;
        let name = if name.is_null() { "(memory)".into() } else { CStr::from_ptr(name).to_string_lossy() };
        *out = handle(Classifier::from_bytes(bytes, &name).map_err(fail)?);
        Ok(())
    })
}

/// Runs the classifier's plans on `threads` threads from now on (default 1). More than one needs
/// a library built with the `threads` feature (the default build; not the small robot build).
/// Plans built so far are dropped.
///
/// # Safety
/// `c` is a live handle or null, not in use by another thread during the call.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_set_threads(c: *mut Pvt3Classifier, threads: usize) -> c_int {
    guard(|| {
        let c = c.as_mut().ok_or_else(|| null("classifier"))?;
        if threads == 0 {
            return Err((PVT3_ERR_INPUT, "threads must be at least 1".into()));
        }
        if threads > 1 && cfg!(not(feature = "threads")) {
            return Err(fail(Error::NoThreads { asked: threads }));
        }
        c.classifier.set_threads(threads);
        Ok(())
    })
}

/// Frees a handle from `pvt3_classifier_load` (null is ignored).
///
/// # Safety
/// `c` came from `pvt3_classifier_load` and is not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_free(c: *mut Pvt3Classifier) {
    free_handle(c);
}

/// How the classifier's plans choose their matrix-product kernels from now on:
/// `PVT3_KERNELS_FIXED` (the default: a fixed rule, bit-identical outputs at every load),
/// `PVT3_KERNELS_TRACT` (tract's own choice) or `PVT3_KERNELS_MEASURED` (timed at each plan's
/// first call; outputs can differ in the last bits between loads). Plans built so far are dropped.
///
/// # Safety
/// `c` is a live handle or null, not in use by another thread during the call.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_set_kernels(c: *mut Pvt3Classifier, kernels: c_int) -> c_int {
    guard(|| {
        let c = c.as_mut().ok_or_else(|| null("classifier"))?;
        let kernels = match kernels {
            PVT3_KERNELS_FIXED => Kernels::Fixed,
            PVT3_KERNELS_TRACT => Kernels::Tract,
            PVT3_KERNELS_MEASURED => Kernels::Measured,
            other => return Err((PVT3_ERR_INPUT, format!("kernel choice {other} is none of PVT3_KERNELS_FIXED, _TRACT, _MEASURED"))),
        };
        c.classifier.set_kernels(kernels);
        Ok(())
    })
}

/// Builds now the plan for `batch` windows and, unless `streaming` is 0, the stages a session
/// runs: what the first such call would otherwise build (tens of milliseconds). Call it at
/// start-up.
///
/// # Safety
/// `c` is a live handle or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_prepare(c: *const Pvt3Classifier, batch: usize, streaming: c_int) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        c.classifier.prepare(&[batch], streaming != 0).map_err(fail)
    })
}

/// Values in one window (`height × width × (channels ×) frames`).
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_sample_len(c: *const Pvt3Classifier, out: *mut usize) -> c_int {
    write_size(c, out, |c| c.classifier.sample_shape().iter().product())
}

/// Frames in one window (its last axis), pruned ones included.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_frames(c: *const Pvt3Classifier, out: *mut usize) -> c_int {
    write_size(c, out, |c| *c.classifier.sample_shape().last().expect("a window has a frame axis"))
}

/// Bytes in one of the camera's frames as `pvt3_session_push_camera_frame` takes it: the
/// recorded frame's (height × width × channels) for a model of camera frames, one model frame's
/// otherwise.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_camera_frame_len(c: *const Pvt3Classifier, out: *mut usize) -> c_int {
    write_size(c, out, |c| c.classifier.camera_frame_len())
}

/// Frames per temporal token: a session answers, and a continuous stream counts its `every`, in
/// whole tokens.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_tubelet(c: *const Pvt3Classifier, out: *mut usize) -> c_int {
    write_size(c, out, |c| c.classifier.tubelet())
}

/// Number of classes.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_num_classes(c: *const Pvt3Classifier, out: *mut usize) -> c_int {
    write_size(c, out, |c| c.names.len())
}

/// The name of class `index`, NUL-terminated, valid as long as the handle; unless `len` is
/// null, its length in bytes (without the NUL) goes to `*len`.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null; `len` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_class_name(
    c: *const Pvt3Classifier,
    index: usize,
    out: *mut *const c_char,
    len: *mut usize,
) -> c_int {
    write_nth(c, index, (out, len), ("class", |c, i| (c.names.get(i).map(CString::as_c_str), c.names.len())))
}

/// The `index`th of a classifier's strings, if it has one, and their count.
type Nth = fn(&Pvt3Classifier, usize) -> (Option<&CStr>, usize);

/// Points `*out` at the `index`th of the classifier's strings that `nth` gives with their count
/// (`what` names one in errors), as [`write_text`] does.
///
/// # Safety
/// `c` is a live handle or null; `out` and `len` are writable or null.
unsafe fn write_nth(
    c: *const Pvt3Classifier,
    index: usize,
    (out, len): (*mut *const c_char, *mut usize),
    (what, nth): (&str, Nth),
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let (text, count) = nth(c, index);
        write_text(text.ok_or_else(|| (PVT3_ERR_INPUT, format!("{what} {index} of {count}")))?, out, len)
    })
}

/// Points `*out` at `text` and, unless `len` is null, writes its length in bytes to `*len`.
///
/// # Safety
/// `out` and `len` are writable or null; `text` outlives what C does with `*out`.
unsafe fn write_text(text: &CStr, out: *mut *const c_char, len: *mut usize) -> std::result::Result<(), (c_int, String)> {
    *out.as_mut().ok_or_else(|| null("out"))? = text.as_ptr();
    if let Some(len) = len.as_mut() {
        *len = text.to_bytes().len();
    }
    Ok(())
}

/// Writes `values` to `out` (room for `out_len`) and their count to `*count`, also when `out` is
/// too small (then PVT3_ERR_INPUT), so that the caller can ask again with room enough.
///
/// # Safety
/// `out` has room for `out_len` values or is null; `count` is writable or null.
unsafe fn write_values<T: Copy>(
    values: &[T],
    (out, out_len): (*mut T, usize),
    (count, count_name): (*mut usize, &str),
) -> std::result::Result<(), (c_int, String)> {
    if out.is_null() {
        return Err(null("out"));
    }
    *count.as_mut().ok_or_else(|| null(count_name))? = values.len();
    if out_len < values.len() {
        return Err((PVT3_ERR_INPUT, format!("out has room for {out_len} values; {} needed", values.len())));
    }
    std::slice::from_raw_parts_mut(out, values.len()).copy_from_slice(values);
    Ok(())
}

/// The axes of one window, `[height, width, (channels,) frames]` (`*rank` of them, 3 or 4), into
/// `shape` (room for `shape_len`); `*rank` is written also when `shape` is too small.
///
/// # Safety
/// `c` is a live handle or null; `shape` has room for `shape_len` values or is null; `rank` is
/// writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_input_shape(
    c: *const Pvt3Classifier,
    shape: *mut usize,
    shape_len: usize,
    rank: *mut usize,
) -> c_int {
    write_list(c, (shape, shape_len), (rank, "rank"), Classifier::sample_shape)
}

/// Writes the classifier's `list` to `out` and its length to `*count`, as [`write_values`] does.
///
/// # Safety
/// `c` is a live handle or null; `out` has room for `out_len` values or is null; `count` is
/// writable or null.
unsafe fn write_list(
    c: *const Pvt3Classifier,
    (out, out_len): (*mut usize, usize),
    (count, count_name): (*mut usize, &str),
    list: fn(&Classifier) -> &[usize],
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        write_values(list(&c.classifier), (out, out_len), (count, count_name))
    })
}

/// One of the camera's frames as `pvt3_session_push_camera_frame` takes it: its height, width and
/// channels (`Classifier::camera_frame_shape`).
///
/// # Safety
/// `c` is a live handle or null; the other pointers are writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_camera_shape(
    c: *const Pvt3Classifier,
    height: *mut usize,
    width: *mut usize,
    channels: *mut usize,
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let [h, w, ch] = c.classifier.camera_frame_shape();
        for (out, value, what) in [(height, h, "height"), (width, w, "width"), (channels, ch, "channels")] {
            *out.as_mut().ok_or_else(|| null(what))? = value;
        }
        Ok(())
    })
}

/// The frames of a window the model reads, ascending (the others were pruned), into `frames`
/// (room for `frames_len`); `*count` is written also when `frames` is too small.
///
/// # Safety
/// `c` is a live handle or null; `frames` has room for `frames_len` values or is null; `count`
/// is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_kept_frames(
    c: *const Pvt3Classifier,
    frames: *mut usize,
    frames_len: usize,
    count: *mut usize,
) -> c_int {
    write_list(c, (frames, frames_len), (count, "count"), Classifier::kept_frames)
}

/// Whether the file can be streamed (sessions, provisional answers): 1, else 0.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_streams(c: *const Pvt3Classifier, out: *mut c_int) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        *out.as_mut().ok_or_else(|| null("out"))? = c_int::from(c.classifier.streams());
        Ok(())
    })
}

/// How many metadata entries the file has.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_metadata_count(c: *const Pvt3Classifier, out: *mut usize) -> c_int {
    write_size(c, out, |c| c.metadata.len())
}

/// The key of metadata entry `index` (in the file's order), as `pvt3_classifier_class_name`
/// gives a name.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null; `len` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_metadata_key(
    c: *const Pvt3Classifier,
    index: usize,
    out: *mut *const c_char,
    len: *mut usize,
) -> c_int {
    write_nth(c, index, (out, len), ("metadata entry", |c, i| (c.metadata.get(i).map(|(k, _)| k.as_c_str()), c.metadata.len())))
}

/// The value of the metadata `key`, NUL-terminated, valid as long as the handle, and unless
/// `len` is null its length; a key the file does not have is no error: `*out` is then NULL and
/// `*len` 0.
///
/// # Safety
/// `c` is a live handle or null; `key` is a NUL-terminated string or null; `out` and `len` are
/// writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classifier_metadata(
    c: *const Pvt3Classifier,
    key: *const c_char,
    out: *mut *const c_char,
    len: *mut usize,
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        if key.is_null() {
            return Err(null("key"));
        }
        let key = CStr::from_ptr(key);
        match c.metadata.iter().find(|(k, _)| k.as_c_str() == key) {
            Some((_, value)) => write_text(value, out, len),
            None => write_text(c"", out, len).map(|()| *out = std::ptr::null()),
        }
    })
}

/// Classifies `batch` windows of raw frames (`frames_len` = batch × sample length values).
/// Writes `batch × classes` probabilities to `probabilities` (room for `probabilities_len`
/// values) and, unless `classes_out` is null, the most probable class of each window.
///
/// # Safety
/// Pointers are null or valid for the lengths given.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classify(
    c: *const Pvt3Classifier,
    frames: *const f32,
    frames_len: usize,
    batch: usize,
    probabilities: *mut f32,
    probabilities_len: usize,
    classes_out: *mut usize,
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let input = values_in(frames, frames_len, "frames")?;
        let probabilities = room(probabilities, probabilities_len, (batch, c.names.len()), "probabilities")?;
        write_predictions(&c.classifier.classify_batch(input, batch).map_err(fail)?, probabilities, classes_out);
        Ok(())
    })
}

/// The logits (the scores before the softmax) of `batch` windows, as `pvt3_classify` takes them:
/// `batch × classes` values into `logits` (room for `logits_len`).
///
/// # Safety
/// Pointers are null or valid for the lengths given.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classify_logits(
    c: *const Pvt3Classifier,
    frames: *const f32,
    frames_len: usize,
    batch: usize,
    logits: *mut f32,
    logits_len: usize,
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let input = values_in(frames, frames_len, "frames")?;
        let out = room(logits, logits_len, (batch, c.names.len()), "logits")?;
        out.copy_from_slice(&c.classifier.run(input, batch).map_err(fail)?.0);
        Ok(())
    })
}

/// Classifies `touches` touches of the camera's 8-bit frames as it gives them (`frames_len`
/// bytes: each touch `[height, width, channels, frames]`, any whole number of frames), each read
/// as the training's import read its videos (`Classifier::classify_camera_touches`); writes
/// what `pvt3_classify` writes.
///
/// # Safety
/// Pointers are null or valid for the lengths given.
#[no_mangle]
pub unsafe extern "C" fn pvt3_classify_camera_touches(
    c: *const Pvt3Classifier,
    frames: *const u8,
    frames_len: usize,
    touches: usize,
    probabilities: *mut f32,
    probabilities_len: usize,
    classes_out: *mut usize,
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let input = values_in(frames, frames_len, "frames")?;
        let probabilities = room(probabilities, probabilities_len, (touches, c.names.len()), "probabilities")?;
        write_predictions(&c.classifier.classify_camera_touches(input, touches).map_err(fail)?, probabilities, classes_out);
        Ok(())
    })
}

/// Each prediction's probabilities, one after the other, and unless `classes_out` is null its
/// class.
///
/// # Safety
/// `probabilities` has room for the predictions' probabilities; `classes_out` is null or has room
/// for a class per prediction.
unsafe fn write_predictions(predictions: &[Prediction], probabilities: &mut [f32], classes_out: *mut usize) {
    let mut rows = probabilities.chunks_mut(probabilities.len() / predictions.len().max(1));
    for (i, (p, row)) in predictions.iter().zip(&mut rows).enumerate() {
        let class_out = if classes_out.is_null() { classes_out } else { classes_out.add(i) };
        write_prediction(p, row.as_mut_ptr(), class_out);
    }
}

/// A touch as the robot recorded it (`frames_len` raw values in the sample layout, any number
/// of frames), slid at `speed` and pressed at `force` (0: not known), brought to the frames the
/// model reads (`Classifier::read_touch`: resampled to its speed, scaled to its force, as its
/// training read touches) into `out`, which has room for `out_len` values. `*written` gets how
/// many values they are, also when `out` is too small (PVT3_ERR_INPUT), so that the caller can
/// ask again with room enough.
///
/// # Safety
/// `c` is a live handle or null; `frames` holds `frames_len` floats or is null; `out` has room
/// for `out_len` floats or is null; `written` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_read_touch(
    c: *const Pvt3Classifier,
    frames: *const f32,
    frames_len: usize,
    speed: f64,
    force: f64,
    out: *mut f32,
    out_len: usize,
    written: *mut usize,
) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let frames = values_in(frames, frames_len, "frames")?;
        if out.is_null() || written.is_null() {
            return Err(null(if out.is_null() { "out" } else { "written" }));
        }
        let read = c.classifier.read_touch(frames, touch(speed, force)).map_err(fail)?;
        write_values(&read, (out, out_len), (written, "written"))
    })
}

/// Starts a streaming session on a classifier; `*out` owns a handle to free with
/// `pvt3_session_free`. The session may outlive the classifier.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_new(c: *const Pvt3Classifier, out: *mut *mut Pvt3Session) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let out = out.as_mut().ok_or_else(|| null("out"))?;
        let session = c.classifier.session().map_err(fail)?;
        *out = Box::into_raw(Box::new(Pvt3Session { session, names: c.names.len() }));
        Ok(())
    })
}

/// Starts a streaming session for touches recorded at `speed` and `force` (0: not known), as
/// `pvt3_session_new`, whose frames are taken as recorded and read as the model reads touches
/// (`Classifier::session_for`, frame by frame what `pvt3_read_touch` does to a whole touch).
/// PVT3_ERR_INPUT for a speed or force the model needs and was not given.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_new_touch(c: *const Pvt3Classifier, speed: f64, force: f64, out: *mut *mut Pvt3Session) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let out = out.as_mut().ok_or_else(|| null("out"))?;
        let session = c.classifier.session_for(touch(speed, force)).map_err(fail)?;
        *out = Box::into_raw(Box::new(Pvt3Session { session, names: c.names.len() }));
        Ok(())
    })
}

/// What the robot knows of a touch, 0 for what it does not.
fn touch(speed: f64, force: f64) -> crate::Touch {
    let known = |v: f64| (v != 0.0).then_some(v);
    crate::Touch { speed: known(speed), force: known(force) }
}

/// Frees a session (null is ignored).
///
/// # Safety
/// `s` came from `pvt3_session_new` and is not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_free(s: *mut Pvt3Session) {
    free_handle(s);
}

/// Takes the touch's next frame (`frame_len` = height × width × channels raw values).
///
/// # Safety
/// `s` is a live session or null; `frame` is null or valid for `frame_len` values.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_push_frame(s: *mut Pvt3Session, frame: *const f32, frame_len: usize) -> c_int {
    guard(|| {
        let s = s.as_mut().ok_or_else(|| null("session"))?;
        s.session.push_frame(values_in(frame, frame_len, "frame")?).map_err(fail)
    })
}

/// Takes the camera's next frame, 8-bit as the camera gives it (`frame_len` =
/// `pvt3_classifier_camera_frame_len` bytes, row-major, channels innermost), read as the
/// training's import read its videos (`Session::push_camera_frame`).
///
/// # Safety
/// `s` is a live session or null; `frame` is null or valid for `frame_len` bytes.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_push_camera_frame(s: *mut Pvt3Session, frame: *const u8, frame_len: usize) -> c_int {
    guard(|| {
        let s = s.as_mut().ok_or_else(|| null("session"))?;
        s.session.push_camera_frame(values_in(frame, frame_len, "frame")?).map_err(fail)
    })
}

/// Ends the touch once all its frames are in: writes the class probabilities (room for
/// `probabilities_len` values) and, unless `class_out` is null, the most probable class. The
/// session is then ready for the next touch.
///
/// # Safety
/// `s` is a live session or null; the other pointers are null or valid for the lengths given.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_finish(
    s: *mut Pvt3Session,
    probabilities: *mut f32,
    probabilities_len: usize,
    class_out: *mut usize,
) -> c_int {
    guard(|| {
        let s = s.as_mut().ok_or_else(|| null("session"))?;
        room(probabilities, probabilities_len, (1, s.names), "probabilities")?;
        write_prediction(&s.session.finish().map_err(fail)?, probabilities, class_out);
        Ok(())
    })
}

/// The `rows × classes` values at `out` (`what` names it in errors), once checked that `out` has
/// room for them: before a call that runs a plan or changes a session.
///
/// # Safety
/// `out` is null or valid for `out_len` values.
unsafe fn room<'a>(
    out: *mut f32,
    out_len: usize,
    (rows, classes): (usize, usize),
    what: &str,
) -> std::result::Result<&'a mut [f32], (c_int, String)> {
    if out.is_null() {
        return Err(null(what));
    }
    let needed = rows.checked_mul(classes).ok_or_else(|| fail(Error::BatchTooLarge { batch: rows }))?;
    if out_len < needed {
        return Err((PVT3_ERR_INPUT, format!("{what} has room for {out_len} values; {needed} needed")));
    }
    Ok(std::slice::from_raw_parts_mut(out, needed))
}

/// Writes `p`'s class probabilities and, unless `class_out` is null, its class.
///
/// # Safety
/// `probabilities` passed [`room`] for `p`'s classes; `class_out` is null or writable.
unsafe fn write_prediction(p: &Prediction, probabilities: *mut f32, class_out: *mut usize) {
    std::slice::from_raw_parts_mut(probabilities, p.probabilities.len()).copy_from_slice(&p.probabilities);
    if let Some(class) = class_out.as_mut() {
        *class = p.class;
    }
}

/// A provisional answer from the touch so far, which goes on: writes the class probabilities
/// (room for `probabilities_len` values) and, unless null, the most probable class, the frames
/// the answer read and whether it meets the file's stopping rule (1, else 0).
///
/// # Safety
/// `s` is a live session or null; the other pointers are null or valid for the lengths given.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_peek(
    s: *mut Pvt3Session,
    probabilities: *mut f32,
    probabilities_len: usize,
    class_out: *mut usize,
    frames_out: *mut usize,
    stop_out: *mut c_int,
) -> c_int {
    guard(|| {
        let s = s.as_mut().ok_or_else(|| null("session"))?;
        room(probabilities, probabilities_len, (1, s.names), "probabilities")?;
        let p = s.session.peek().map_err(fail)?;
        write_prediction(&p.prediction, probabilities, class_out);
        if let Some(frames) = frames_out.as_mut() {
            *frames = p.frames;
        }
        if let Some(stop) = stop_out.as_mut() {
            *stop = c_int::from(p.stop);
        }
        Ok(())
    })
}

/// Starts a continuous classification of an unbounded stream of frames, answering for the latest
/// window after every `every` temporal tokens once a whole window is in; `*out` owns a handle to
/// free with `pvt3_continuous_free`. It may outlive the classifier.
///
/// # Safety
/// `c` is a live handle or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_continuous_new(c: *const Pvt3Classifier, every: usize, out: *mut *mut Pvt3Continuous) -> c_int {
    guard(|| {
        let c = c.as_ref().ok_or_else(|| null("classifier"))?;
        let out = out.as_mut().ok_or_else(|| null("out"))?;
        let continuous = c.classifier.continuous(every).map_err(fail)?;
        *out = Box::into_raw(Box::new(Pvt3Continuous { continuous, names: c.names.len() }));
        Ok(())
    })
}

/// Frees a continuous stream (null is ignored).
///
/// # Safety
/// `s` came from `pvt3_continuous_new` and is not used afterwards.
#[no_mangle]
pub unsafe extern "C" fn pvt3_continuous_free(s: *mut Pvt3Continuous) {
    free_handle(s);
}

/// Takes the stream's next frame. When an answer is due, writes the class probabilities of the
/// window ending at this frame (room for `probabilities_len` values) and, unless null, its most
/// probable class, and sets `*answered_out` (unless null) to 1; otherwise to 0, writing nothing
/// else.
///
/// # Safety
/// `s` is a live stream or null; `frame` is null or valid for `frame_len` values; the other
/// pointers are null or valid for the lengths given.
#[no_mangle]
pub unsafe extern "C" fn pvt3_continuous_push_frame(
    s: *mut Pvt3Continuous,
    frame: *const f32,
    frame_len: usize,
    probabilities: *mut f32,
    probabilities_len: usize,
    class_out: *mut usize,
    answered_out: *mut c_int,
) -> c_int {
    guard(|| {
        let s = s.as_mut().ok_or_else(|| null("stream"))?;
        let frame = values_in(frame, frame_len, "frame")?;
        room(probabilities, probabilities_len, (1, s.names), "probabilities")?;
        let answer = s.continuous.push_frame(frame).map_err(fail)?;
        if let Some(p) = &answer {
            write_prediction(p, probabilities, class_out);
        }
        if let Some(answered) = answered_out.as_mut() {
            *answered = c_int::from(answer.is_some());
        }
        Ok(())
    })
}

/// Forgets the stream: the next answer comes after a whole new window.
///
/// # Safety
/// `s` is a live stream or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_continuous_reset(s: *mut Pvt3Continuous) -> c_int {
    guard(|| {
        s.as_mut().ok_or_else(|| null("stream"))?.continuous.reset();
        Ok(())
    })
}

/// Forgets the touch in progress, so that the session takes a new touch from its first frame: what
/// a robot calls when it ends a touch early on a peek, instead of freeing the session and making
/// another.
///
/// # Safety
/// `s` is a live session or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_reset(s: *mut Pvt3Session) -> c_int {
    guard(|| {
        s.as_mut().ok_or_else(|| null("session"))?.session.reset();
        Ok(())
    })
}

/// The frames of this touch's window the session has taken so far, as the model reads them (of
/// `pvt3_classifier_frames`; a frame read by distance counts once it is read).
///
/// # Safety
/// `s` is a live session or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_session_received(s: *const Pvt3Session, out: *mut usize) -> c_int {
    guard(|| {
        let s = s.as_ref().ok_or_else(|| null("session"))?;
        *out.as_mut().ok_or_else(|| null("out"))? = s.session.received();
        Ok(())
    })
}

/// The frames the stream has taken since it started or was last reset.
///
/// # Safety
/// `s` is a live stream or null; `out` is writable or null.
#[no_mangle]
pub unsafe extern "C" fn pvt3_continuous_received(s: *const Pvt3Continuous, out: *mut u64) -> c_int {
    guard(|| {
        let s = s.as_ref().ok_or_else(|| null("stream"))?;
        *out.as_mut().ok_or_else(|| null("out"))? = s.continuous.received();
        Ok(())
    })
}

/// What a status code means, e.g. `PVT3_ERR_INPUT: an argument or input …`; a static string
/// ("unknown pvt3 status" for a code that is none of them).
#[no_mangle]
pub extern "C" fn pvt3_status_text(status: c_int) -> *const c_char {
    let known = usize::try_from(status).ok().and_then(|s| STATUS_TEXT.get(s));
    known.map_or(c"unknown pvt3 status".as_ptr(), |t| t.as_ptr())
}

/// The library's version and the file format it reads, e.g. `0.1.0 (format 1.1)`; a static string.
#[no_mangle]
pub extern "C" fn pvt3_version() -> *const c_char {
    static VERSION: OnceLock<CString> = OnceLock::new();
    VERSION.get_or_init(|| CString::new(crate::version()).expect("no NUL")).as_ptr()
}

/// The message of the last failed call on this thread ("" if none); valid until the next call.
#[no_mangle]
pub extern "C" fn pvt3_last_error() -> *const c_char {
    LAST_ERROR.with(|e| e.borrow().as_ptr())
}
