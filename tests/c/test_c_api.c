/* The C ABI from C99 (compiled with -std=c99 -pedantic -Werror): versions, device listing, handles and their
 * reference counts, explicit sizes, every kind of bad argument, the error callback and the thread-local last error,
 * the surround pipeline host path against the device path, their host-transfer counts, and an application's own
 * OpenCL context, queue and buffers. Usage: test_c_api <source dir> (models/ inside it). Exit code 0 = all passed. */
#include <CL/cl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ngi.h"

static int failures = 0, checks = 0;

#define CHECK(cond)                                                                                   \
    do {                                                                                              \
        ++checks;                                                                                     \
        if (!(cond)) {                                                                                \
            ++failures;                                                                               \
            fprintf(stderr, "%s:%d: CHECK(%s) failed; last error: %s\n", __FILE__, __LINE__, #cond,  \
                    ngi_last_error());                                                                \
        }                                                                                             \
    } while (0)

/* The call failed with `status`, and its message names the call and mentions `word`. */
#define CHECK_FAILS(call_expr, status, name, word)                                                    \
    do {                                                                                              \
        ngi_status s_ = (call_expr);                                                                  \
        CHECK(s_ == (status));                                                                        \
        CHECK(strstr(ngi_last_error(), name) != NULL);                                                \
        CHECK(strstr(ngi_last_error(), word) != NULL);                                                \
    } while (0)

static int callback_calls = 0;
static ngi_status callback_status = NGI_OK;
static void on_error(void* user, ngi_status status, const char* message) {
    (void)message;
    ++*(int*)user;
    callback_status = status;
}

/* Deterministic frame planes with plausible values (albedo, normal, depth, direct; emission and env zero). */
static void fill_planes(float* p, int n, int faces) {
    unsigned state = 12345u;
    int f, plane, i;
    const size_t np = (size_t)n * (size_t)n;
    for (f = 0; f < faces; ++f)
        for (plane = 0; plane < 16; ++plane)
            for (i = 0; i < (int)np; ++i) {
                float u;
                state = state * 1664525u + 1013904223u;
                u = (float)(state >> 8) / 16777216.0f;
                float* v = &p[((size_t)f * 16 + (size_t)plane) * np + (size_t)i];
                if (plane < 3) *v = u;                        /* albedo */
                else if (plane < 6) *v = 2.0f * u - 1.0f;     /* normal */
                else if (plane == 6) *v = 0.5f + 30.0f * u;   /* depth */
                else if (plane < 10) *v = 3.0f * u;           /* direct */
                else *v = 0.0f;
            }
}

static void test_errors_and_listing(void) {
    int count = 0;
    long long v = 0;
    char name[256];
    char tiny[4];
    size_t needed = 0;
    CHECK(ngi_version() == NGI_VERSION);
    CHECK(strcmp(ngi_status_name(NGI_ERROR_OUT_OF_MEMORY), "NGI_ERROR_OUT_OF_MEMORY") == 0);
    CHECK(ngi_device_count(&count) == NGI_OK && count >= 1);
    CHECK(strcmp(ngi_last_error(), "") == 0);
    CHECK(ngi_device_list_string(0, NGI_DEVICE_NAME, name, sizeof name, &needed) == NGI_OK);
    CHECK(strlen(name) > 0 && needed == strlen(name) + 1);
    CHECK_FAILS(ngi_device_list_string(0, NGI_DEVICE_NAME, tiny, sizeof tiny, &needed), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_device_list_string", "too small");
    CHECK(strlen(tiny) == 3); /* truncated, terminated */
    CHECK_FAILS(ngi_device_list_string(count, NGI_DEVICE_NAME, name, sizeof name, NULL), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_device_list_string", "index");
    CHECK_FAILS(ngi_device_list_integer(0, NGI_DEVICE_NAME, &v), NGI_ERROR_INVALID_ARGUMENT, "ngi_device_list_integer",
                "not an integer property");
    CHECK(ngi_device_list_integer(0, NGI_DEVICE_COMPUTE_UNITS, &v) == NGI_OK && v >= 1);
    CHECK_FAILS(ngi_device_count(NULL), NGI_ERROR_INVALID_ARGUMENT, "ngi_device_count", "NULL");
    /* Each call resets the last error. */
    CHECK(ngi_device_count(&count) == NGI_OK);
    CHECK(strcmp(ngi_last_error(), "") == 0);
}

static void test_null_handles(void) {
    float f[4] = {0, 0, 0, 0};
    size_t bytes = 0;
    int i = 0;
    long long v = 0;
    ngi_device* d = NULL;
    ngi_model* m = NULL;
    ngi_buffer* b = NULL;
    ngi_pipeline* p = NULL;
    CHECK_FAILS(ngi_device_open("no-such-device-xyz", &d), NGI_ERROR_INPUT, "ngi_device_open", "no device matches");
    CHECK(d == NULL);
    CHECK_FAILS(ngi_device_open(NULL, NULL), NGI_ERROR_INVALID_ARGUMENT, "ngi_device_open", "out is NULL");
    CHECK_FAILS(ngi_device_integer(NULL, NGI_DEVICE_IS_GPU, &v), NGI_ERROR_INVALID_HANDLE, "ngi_device_integer", "device");
    CHECK_FAILS(ngi_device_sync(NULL), NGI_ERROR_INVALID_HANDLE, "ngi_device_sync", "device is NULL");
    CHECK_FAILS(ngi_device_from_opencl(NULL, NULL, NULL, &d), NGI_ERROR_INVALID_ARGUMENT, "ngi_device_from_opencl", "NULL");
    CHECK_FAILS(ngi_model_load(NULL, "x", &m), NGI_ERROR_INVALID_HANDLE, "ngi_model_load", "device");
    CHECK_FAILS(ngi_model_run(NULL, f, sizeof f, 1, 1, f, sizeof f), NGI_ERROR_INVALID_HANDLE, "ngi_model_run", "model");
    CHECK_FAILS(ngi_model_channels(NULL, &i, &i, &i), NGI_ERROR_INVALID_HANDLE, "ngi_model_channels", "model");
    CHECK_FAILS(ngi_model_enqueue(NULL, NULL, NULL, 64, 64), NGI_ERROR_INVALID_HANDLE, "ngi_model_enqueue", "model");
    CHECK_FAILS(ngi_buffer_new(NULL, 16, &b), NGI_ERROR_INVALID_HANDLE, "ngi_buffer_new", "device");
    CHECK_FAILS(ngi_buffer_size(NULL, &bytes), NGI_ERROR_INVALID_HANDLE, "ngi_buffer_size", "buffer");
    CHECK_FAILS(ngi_buffer_write(NULL, 0, f, 4), NGI_ERROR_INVALID_HANDLE, "ngi_buffer_write", "buffer");
    CHECK_FAILS(ngi_pipeline_new(NULL, 64, NGI_GLOBAL_VIEW_THESIS, NGI_TRANSFER_REINHARD, &p), NGI_ERROR_INVALID_HANDLE,
                "ngi_pipeline_new", "device");
    CHECK_FAILS(ngi_pipeline_run(NULL, NULL, f, sizeof f, 6, 0, f, sizeof f, NULL, 0, NULL, 0), NGI_ERROR_INVALID_HANDLE,
                "ngi_pipeline_run", "pipeline");
    CHECK_FAILS(ngi_read_frame_planes(NULL, 6, NULL, 0, &i, &bytes, NULL, NULL, NULL), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_read_frame_planes", "folder is NULL");
    CHECK_FAILS(ngi_read_frame_planes("/nonexistent/frame", 6, NULL, 0, &i, &bytes, NULL, NULL, NULL), NGI_ERROR_INPUT,
                "ngi_read_frame_planes", "/nonexistent/frame");
    CHECK_FAILS(ngi_write_image(NULL, f, sizeof f, 2, 2, 1), NGI_ERROR_INVALID_ARGUMENT, "ngi_write_image", "path");
    CHECK_FAILS(ngi_write_image("/tmp/ngi_c_api_small.exr", f, sizeof f - 1, 2, 2, 1), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_write_image", "bytes");
    /* Releasing NULL is a no-op, like free(NULL). */
    CHECK(ngi_model_release(NULL) == NGI_OK);
    CHECK(ngi_device_release(NULL) == NGI_OK);
}

static void test_model(ngi_device* dev, const char* models) {
    char path[4096];
    ngi_model* m = NULL;
    int in_nc = 0, out_nc = 0, downs = 0, sanitized = -1;
    const int h = 64, w = 64;
    float *x, *y;
    size_t in_bytes, out_bytes, i;
    snprintf(path, sizeof path, "%s/single_view.safetensors", models);
    CHECK_FAILS(ngi_model_load(dev, "/nonexistent.safetensors", &m), NGI_ERROR_INPUT, "ngi_model_load",
                "/nonexistent.safetensors");
    CHECK_FAILS(ngi_model_load_with_options(dev, path, (ngi_bn_mode)7, NGI_DROPOUT_OFF, &m), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_model_load_with_options", "bn_mode");
    CHECK_FAILS(ngi_model_load_with_options(dev, path, NGI_BN_FROM_FILE, (ngi_dropout)-1, &m), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_model_load_with_options", "dropout -1");
    CHECK(ngi_model_load_with_options(dev, path, NGI_BN_FROM_FILE, NGI_DROPOUT_OFF, &m) == NGI_OK);
    CHECK(ngi_model_channels(m, &in_nc, &out_nc, &downs) == NGI_OK && in_nc == 10 && out_nc == 3 && downs == 6);
    {
        ngi_output_mode mode = NGI_OUTPUT_INDIRECT;
        CHECK(ngi_model_output_mode(m, &mode) == NGI_OK && mode == NGI_OUTPUT_LIGHTMAP);  /* no key: lightmap */
        CHECK_FAILS(ngi_model_output_mode(m, NULL), NGI_ERROR_INVALID_ARGUMENT, "ngi_model_output_mode", "mode");
        CHECK_FAILS(ngi_model_output_mode(NULL, &mode), NGI_ERROR_INVALID_HANDLE, "ngi_model_output_mode", "model");
    }
    in_bytes = (size_t)in_nc * h * w * sizeof(float);
    out_bytes = (size_t)out_nc * h * w * sizeof(float);
    x = (float*)malloc(in_bytes);
    y = (float*)malloc(out_bytes);
    for (i = 0; i < in_bytes / sizeof(float); ++i) x[i] = (float)((i * 7919u) % 1000u) / 500.0f - 1.0f;
    x[5] = NAN;
    x[6] = INFINITY;
    CHECK_FAILS(ngi_model_run(m, x, in_bytes - 4, h, w, y, out_bytes), NGI_ERROR_INVALID_ARGUMENT, "ngi_model_run",
                "input_bytes");
    CHECK_FAILS(ngi_model_run(m, x, in_bytes, h, w, y, out_bytes - 1), NGI_ERROR_INVALID_ARGUMENT, "ngi_model_run",
                "output_bytes");
    CHECK_FAILS(ngi_model_run(m, x, in_bytes, 0, w, y, out_bytes), NGI_ERROR_INVALID_ARGUMENT, "ngi_model_run", "positive");
    CHECK_FAILS(ngi_model_run(m, x, in_bytes, 32, 32, y, out_bytes), NGI_ERROR_INPUT, "ngi_model_run", "32");
    CHECK(ngi_model_run(m, x, in_bytes, h, w, y, out_bytes) == NGI_OK);
    CHECK(ngi_model_sanitized_inputs(m, &sanitized) == NGI_OK && sanitized == 2);
    for (i = 0; i < out_bytes / sizeof(float); ++i)
        if (!isfinite(y[i])) break;
    CHECK(i == out_bytes / sizeof(float));

    /* Reference counts: a retained model survives one release; the last release ends it; a third is refused. */
    CHECK(ngi_model_retain(m) == NGI_OK);
    CHECK(ngi_model_release(m) == NGI_OK);
    CHECK(ngi_model_channels(m, &in_nc, NULL, NULL) == NGI_OK);
    CHECK(ngi_model_release(m) == NGI_OK);
    CHECK_FAILS(ngi_model_channels(m, &in_nc, NULL, NULL), NGI_ERROR_INVALID_HANDLE, "ngi_model_channels", "not a live handle");
    CHECK_FAILS(ngi_model_release(m), NGI_ERROR_INVALID_HANDLE, "ngi_model_release", "not a live handle");
    free(x);
    free(y);
}

/* The surround pipeline: host run vs device enqueue (bitwise equal), transfer counts, bad arguments. */
static void test_pipeline(ngi_device* dev, const char* models) {
    char path[4096];
    const int n = 64;
    ngi_model* m = NULL;
    ngi_pipeline* p = NULL;
    ngi_buffer *planes_b = NULL, *light_b = NULL, *disp_b = NULL, *small_b = NULL;
    size_t plane_bytes = 0, out_bytes = (size_t)n * n * 3 * sizeof(float);
    float *planes, *light, *disp, *light2, *disp2;
    long long up0, down0, up1, down1;
    const float look[3] = {0.2f, 0.1f, -1.0f}, up[3] = {0.0f, 1.0f, 0.0f}, bad_up[3] = {0.4f, 0.2f, -2.0f};
    snprintf(path, sizeof path, "%s/surround.safetensors", models);
    CHECK(ngi_model_load(dev, path, &m) == NGI_OK);
    CHECK_FAILS(ngi_pipeline_new(dev, 3, NGI_GLOBAL_VIEW_THESIS, NGI_TRANSFER_REINHARD, &p), NGI_ERROR_INPUT,
                "ngi_pipeline_new", "3");
    CHECK_FAILS(ngi_pipeline_new(dev, n, (ngi_global_view_mode)9, NGI_TRANSFER_REINHARD, &p), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_pipeline_new", "mode");
    CHECK(ngi_pipeline_new(dev, n, NGI_GLOBAL_VIEW_THESIS, NGI_TRANSFER_REINHARD, &p) == NGI_OK);
    CHECK(ngi_pipeline_frame_bytes(p, 6, &plane_bytes) == NGI_OK && plane_bytes == (size_t)6 * 16 * n * n * 4);
    CHECK(ngi_pipeline_set_camera(p, look, up) == NGI_OK);
    CHECK_FAILS(ngi_pipeline_set_camera(p, look, bad_up), NGI_ERROR_INVALID_ARGUMENT, "ngi_pipeline_set_camera", "parallel");
    CHECK_FAILS(ngi_pipeline_set_tonemap(p, 100.0f, NGI_TONE_ACES, 1), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_pipeline_set_tonemap", "exposure_ev");
    CHECK(ngi_pipeline_set_tonemap(p, 0.5f, NGI_TONE_REINHARD, 1) == NGI_OK);

    planes = (float*)malloc(plane_bytes);
    light = (float*)malloc(out_bytes);
    disp = (float*)malloc(out_bytes);
    light2 = (float*)malloc(out_bytes);
    disp2 = (float*)malloc(out_bytes);
    fill_planes(planes, n, 6);
    CHECK_FAILS(ngi_pipeline_run(p, m, planes, plane_bytes - 4, 6, 0, light, out_bytes, NULL, 0, disp, out_bytes),
                NGI_ERROR_INPUT, "ngi_pipeline_run", "planes hold");
    CHECK_FAILS(ngi_pipeline_run(p, m, planes, plane_bytes, 6, 0, light, out_bytes - 4, NULL, 0, disp, out_bytes),
                NGI_ERROR_INVALID_ARGUMENT, "ngi_pipeline_run", "lightmap_bytes");
    CHECK_FAILS(ngi_pipeline_run(p, m, planes, plane_bytes, 6, 8, light, out_bytes, NULL, 0, NULL, 0),
                NGI_ERROR_INVALID_ARGUMENT, "ngi_pipeline_run", "flags");
    CHECK_FAILS(ngi_pipeline_run(p, m, planes, plane_bytes, 1, 0, light, out_bytes, NULL, 0, NULL, 0), NGI_ERROR_INPUT,
                "ngi_pipeline_run", "6 faces");
    CHECK(ngi_pipeline_run(p, m, planes, plane_bytes, 6, 0, light, out_bytes, NULL, 0, disp, out_bytes) == NGI_OK);
    CHECK(ngi_device_host_transfers(dev, &up0, &down0) == NGI_OK);
    CHECK(ngi_pipeline_run(p, m, planes, plane_bytes, 6, 0, light, out_bytes, NULL, 0, disp, out_bytes) == NGI_OK);
    CHECK(ngi_device_host_transfers(dev, &up1, &down1) == NGI_OK);
    CHECK(up1 - up0 == 1 && down1 - down0 == 1);

    CHECK(ngi_buffer_new(dev, plane_bytes, &planes_b) == NGI_OK);
    CHECK(ngi_buffer_new(dev, out_bytes, &light_b) == NGI_OK);
    CHECK(ngi_buffer_new(dev, out_bytes, &disp_b) == NGI_OK);
    CHECK(ngi_buffer_new(dev, 64, &small_b) == NGI_OK);
    CHECK(ngi_buffer_write(planes_b, 0, planes, plane_bytes) == NGI_OK);
    CHECK_FAILS(ngi_buffer_write(planes_b, 8, planes, plane_bytes), NGI_ERROR_INPUT, "ngi_buffer_write", "outside");
    CHECK_FAILS(ngi_pipeline_enqueue(p, m, planes_b, 6, 0, small_b, NULL, NULL), NGI_ERROR_INPUT, "ngi_pipeline_enqueue",
                "lightmap buffer holds");
    CHECK_FAILS(ngi_pipeline_enqueue(p, m, small_b, 6, 0, light_b, NULL, NULL), NGI_ERROR_INPUT, "ngi_pipeline_enqueue",
                "planes buffer holds");
    CHECK_FAILS(ngi_pipeline_enqueue(p, m, planes_b, 6, 0, NULL, NULL, NULL), NGI_ERROR_INVALID_ARGUMENT,
                "ngi_pipeline_enqueue", "nothing to make");
    CHECK(ngi_pipeline_enqueue(p, m, planes_b, 6, 0, light_b, NULL, disp_b) == NGI_OK);
    CHECK(ngi_device_sync(dev) == NGI_OK);
    CHECK(ngi_device_host_transfers(dev, &up0, &down0) == NGI_OK);
    CHECK(ngi_pipeline_enqueue(p, m, planes_b, 6, 0, light_b, NULL, disp_b) == NGI_OK);
    CHECK(ngi_device_sync(dev) == NGI_OK);
    CHECK(ngi_device_host_transfers(dev, &up1, &down1) == NGI_OK);
    CHECK(up1 == up0 && down1 == down0);
    CHECK(ngi_buffer_read(light_b, 0, light2, out_bytes) == NGI_OK);
    CHECK(ngi_buffer_read(disp_b, 0, disp2, out_bytes) == NGI_OK);
    CHECK(memcmp(light, light2, out_bytes) == 0);
    CHECK(memcmp(disp, disp2, out_bytes) == 0);

    /* The same frame as image descriptors (each feature a planar float image inside the planes), from host memory
       and from the device buffer: the same bits. A descriptor that does not fit names its face and feature. */
    {
        static const int first_plane[6] = {0, 3, 6, 7, 10, 13};
        ngi_image_desc images[36];
        int f, k;
        memset(images, 0, sizeof images);
        for (f = 0; f < 6; ++f)
            for (k = 0; k < NGI_FEATURE_EMISSION; ++k) { /* emission and env absent: flags 0 above */
                ngi_image_desc* d = &images[f * 6 + k];
                d->host = planes;
                d->host_bytes = plane_bytes;
                d->format = NGI_FORMAT_F32;
                d->channels = k == NGI_FEATURE_DEPTH ? 1 : 3;
                d->width = d->height = n;
                d->offset = ((size_t)f * 16 + (size_t)first_plane[k]) * (size_t)n * n * sizeof(float);
                d->pixel_stride = sizeof(float);
                d->channel_stride = (size_t)n * n * sizeof(float);
            }
        CHECK(ngi_pipeline_run_images(p, m, images, light2, out_bytes, NULL, 0, disp2, out_bytes) == NGI_OK);
        CHECK(memcmp(light, light2, out_bytes) == 0);
        CHECK(memcmp(disp, disp2, out_bytes) == 0);
        for (f = 0; f < 36; ++f) {
            images[f].host = NULL;
            images[f].host_bytes = 0;
            if (images[f].channels) images[f].buffer = planes_b;
        }
        memset(light2, 0, out_bytes);
        CHECK(ngi_pipeline_enqueue_images(p, m, images, light_b, NULL, NULL) == NGI_OK);
        CHECK(ngi_buffer_read(light_b, 0, light2, out_bytes) == NGI_OK);
        CHECK(memcmp(light, light2, out_bytes) == 0);
        images[2 * 6 + NGI_FEATURE_NORMAL].channels = 2;
        CHECK_FAILS(ngi_pipeline_enqueue_images(p, m, images, light_b, NULL, NULL), NGI_ERROR_INPUT,
                    "ngi_pipeline_enqueue_images", "image 'normal' of face 'left' has 2 channels");
        CHECK_FAILS(ngi_pipeline_run_images(p, m, NULL, light2, out_bytes, NULL, 0, NULL, 0), NGI_ERROR_INVALID_ARGUMENT,
                    "ngi_pipeline_run_images", "images is NULL");
    }

    /* Out of memory is its own status. */
    {
        ngi_buffer* huge = NULL;
        CHECK_FAILS(ngi_buffer_new(dev, (size_t)1 << 62, &huge), NGI_ERROR_OUT_OF_MEMORY, "ngi_buffer_new", "bytes");
        CHECK(huge == NULL);
    }
    /* Objects keep what they were made from: the pipeline and model outlive the buffers' release order. */
    CHECK(ngi_buffer_release(small_b) == NGI_OK);
    CHECK(ngi_buffer_release(planes_b) == NGI_OK);
    CHECK(ngi_buffer_release(light_b) == NGI_OK);
    CHECK(ngi_buffer_release(disp_b) == NGI_OK);
    CHECK_FAILS(ngi_buffer_read(light_b, 0, light2, 4), NGI_ERROR_INVALID_HANDLE, "ngi_buffer_read", "not a live handle");
    CHECK(ngi_pipeline_release(p) == NGI_OK);
    CHECK(ngi_model_release(m) == NGI_OK);
    free(planes);
    free(light);
    free(disp);
    free(light2);
    free(disp2);
}

/* An application that owns its OpenCL context: its queue, its planes buffer, its lightmap buffer; no host copy. */
static void test_interop(ngi_device* ngi_dev, const char* models) {
    char path[4096];
    const int n = 64;
    struct _cl_context* ngi_ctx = NULL;
    struct _cl_command_queue* ngi_queue = NULL;
    cl_device_id cl_dev = NULL;
    cl_context app_ctx;
    cl_command_queue app_queue;
    cl_mem app_planes, app_light, foreign;
    cl_int err = CL_SUCCESS;
    ngi_device* dev = NULL;
    ngi_model* m = NULL;
    ngi_pipeline* p = NULL;
    ngi_buffer *planes_b = NULL, *light_b = NULL, *bad = NULL;
    size_t plane_bytes = (size_t)6 * 16 * n * n * 4, out_bytes = (size_t)3 * n * n * 4;
    float *planes = (float*)malloc(plane_bytes), *want = (float*)malloc(out_bytes), *got = (float*)malloc(out_bytes);
    long long up0, down0, up1, down1;

    CHECK(ngi_device_opencl(ngi_dev, &ngi_ctx, &ngi_queue) == NGI_OK);
    CHECK(clGetCommandQueueInfo(ngi_queue, CL_QUEUE_DEVICE, sizeof cl_dev, &cl_dev, NULL) == CL_SUCCESS);
    app_ctx = clCreateContext(NULL, 1, &cl_dev, NULL, NULL, &err);
    CHECK(err == CL_SUCCESS);
    app_queue = clCreateCommandQueue(app_ctx, cl_dev, 0, &err);
    CHECK(err == CL_SUCCESS);
    app_planes = clCreateBuffer(app_ctx, CL_MEM_READ_ONLY, plane_bytes, NULL, &err);
    app_light = clCreateBuffer(app_ctx, CL_MEM_READ_WRITE, out_bytes, NULL, &err);
    foreign = clCreateBuffer(ngi_ctx, CL_MEM_READ_WRITE, out_bytes, NULL, &err);
    fill_planes(planes, n, 6);
    CHECK(clEnqueueWriteBuffer(app_queue, app_planes, CL_TRUE, 0, plane_bytes, planes, 0, NULL, NULL) == CL_SUCCESS);

    /* The reference: the host path on ngi's own device. */
    snprintf(path, sizeof path, "%s/surround.safetensors", models);
    {
        ngi_model* rm = NULL;
        ngi_pipeline* rp = NULL;
        CHECK(ngi_model_load(ngi_dev, path, &rm) == NGI_OK);
        CHECK(ngi_pipeline_new(ngi_dev, n, NGI_GLOBAL_VIEW_THESIS, NGI_TRANSFER_REINHARD, &rp) == NGI_OK);
        CHECK(ngi_pipeline_run(rp, rm, planes, plane_bytes, 6, 0, want, out_bytes, NULL, 0, NULL, 0) == NGI_OK);
        ngi_pipeline_release(rp);
        ngi_model_release(rm);
    }

    CHECK(ngi_device_from_opencl(app_ctx, cl_dev, app_queue, &dev) == NGI_OK);
    CHECK(ngi_model_load(dev, path, &m) == NGI_OK);
    CHECK(ngi_pipeline_new(dev, n, NGI_GLOBAL_VIEW_THESIS, NGI_TRANSFER_REINHARD, &p) == NGI_OK);
    CHECK(ngi_buffer_wrap(dev, app_planes, 0, plane_bytes, &planes_b) == NGI_OK);
    CHECK(ngi_buffer_wrap(dev, app_light, 0, out_bytes, &light_b) == NGI_OK);
    CHECK_FAILS(ngi_buffer_wrap(dev, foreign, 0, out_bytes, &bad), NGI_ERROR_INPUT, "ngi_buffer_wrap", "another OpenCL context");
    CHECK_FAILS(ngi_buffer_wrap(dev, app_light, 0, out_bytes + 4, &bad), NGI_ERROR_INPUT, "ngi_buffer_wrap", "outside");
    CHECK_FAILS(ngi_pipeline_enqueue(p, m, planes_b, 6, 0, planes_b, NULL, NULL), NGI_ERROR_INPUT, "ngi_pipeline_enqueue",
                "READ_ONLY");
    CHECK(ngi_pipeline_enqueue(p, m, planes_b, 6, 0, light_b, NULL, NULL) == NGI_OK); /* warm-up */
    CHECK(ngi_device_host_transfers(dev, &up0, &down0) == NGI_OK);
    CHECK(ngi_pipeline_enqueue(p, m, planes_b, 6, 0, light_b, NULL, NULL) == NGI_OK);
    CHECK(ngi_device_host_transfers(dev, &up1, &down1) == NGI_OK);
    CHECK(up1 == up0 && down1 == down0);
    /* The application reads its own buffer on its own queue, in order after ngi's work. */
    CHECK(clEnqueueReadBuffer(app_queue, app_light, CL_TRUE, 0, out_bytes, got, 0, NULL, NULL) == CL_SUCCESS);
    CHECK(memcmp(got, want, out_bytes) == 0);
    /* Released in an order that leaves the device's last reference to the objects made from it. */
    CHECK(ngi_device_release(dev) == NGI_OK);
    CHECK(ngi_pipeline_release(p) == NGI_OK);
    CHECK(ngi_model_release(m) == NGI_OK);
    CHECK(ngi_buffer_release(planes_b) == NGI_OK);
    CHECK(ngi_buffer_release(light_b) == NGI_OK);
    clReleaseMemObject(foreign);
    clReleaseMemObject(app_planes);
    clReleaseMemObject(app_light);
    clReleaseCommandQueue(app_queue);
    clReleaseContext(app_ctx);
    free(planes);
    free(want);
    free(got);
}

int main(int argc, char** argv) {
    char models[2048];
    const char* spec = getenv("NGI_TEST_DEVICE");
    ngi_device* dev = NULL;
    if (argc != 2) {
        fprintf(stderr, "usage: %s <ngi source dir>\n", argv[0]);
        return 2;
    }
    snprintf(models, sizeof models, "%s/models", argv[1]);
    ngi_set_error_callback(on_error, &callback_calls);
    test_errors_and_listing();
    CHECK(callback_calls >= 3 && callback_status == NGI_ERROR_INVALID_ARGUMENT);
    test_null_handles();
    CHECK(ngi_device_open(spec && *spec ? spec : "cpu", &dev) == NGI_OK);
    test_model(dev, models);
    test_pipeline(dev, models);
    test_interop(dev, models);
    CHECK(ngi_device_release(dev) == NGI_OK);
    CHECK_FAILS(ngi_device_release(dev), NGI_ERROR_INVALID_HANDLE, "ngi_device_release", "not a live handle");
    ngi_set_error_callback(NULL, NULL);
    printf("test_c_api: %d checks, %d failed\n", checks, failures);
    return failures == 0 ? 0 : 1;
}
