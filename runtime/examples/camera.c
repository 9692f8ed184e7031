/* Classify a camera-based sensor's touch (GelSight, DIGIT) with the pvt3 C ABI, from its frames
 * as the camera gives them.
 *
 *   camera MODEL.onnx TOUCH.u8
 *
 * TOUCH.u8 holds the touch's 8-bit frames back to back, each pvt3_classifier_camera_frame_len
 * bytes (height x width x channels, row-major, channels innermost, as the camera delivers them);
 * for a model trained on frames less the touch's first (`pvt3 import --subtract-first`), the first
 * is the gel before contact. The session reads each frame as the training's `pvt3 import` read its
 * videos (crop, shrink, grey: the file says how) and answers once the touch is in. Prints
 * "camera", the class index, its name and probability, then all probabilities. */
#include <stdio.h>
#include <stdlib.h>

#include "pvt3.h"

static int failed(int rc, const char *what, int *status) {
    if (rc == PVT3_OK) return 0;
    fprintf(stderr, "camera: %s: %s [%s]\n", what, pvt3_last_error(), pvt3_status_text(rc));
    *status = 1;
    return 1;
}

int main(int argc, char **argv) {
    if (argc != 3) {
        fprintf(stderr, "usage: camera MODEL.onnx TOUCH.u8\n");
        return 2;
    }
    int status = 0;
    pvt3_classifier *model = NULL;
    pvt3_session *session = NULL;
    unsigned char *frame = NULL;
    float *probs = NULL;
    FILE *f = NULL;
    size_t frame_len = 0, classes = 0, class = 0;
    if (failed(pvt3_classifier_load(argv[1], &model), "load", &status)) goto done;
    if (failed(pvt3_classifier_camera_frame_len(model, &frame_len), "camera_frame_len", &status)) goto done;
    if (failed(pvt3_classifier_num_classes(model, &classes), "num_classes", &status)) goto done;
    if (failed(pvt3_session_new(model, &session), "session_new", &status)) goto done;
    f = fopen(argv[2], "rb");
    if (!f) {
        fprintf(stderr, "camera: cannot open %s\n", argv[2]);
        status = 1;
        goto done;
    }
    frame = malloc(frame_len);
    probs = malloc(classes * sizeof(float));
    /* Frame after frame, as a robot's camera delivers them. */
    while (fread(frame, 1, frame_len, f) == frame_len) {
        if (failed(pvt3_session_push_camera_frame(session, frame, frame_len), "push_camera_frame", &status)) goto done;
    }
    if (failed(pvt3_session_finish(session, probs, classes, &class), "finish", &status)) goto done;
    const char *name = "?";
    size_t name_len = 1;
    pvt3_classifier_class_name(model, class, &name, &name_len);
    printf("camera\t%zu\t%.*s\t%.6f", class, (int)name_len, name, probs[class]);
    for (size_t k = 0; k < classes; k++) printf("\t%.9g", probs[k]);
    printf("\n");
done:
    if (f) fclose(f);
    pvt3_session_free(session);
    pvt3_classifier_free(model);
    free(frame);
    free(probs);
    return status;
}
