/* A C99 program that uses only ngi.h: reads a frame folder's planes into memory, runs the surround pipeline through
 * the C ABI and writes the front view's GI lightmap (linear, EXR) and the tone-mapped final image (PNG).
 *
 *   ngi_c_lightmap <frame folder> <model.safetensors> <lightmap.exr> <final.png> [device]
 *
 * The model decides what the frame must hold: a surround model (12 input channels) reads all six faces, a
 * single-view model (10) the front face only. */
#include <stdio.h>
#include <stdlib.h>

#include "ngi.h"

/* Prints the failing call's status and message and leaves with exit code 1. */
static void check(ngi_status status) {
    if (status != NGI_OK) {
        fprintf(stderr, "ngi_c_lightmap: %s: %s\n", ngi_status_name(status), ngi_last_error());
        exit(1);
    }
}

int main(int argc, char** argv) {
    ngi_device* device = NULL;
    ngi_model* model = NULL;
    ngi_pipeline* pipeline = NULL;
    int input_nc = 0, faces, n = 0;
    size_t plane_bytes = 0, out_bytes;
    unsigned flags = 0;
    float look[3], up[3];
    float *planes, *lightmap, *display;
    if (argc < 5 || argc > 6) {
        fprintf(stderr, "usage: %s <frame folder> <model.safetensors> <lightmap.exr> <final.png> [device]\n", argv[0]);
        return 2;
    }
    if (ngi_version() / 100 != NGI_VERSION / 100) {
        fprintf(stderr, "ngi_c_lightmap: built against ngi %d, running with %d\n", NGI_VERSION, ngi_version());
        return 1;
    }
    check(ngi_device_open(argc == 6 ? argv[5] : NULL, &device));
    check(ngi_model_load(device, argv[2], &model));
    check(ngi_model_channels(model, &input_nc, NULL, NULL));
    faces = input_nc == 12 ? 6 : 1;

    /* First call: the frame's size; second: its planes. */
    check(ngi_read_frame_planes(argv[1], faces, NULL, 0, &n, &plane_bytes, &flags, look, up));
    planes = (float*)malloc(plane_bytes);
    out_bytes = (size_t)n * (size_t)n * 3 * sizeof(float);
    lightmap = (float*)malloc(out_bytes);
    display = (float*)malloc(out_bytes);
    if (!planes || !lightmap || !display) {
        fprintf(stderr, "ngi_c_lightmap: out of memory\n");
        return 1;
    }
    check(ngi_read_frame_planes(argv[1], faces, planes, plane_bytes, NULL, NULL, NULL, NULL, NULL));

    check(ngi_pipeline_new(device, n, NGI_GLOBAL_VIEW_THESIS, NGI_TRANSFER_REINHARD, &pipeline));
    check(ngi_pipeline_set_camera(pipeline, look, up));
    check(ngi_pipeline_run(pipeline, model, planes, plane_bytes, faces, flags, lightmap, out_bytes, NULL, 0, display,
                           out_bytes));
    check(ngi_write_image(argv[3], lightmap, out_bytes, n, n, 3));
    check(ngi_write_image(argv[4], display, out_bytes, n, n, 3));
    printf("ngi_c_lightmap: %dx%d lightmap -> %s, final image -> %s\n", n, n, argv[3], argv[4]);

    check(ngi_pipeline_release(pipeline));
    check(ngi_model_release(model));
    check(ngi_device_release(device));
    free(planes);
    free(lightmap);
    free(display);
    return 0;
}
