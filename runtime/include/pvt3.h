/* pvt3: tactile texture classification on the robot (C ABI of the pvt3-runtime crate).
 *
 * Link libpvt3_runtime.a (with -lm -lpthread -ldl) or libpvt3_runtime.so; installed by
 * runtime/install.sh, `pkg-config --cflags --libs pvt3` gives the flags. Every function that
 * returns int returns a pvt3_status: PVT3_OK or an error code, which pvt3_status_text() names;
 * pvt3_last_error() then says what went wrong.
 * No call panics or aborts on bad input: null pointers, wrong lengths, non-finite values,
 * truncated or foreign files are all reported; a file damaged or altered since export is refused
 * at load (integrity digest).
 *
 * Memory order of every buffer: row-major (C order) over the axes as written, the last axis
 * innermost. Windows are [batch, height, width, (channels,) frames]: frames innermost, so the
 * value of taxel (h, w), channel c, frame t of window b is at
 *     frames[((((b * height + h) * width + w) * channels + c) * n_frames) + t]
 * (channels = 1 without a channel axis; pvt3_classifier_input_shape gives the axes). A frame
 * pushed to a session is [height, width, (channels)]: value (h, w, c) at (h * width + w) *
 * channels + c. A camera's 8-bit frame is the same, row-major with channels innermost as the
 * camera gives it; whole camera touches (pvt3_classify_camera_touches) are [touches, height,
 * width, channels, frames], frames innermost again. Probabilities and logits are [batch,
 * classes]. A buffer of the right length in another order is classified without error, and
 * wrongly: check it against the runtime on a recorded window once.
 *
 * Threads: a classifier may be used from several threads at once (pvt3_classify,
 * pvt3_classifier_prepare, pvt3_session_new, pvt3_session_new_touch, pvt3_continuous_new and the
 * getters; the Rust API's test checks every answer against one thread's), but
 * pvt3_classifier_set_kernels, pvt3_classifier_set_threads and pvt3_classifier_free must not run
 * alongside any other call on it. A session or a continuous stream belongs to one thread at a time. pvt3_last_error() is per
 * thread. */
#ifndef PVT3_H
#define PVT3_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* The library's version, and the file format it reads (pvt3_version() says both at run time). */
#define PVT3_VERSION_MAJOR 0
#define PVT3_VERSION_MINOR 1
#define PVT3_VERSION_PATCH 0
#define PVT3_FORMAT_MAJOR 1
#define PVT3_FORMAT_MINOR 1

/* What every function that returns int returns (pvt3_status_text() in words). */
typedef enum pvt3_status {
    PVT3_OK = 0,          /* success */
    PVT3_ERR_NULL = 1,    /* a pointer the call needs is NULL */
    PVT3_ERR_IO = 2,      /* a file could not be read */
    PVT3_ERR_MODEL = 3,   /* not a model this library runs: damaged, foreign, another format */
    PVT3_ERR_INPUT = 4,   /* an argument or input the model cannot take */
    PVT3_ERR_INTERNAL = 5 /* a fault inside the library: please report it */
} pvt3_status;

/* How plans choose their matrix-product kernels (pvt3_classifier_set_kernels). */
#define PVT3_KERNELS_FIXED 0
#define PVT3_KERNELS_TRACT 1
#define PVT3_KERNELS_MEASURED 2

typedef struct Pvt3Classifier pvt3_classifier;
typedef struct Pvt3Session pvt3_session;
typedef struct Pvt3Continuous pvt3_continuous;

/* Loads an .onnx written by `pvt3 export`; *out owns a handle to free with pvt3_classifier_free.
 * The file's integrity digest is checked first: a file altered or damaged after export is
 * refused with PVT3_ERR_MODEL. */
int pvt3_classifier_load(const char *path, pvt3_classifier **out);
/* Loads a model from the `len` bytes of an .onnx file in memory (flash, a download), checked as
 * pvt3_classifier_load checks a file; `name` (NULL: "(memory)") names it in errors. The bytes
 * are copied: they may be freed after the call. */
int pvt3_classifier_load_bytes(const unsigned char *bytes, size_t len, const char *name, pvt3_classifier **out);
/* Frees a handle (NULL is ignored). */
void pvt3_classifier_free(pvt3_classifier *c);
/* How plans choose their matrix-product kernels from now on: PVT3_KERNELS_FIXED (the default, a
 * fixed rule: the same outputs, bit for bit, at every load), PVT3_KERNELS_TRACT (tract's own
 * choice) or PVT3_KERNELS_MEASURED (timed at each plan's first call, 50-100 ms; outputs can differ
 * in the last bits between loads). Call it before sharing the classifier between threads. */
int pvt3_classifier_set_kernels(pvt3_classifier *c, int kernels);
/* Runs the classifier's plans on `threads` threads from now on (default 1: small models rarely
 * gain from more). More than one needs a library built with the `threads` feature (the default
 * build, not the small robot build): PVT3_ERR_INPUT otherwise, and for 0. Call it before sharing
 * the classifier between threads. */
int pvt3_classifier_set_threads(pvt3_classifier *c, size_t threads);
/* Builds now the plan for `batch` windows and, unless streaming is 0, the stages a session runs:
 * what the first such call would otherwise build (tract's optimisation, tens of milliseconds).
 * Call it at start-up so that the first touch costs what every touch costs. */
int pvt3_classifier_prepare(const pvt3_classifier *c, size_t batch, int streaming);
/* Values in one window: height x width x (channels x) frames, raw sensor values, frames
 * innermost (the memory order above). */
int pvt3_classifier_sample_len(const pvt3_classifier *c, size_t *out);
/* Frames in one window (its last axis); a frame has sample_len / frames values. */
int pvt3_classifier_frames(const pvt3_classifier *c, size_t *out);
/* Number of classes. */
int pvt3_classifier_num_classes(const pvt3_classifier *c, size_t *out);
/* Bytes in one of the camera's frames as pvt3_session_push_camera_frame takes it: for a model of
 * camera frames (GelSight, DIGIT), the frame as the camera gives it (height x width x channels);
 * otherwise one model frame. */
int pvt3_classifier_camera_frame_len(const pvt3_classifier *c, size_t *out);
/* Frames per temporal token: sessions answer, and continuous streams count `every`, in tokens. */
int pvt3_classifier_tubelet(const pvt3_classifier *c, size_t *out);
/* The axes of one window, [height, width, (channels,) frames]: *rank of them (3, or 4 with a
 * channel axis) written to `shape` (room for shape_len values); *rank is written also when shape
 * is too small (PVT3_ERR_INPUT): ask again with room enough. */
int pvt3_classifier_input_shape(const pvt3_classifier *c, size_t *shape, size_t shape_len, size_t *rank);
/* One of the camera's frames as pvt3_session_push_camera_frame takes it: for a model of camera
 * frames, the frame as the camera gives it (the file's pvt3.camera says how it is read); otherwise
 * one model frame (channels 1 for a window without a channel axis). */
int pvt3_classifier_camera_shape(const pvt3_classifier *c, size_t *height, size_t *width, size_t *channels);
/* The frames of a window the model reads, ascending, into `frames` (room for frames_len values);
 * the others were pruned and are dropped on arrival. *count is written also when frames is too
 * small (PVT3_ERR_INPUT). */
int pvt3_classifier_kept_frames(const pvt3_classifier *c, size_t *frames, size_t frames_len, size_t *count);
/* Whether the file can be streamed (sessions and provisional answers): *out = 1, else 0 (a file
 * whose spectral head reads the whole window, exported before the head streamed). */
int pvt3_classifier_streams(const pvt3_classifier *c, int *out);
/* The file's metadata, key and value strings (docs/guide/file-format.md lists the keys): pvt3.classes,
 * pvt3.format (the format version), pvt3.input_layout, pvt3.kept_frames, pvt3.config,
 * pvt3.provenance (JSON: how the model was trained and, for a `pvt3 final` file, the accuracy
 * its cross-validation expects, under "expected"), pvt3.stop_rule, pvt3.reading, pvt3.camera,
 * pvt3.digest. *out gets the value of `key`, NUL-terminated, valid as long as the handle, and
 * unless len is NULL *len its length in bytes; a key the file does not have is no error: *out is
 * then NULL and *len 0. */
int pvt3_classifier_metadata(const pvt3_classifier *c, const char *key, const char **out, size_t *len);
/* How many metadata entries the file has. */
int pvt3_classifier_metadata_count(const pvt3_classifier *c, size_t *out);
/* The key of metadata entry `index` (0 to count - 1, in the file's order), as
 * pvt3_classifier_class_name gives a name. */
int pvt3_classifier_metadata_key(const pvt3_classifier *c, size_t index, const char **out, size_t *len);
/* Name of class `index`, NUL-terminated, valid as long as the handle; unless len is NULL, its
 * length in bytes (without the NUL) is written to *len. */
int pvt3_classifier_class_name(const pvt3_classifier *c, size_t index, const char **out, size_t *len);
/* Classifies `batch` windows (frames_len = batch x sample_len values): batch x classes
 * probabilities, and the most probable class of each window unless classes_out is NULL. */
int pvt3_classify(const pvt3_classifier *c, const float *frames, size_t frames_len, size_t batch,
                  float *probabilities, size_t probabilities_len, size_t *classes_out);
/* The logits of `batch` windows (the scores the probabilities are the softmax of), taking what
 * pvt3_classify takes: batch x classes values into `logits` (room for logits_len values). */
int pvt3_classify_logits(const pvt3_classifier *c, const float *frames, size_t frames_len, size_t batch, float *logits,
                         size_t logits_len);
/* Classifies `touches` whole touches of the camera's 8-bit frames as it gives them: frames_len
 * bytes, each touch [height, width, channels, frames] (frames innermost, any whole number of
 * frames, the same for every touch), each read as a session reads the frames pushed one by one
 * with pvt3_session_push_camera_frame. Writes what pvt3_classify writes. */
int pvt3_classify_camera_touches(const pvt3_classifier *c, const unsigned char *frames, size_t frames_len, size_t touches,
                                 float *probabilities, size_t probabilities_len, size_t *classes_out);
/* A touch as the robot recorded it (frames_len raw values in the window's layout, with any
 * number of frames), slid at `speed` and pressed at `force` (0: not known), brought to the frames
 * the model reads: for a model trained on touches read by distance and scaled to one force
 * (pvt3 import --per-distance, --per-force), resampled to its speed and scaled to its force, as its
 * training read them; other models get the frames as they are. Writes them to `out` (room for
 * out_len values) and their count to *written, also when out is too small (PVT3_ERR_INPUT): ask
 * again with room enough. PVT3_ERR_INPUT for a speed or force the model needs and was not given. */
int pvt3_read_touch(const pvt3_classifier *c, const float *frames, size_t frames_len, double speed, double force,
                    float *out, size_t out_len, size_t *written);
/* Streaming: a session takes a touch frame by frame (frame_len = height x width x channels raw
 * values, in time order). Pruned frames are dropped on arrival, each kept frame is encoded when it
 * arrives, and finishing runs only the temporal stage; the result equals pvt3_classify on the
 * whole window. After finish the session is ready for the next touch. */
int pvt3_session_new(const pvt3_classifier *c, pvt3_session **out);
/* A session for touches recorded at `speed` and `force` (0: not known): it takes the frames as
 * the sensor records them and reads them as the model reads touches, frame by frame what
 * pvt3_read_touch does to a whole touch (a frame read by distance is pushed on as soon as the
 * recorded frames it spans are in; frames read beyond the window are dropped; finishing first takes
 * the frames read after the last recorded one). For a model without a reading, pvt3_session_new.
 * PVT3_ERR_INPUT for a speed or force the model needs and was not given. */
int pvt3_session_new_touch(const pvt3_classifier *c, double speed, double force, pvt3_session **out);
/* Frees a session (NULL is ignored); it may outlive its classifier. */
void pvt3_session_free(pvt3_session *s);
/* Takes the touch's next frame (frame_len = height x width x channels raw values). PVT3_ERR_INPUT
 * for a frame of another length, a non-finite value, or a frame beyond the window. */
int pvt3_session_push_frame(pvt3_session *s, const float *frame, size_t frame_len);
/* Takes the camera's next frame, 8-bit as the camera gives it, row-major, channels innermost
 * (frame_len = pvt3_classifier_camera_frame_len): cropped, shrunk, greyed as the training's
 * `pvt3 import` read its videos; for a model trained on frames less the touch's first, the first
 * frame of each touch is that background, not one of the model's frames. */
int pvt3_session_push_camera_frame(pvt3_session *s, const unsigned char *frame, size_t frame_len);
/* Writes the class probabilities, and the most probable class unless class_out is NULL. */
int pvt3_session_finish(pvt3_session *s, float *probabilities, size_t probabilities_len, size_t *class_out);
/* A provisional answer from the touch so far, which goes on: the temporal stage over the whole
 * temporal tokens received (pruned ones as their constants), as if the touch ended there; with
 * every frame in, what pvt3_session_finish answers. Writes the probabilities and, unless NULL,
 * the most probable class, the frames it read, and whether it meets the file's stopping rule
 * (1: its top probability reached the rule's and the answers after the tokens just before agree
 * on its class, so the touch may end; 0 otherwise or without a rule; the rule is calibrated at
 * training). PVT3_ERR_INPUT before the first whole token; PVT3_ERR_MODEL for
 * a file exported before format 1.1. */
int pvt3_session_peek(pvt3_session *s, float *probabilities, size_t probabilities_len, size_t *class_out,
                      size_t *frames_out, int *stop_out);
/* Forgets the touch in progress: the session takes a new touch from its first frame. What a robot
 * calls when it ends a touch early on a peek (pvt3_session_finish resets the session itself). */
int pvt3_session_reset(pvt3_session *s);
/* The frames of the touch's window the session has taken so far, as the model reads them (of
 * pvt3_classifier_frames; a session for a touch counts the frames it has read, not those
 * recorded). */
int pvt3_session_received(const pvt3_session *s, size_t *out);
/* Continuous classification of a stream longer than the window (a robot that keeps sliding):
 * frames go in one by one, without end; once a whole window is in, and then after every `every`
 * temporal tokens, the answer for the window ending at the latest frame comes out. Each answer
 * is pvt3_classify on that window (the same plan, the same bits) and costs one window's
 * classification. Works for every file. PVT3_ERR_INPUT for every = 0. */
int pvt3_continuous_new(const pvt3_classifier *c, size_t every, pvt3_continuous **out);
/* Frees a stream (NULL is ignored); it may outlive its classifier. */
void pvt3_continuous_free(pvt3_continuous *s);
/* Takes the next frame (frame_len = height x width x channels). When an answer is due, writes the
 * probabilities and, unless NULL, the most probable class, and sets *answered_out to 1; else
 * *answered_out = 0 and nothing else is written. probabilities must have room either way. */
int pvt3_continuous_push_frame(pvt3_continuous *s, const float *frame, size_t frame_len, float *probabilities,
                               size_t probabilities_len, size_t *class_out, int *answered_out);
/* Forgets the stream: the next answer comes after a whole new window. */
int pvt3_continuous_reset(pvt3_continuous *s);
/* The frames the stream has taken since it started or was last reset. */
int pvt3_continuous_received(const pvt3_continuous *s, uint64_t *out);
/* The library's version and the file format it reads, e.g. "0.1.0 (format 1.1)"; a static string.
 * The runtime reads every file of its format's major version and refuses others (PVT3_ERR_MODEL). */
const char *pvt3_version(void);
/* Message of the last failed call on this thread ("" if none), valid until the next call. */
const char *pvt3_last_error(void);
/* What a status code means, e.g. "PVT3_ERR_INPUT: an argument or input the model cannot take (…)";
 * a static string ("unknown pvt3 status" for another number). */
const char *pvt3_status_text(int status);

#ifdef __cplusplus
}
#endif

#endif
