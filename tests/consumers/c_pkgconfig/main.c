/* An out-of-tree C99 consumer of an installed ngi, built through pkg-config (tools/ci/install_consumers.sh):
 * lists the devices, loads a model, runs it on a small input and checks the output is finite. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include <ngi.h>

int main(int argc, char** argv) {
    ngi_device* device = NULL;
    ngi_model* model = NULL;
    int count = 0, in_nc = 0, out_nc = 0, downs = 0;
    int h, w;
    size_t i, in_bytes, out_bytes;
    float *x, *y;
    char name[256];
    if (argc != 2) {
        fprintf(stderr, "usage: %s model.safetensors\n", argv[0]);
        return 2;
    }
    if (ngi_version() != NGI_VERSION) {
        fprintf(stderr, "header %d, library %d\n", NGI_VERSION, ngi_version());
        return 1;
    }
    if (ngi_device_count(&count) != NGI_OK || count < 1 || ngi_device_open(NULL, &device) != NGI_OK ||
        ngi_device_string(device, NGI_DEVICE_NAME, name, sizeof name, NULL) != NGI_OK ||
        ngi_model_load(device, argv[1], &model) != NGI_OK ||
        ngi_model_channels(model, &in_nc, &out_nc, &downs) != NGI_OK) {
        fprintf(stderr, "c consumer: %s\n", ngi_last_error());
        return 1;
    }
    h = w = 1 << downs;
    in_bytes = (size_t)in_nc * h * w * sizeof(float);
    out_bytes = (size_t)out_nc * h * w * sizeof(float);
    x = (float*)malloc(in_bytes);
    y = (float*)malloc(out_bytes);
    for (i = 0; i < in_bytes / sizeof(float); ++i) x[i] = (float)(i % 7) / 7.0f;
    if (ngi_model_run(model, x, in_bytes, h, w, y, out_bytes) != NGI_OK) {
        fprintf(stderr, "c consumer: %s\n", ngi_last_error());
        return 1;
    }
    for (i = 0; i < out_bytes / sizeof(float); ++i)
        if (!isfinite(y[i])) {
            fprintf(stderr, "c consumer: output %lu is not finite\n", (unsigned long)i);
            return 1;
        }
    printf("c consumer: ngi %d on %s (%d devices): %dx%d, %d -> %d channels, finite\n", ngi_version(), name, count, h,
           w, in_nc, out_nc);
    ngi_model_release(model);
    ngi_device_release(device);
    free(x);
    free(y);
    return 0;
}
