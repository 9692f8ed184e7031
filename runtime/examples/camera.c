/* Classify a camera-based sensor's touch (GelSight, DIGIT) with the pvt3 C ABI, from its frames
 * as the camera gives them.
 *
 *   camera MODEL.onnx TOUCH.u8
 *
 * TOUCH.u8 holds the touch's 8-bit frames back to back, each height x width x channels bytes
 * (pvt3_classifier_camera_shape; row-major, channels innermost, as the camera delivers them);
 * for a model trained on frames less the touch's first (`pvt3 import --subtract-first`), the first
 * is the gel before contact. The session reads each frame as the training's `pvt3 import` read its
 * videos (crop, shrink, grey: the file says how) and answers once the touch is in; then the touch
 * is classified whole, as a robot that records first and classifies after. Prints, per way
 * ("camera", then "whole"), the class index, its name and probability, then all probabilities. */
#include <stdio.h>
#include <stdlib.h>

#include "pvt3.h"

static int failed(int rc, const char *what, int *status) {
    if (rc == PVT3_OK) return 0;
    fprintf(stderr, "camera: %s: %s [%s]\n", what, pvt3_last_error(), pvt3_status_text(rc));
    *status = 1;
    return 1;
}

static void print(const char *way, const pvt3_classifier *model, size_t class, const float *probs, size_t classes) {
    const char *name = "?";
    size_t name_len = 1;
    pvt3_classifier_class_name(model, class, &name, &name_len);
    printf("%s\t%zu\t%.*s\t%.6f", way, class, (int)name_len, name, probs[class]);
    for (size_t k = 0; k < classes; k++) printf("\t%.9g", probs[k]);
    printf("\n");
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: camera MODEL.onnx TOUCH.u8\n");
        return 2;
    }
    int status = 0;
    pvt3_classifier *model = NULL;
    pvt3_session *session = NULL;
    unsigned char *touch = NULL, *whole = NULL;
    float *probs = NULL;
    FILE *f = NULL;
    size_t height = 0, width = 0, channels = 0, classes = 0, class = 0, frames = 0;
    if (failed(pvt3_classifier_load(argv[1], &model), "load", &status)) goto done;
    if (failed(pvt3_classifier_camera_shape(model, &height, &width, &channels), "camera_shape", &status)) goto done;
    size_t frame_len = height * width * channels;
    if (failed(pvt3_classifier_num_classes(model, &classes), "num_classes", &status)) goto done;
    if (failed(pvt3_session_new(model, &session), "session_new", &status)) goto done;
    f = fopen(argv[2], "rb");
    if (!f) {
        fprintf(stderr, "camera: cannot open %s\n", argv[2]);
        status = 1;
        goto done;
    }
    fseek(f, 0, SEEK_END);
    frames = (size_t)ftell(f) / frame_len;
    rewind(f);
    touch = malloc(frames * frame_len + 1);
    whole = malloc(frames * frame_len + 1);
    probs = malloc(classes * sizeof(float));
    if (fread(touch, frame_len, frames, f) != frames) {
        fprintf(stderr, "camera: cannot read %s\n", argv[2]);
        status = 1;
        goto done;
    }
    /* Frame after frame, as a robot's camera delivers them. */
    for (size_t t = 0; t < frames; t++) {
        if (failed(pvt3_session_push_camera_frame(session, touch + t * frame_len, frame_len), "push_camera_frame", &status)) goto done;
    }
    if (failed(pvt3_session_finish(session, probs, classes, &class), "finish", &status)) goto done;
    print("camera", model, class, probs, classes);
    /* The same touch whole, frames innermost: [height, width, channels, frames]. */
    for (size_t t = 0; t < frames; t++)
        for (size_t j = 0; j < frame_len; j++) whole[j * frames + t] = touch[t * frame_len + j];
    if (failed(pvt3_classify_camera_touches(model, whole, frames * frame_len, 1, probs, classes, &class), "classify_camera_touches",
               &status))
        goto done;
    print("whole", model, class, probs, classes);
done:
    if (f) fclose(f);
    pvt3_session_free(session);
    pvt3_classifier_free(model);
    free(touch);
    free(whole);
    free(probs);
    return status;
}
