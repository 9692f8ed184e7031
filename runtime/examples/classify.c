/* Classify windows with the pvt3 C ABI.
 *
 *   classify MODEL.onnx FRAMES.f32 BATCH
 *
 * FRAMES.f32 holds BATCH windows of raw float32 values (little-endian, the model's input layout).
 * Prints, per window, the class index, its name and probability, then all probabilities. */
#include <stdio.h>
#include <stdlib.h>

#include "pvt3.h"

static int fail(const char *what) {
    fprintf(stderr, "classify: %s: %s\n", what, pvt3_last_error());
    return 1;
}

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: classify MODEL.onnx FRAMES.f32 BATCH\n");
        return 2;
    }
    size_t batch = (size_t)strtoul(argv[3], NULL, 10);
    pvt3_classifier *model = NULL;
    if (pvt3_classifier_load(argv[1], &model) != PVT3_OK) return fail("load");
    size_t sample_len = 0, classes = 0;
    if (pvt3_classifier_sample_len(model, &sample_len) != PVT3_OK) return fail("sample_len");
    if (pvt3_classifier_num_classes(model, &classes) != PVT3_OK) return fail("num_classes");

    FILE *f = fopen(argv[2], "rb");
    if (!f) {
        fprintf(stderr, "classify: cannot open %s\n", argv[2]);
        return 1;
    }
    size_t n = batch * sample_len;
    float *frames = malloc(n * sizeof(float));
    size_t got = fread(frames, sizeof(float), n, f);
    fclose(f);
    float *probs = malloc(batch * classes * sizeof(float));
    size_t *best = malloc(batch * sizeof(size_t));
    if (pvt3_classify(model, frames, got, batch, probs, batch * classes, best) != PVT3_OK) return fail("classify");
    for (size_t i = 0; i < batch; i++) {
        const char *name = NULL;
        if (pvt3_classifier_class_name(model, best[i], &name) != PVT3_OK) return fail("class_name");
        printf("%zu\t%zu\t%s\t%.6f", i, best[i], name, probs[i * classes + best[i]]);
        for (size_t k = 0; k < classes; k++) printf("\t%.9g", probs[i * classes + k]);
        printf("\n");
    }
    free(frames);
    free(probs);
    free(best);
    pvt3_classifier_free(model);
    return 0;
}
