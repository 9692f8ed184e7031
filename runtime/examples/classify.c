/* Classify windows with the pvt3 C ABI.
 *
 *   classify MODEL.onnx FRAMES.f32 BATCH
 *
 * FRAMES.f32 holds BATCH windows of raw float32 values (little-endian, the model's input layout).
 * Classifies them as one batch, then streams each window frame by frame through a session, as a
 * robot would during a touch; then streams the first half of each and takes a provisional answer,
 * as a robot that ends a touch early, resetting the session for the next; then all windows back to
 * back as one continuous stream, as a robot that keeps sliding, answering once a window. Prints
 * first the model's input ("input", the window's axes, the frames it reads of them, whether it
 * streams, its format version, its metadata entries and the last one's key); then, per window and way ("batch", "stream", "peek" or "slide"),
 * the window, the class index, its name and probability, then all probabilities; then each
 * window's logits ("logits"). */
#include <stdio.h>
#include <stdlib.h>

#include "pvt3.h"

/* Whether a call failed (`rc` is not PVT3_OK): then reports it, and `status` becomes 1; main frees
 * what it took before returning it. */
static int failed(int rc, const char *what, int *status) {
    if (rc == PVT3_OK) return 0;
    fprintf(stderr, "classify: %s: %s [%s]\n", what, pvt3_last_error(), pvt3_status_text(rc));
    *status = 1;
    return 1;
}

/* Frame `t` of `window` ([height, width, (channels,) frames]: every frames-th value) into `frame`. */
static void frame_at(const float *window, size_t t, size_t frames, float *frame, size_t frame_len) {
    for (size_t j = 0; j < frame_len; j++) frame[j] = window[j * frames + t];
}

/* The model's input: its window's axes, how many of its frames it reads, whether it streams, and
 * the format version its file states. */
static int print_input(const pvt3_classifier *model, int *status) {
    size_t shape[4], rank = 0, kept = 0, frames = 0;
    int streams = 0;
    const char *format = NULL;
    if (failed(pvt3_classifier_input_shape(model, shape, 4, &rank), "input_shape", status)) return 1;
    if (failed(pvt3_classifier_frames(model, &frames), "frames", status)) return 1;
    size_t *kept_frames = malloc(frames * sizeof(size_t));
    int rc = pvt3_classifier_kept_frames(model, kept_frames, frames, &kept);
    free(kept_frames);
    if (failed(rc, "kept_frames", status)) return 1;
    if (failed(pvt3_classifier_streams(model, &streams), "streams", status)) return 1;
    if (failed(pvt3_classifier_metadata(model, "pvt3.format", &format, NULL), "metadata", status)) return 1;
    /* Every metadata key by its index (printed: how many, and the last). */
    size_t entries = 0, key_len = 0;
    const char *key = "";
    if (failed(pvt3_classifier_metadata_count(model, &entries), "metadata_count", status)) return 1;
    for (size_t i = 0; i < entries; i++)
        if (failed(pvt3_classifier_metadata_key(model, i, &key, &key_len), "metadata_key", status)) return 1;
    printf("input\t");
    for (size_t i = 0; i < rank; i++) printf(i ? "x%zu" : "%zu", shape[i]);
    printf("\t%zu\t%d\t%s\t%zu %.*s\n", kept, streams, format ? format : "?", entries, (int)key_len, key);
    return 0;
}

static void print(const char *way, const pvt3_classifier *model, size_t i, size_t class, const float *probs, size_t classes) {
    const char *name = "?";
    size_t name_len = 1;
    pvt3_classifier_class_name(model, class, &name, &name_len);
    printf("%s\t%zu\t%zu\t%.*s\t%.6f", way, i, class, (int)name_len, name, probs[class]);
    for (size_t k = 0; k < classes; k++) printf("\t%.9g", probs[k]);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: classify MODEL.onnx FRAMES.f32 BATCH\n");
        return 2;
    }
    size_t batch = (size_t)strtoul(argv[3], NULL, 10);
    int status = 0;
    /* Everything taken, freed at `done` whichever way main leaves (free and the pvt3 frees take NULL). */
    pvt3_classifier *model = NULL;
    pvt3_session *session = NULL;
    pvt3_continuous *slide = NULL;
    float *frames = NULL, *probs = NULL, *frame = NULL;
    size_t *best = NULL;
    size_t sample_len = 0, classes = 0, frames_per_window = 0, tubelet = 0;
    if (failed(pvt3_classifier_load(argv[1], &model), "load", &status)) goto done;
    if (failed(pvt3_classifier_sample_len(model, &sample_len), "sample_len", &status)) goto done;
    if (failed(pvt3_classifier_num_classes(model, &classes), "num_classes", &status)) goto done;
    if (failed(pvt3_classifier_frames(model, &frames_per_window), "frames", &status)) goto done;
    if (failed(pvt3_classifier_tubelet(model, &tubelet), "tubelet", &status)) goto done;
    size_t frame_len = sample_len / frames_per_window;
    if (print_input(model, &status)) goto done;

    FILE *f = fopen(argv[2], "rb");
    if (!f) {
        fprintf(stderr, "classify: cannot open %s\n", argv[2]);
        status = 1;
        goto done;
    }
    size_t n = batch * sample_len;
    frames = malloc(n * sizeof(float));
    probs = malloc(batch * classes * sizeof(float));
    best = malloc(batch * sizeof(size_t));
    frame = malloc(frame_len * sizeof(float));
    size_t got = fread(frames, sizeof(float), n, f);
    fclose(f);
    /* Start-up: build the plans now, so that the first classification costs what every one does. */
    if (failed(pvt3_classifier_prepare(model, batch, 1), "prepare", &status)) goto done;
    if (failed(pvt3_classify(model, frames, got, batch, probs, batch * classes, best), "classify", &status)) goto done;
    for (size_t i = 0; i < batch; i++) print("batch", model, i, best[i], probs + i * classes, classes);

    /* Each window streamed frame by frame, as a robot records a touch: each kept frame is encoded as
     * it arrives, and finishing runs only the temporal stage. */
    if (failed(pvt3_session_new(model, &session), "session_new", &status)) goto done;
    for (size_t i = 0; i < batch; i++) {
        for (size_t t = 0; t < frames_per_window; t++) {
            frame_at(frames + i * sample_len, t, frames_per_window, frame, frame_len);
            if (failed(pvt3_session_push_frame(session, frame, frame_len), "push_frame", &status)) goto done;
        }
        size_t class = 0, received = 0;
        if (failed(pvt3_session_received(session, &received), "session_received", &status)) goto done;
        if (received != frames_per_window) {
            fprintf(stderr, "classify: the session took %zu of the window's %zu frames\n", received, frames_per_window);
            status = 1;
            goto done;
        }
        if (failed(pvt3_session_finish(session, probs, classes, &class), "finish", &status)) goto done;
        print("stream", model, i, class, probs, classes);
    }
    /* Touches ended halfway: a provisional answer from the frames so far (a robot ends the touch
     * when `stop` says the file's stopping rule is met), then the session reset for the next. */
    for (size_t i = 0; i < batch; i++) {
        for (size_t t = 0; t < frames_per_window / 2; t++) {
            frame_at(frames + i * sample_len, t, frames_per_window, frame, frame_len);
            if (failed(pvt3_session_push_frame(session, frame, frame_len), "push_frame", &status)) goto done;
        }
        size_t class = 0, used = 0;
        int stop = 0;
        if (failed(pvt3_session_peek(session, probs, classes, &class, &used, &stop), "peek", &status)) goto done;
        print("peek", model, i, class, probs, classes);
        if (failed(pvt3_session_reset(session), "session_reset", &status)) goto done;
    }

    /* The windows back to back as one stream that never ends: an answer for the latest window
     * once a window is in, then every `tokens` temporal tokens (here: once a window, so the
     * answers are the windows' own). */
    if (failed(pvt3_continuous_new(model, frames_per_window / tubelet, &slide), "continuous_new", &status)) goto done;
    for (size_t i = 0; i < batch; i++) {
        for (size_t t = 0; t < frames_per_window; t++) {
            frame_at(frames + i * sample_len, t, frames_per_window, frame, frame_len);
            size_t class = 0;
            int answered = 0;
            if (failed(pvt3_continuous_push_frame(slide, frame, frame_len, probs, classes, &class, &answered), "continuous_push_frame",
                       &status))
                goto done;
            if (answered) print("slide", model, i, class, probs, classes);
        }
    }
    uint64_t slid = 0;
    if (failed(pvt3_continuous_received(slide, &slid), "continuous_received", &status)) goto done;
    if (slid != (uint64_t)(batch * frames_per_window)) {
        fprintf(stderr, "classify: the stream took %llu frames of %zu\n", (unsigned long long)slid, batch * frames_per_window);
        status = 1;
        goto done;
    }

    /* The scores the probabilities are the softmax of, for a robot that combines touches. */
    if (failed(pvt3_classify_logits(model, frames, got, batch, probs, batch * classes), "classify_logits", &status)) goto done;
    for (size_t i = 0; i < batch; i++) {
        printf("logits\t%zu", i);
        for (size_t k = 0; k < classes; k++) printf("\t%.9g", probs[i * classes + k]);
        printf("\n");
    }
done:
    pvt3_continuous_free(slide);
    pvt3_session_free(session);
    pvt3_classifier_free(model);
    free(frame);
    free(frames);
    free(probs);
    free(best);
    return status;
}
