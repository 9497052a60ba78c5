/* ngi C API: the stable contract of the ngi library (libngi_c, C99). The rules in full: bindings/c/README.md.
 *
 * Handles are opaque, typed and reference-counted: every *_new / *_open / *_load / *_read call returns a handle with
 * one reference; *_retain adds one, *_release drops one, and the object is destroyed with its last reference. An
 * object keeps what it was made from alive (a model its device, a buffer its device), so handles may be released in
 * any order. Every call checks each handle it is given against the live handles and their types: a handle used
 * after its last release is refused (NGI_ERROR_INVALID_HANDLE), a handle of another type (an ngi_device cast to
 * ngi_model*) is refused with NGI_ERROR_INVALID_ARGUMENT naming both types; neither is a crash or garbage.
 *
 * Errors: every call returns an ngi_status, one per kind of error (see ngi_status below). On failure,
 * ngi_last_error() returns a message that names the call, the argument or file and, for OpenCL failures, the CL
 * error name; it is thread-local and reset by every call ("" after a success). An error callback
 * (ngi_set_error_callback) sees every failure as it happens. A failing call writes none of its outputs (out
 * handles are set to NULL).
 *
 * Threading: a device may be used by any number of threads at once; every other handle (buffer, model, pipeline,
 * frame, AO network, voxels, Neural GI renderer) is used by one thread at a time, as the object of a call or as an
 * argument; different objects on one device may be used from different threads concurrently.
 *
 * Sizes: every buffer argument comes with its size in bytes; a size (or device buffer) smaller than the call needs
 * is NGI_ERROR_INVALID_ARGUMENT. Layouts and value ranges: docs/CONVENTIONS.md. Frames: bindings/c/README.md and
 * ngi/pipeline.hpp.
 */
#ifndef NGI_H
#define NGI_H

#include <stddef.h>

#if defined(_WIN32)
#  if defined(NGI_C_BUILD)
#    define NGI_API __declspec(dllexport)
#  else
#    define NGI_API __declspec(dllimport)
#  endif
#elif defined(__GNUC__)
#  define NGI_API __attribute__((visibility("default")))
#else
#  define NGI_API
#endif

#define NGI_VERSION_MAJOR 0
#define NGI_VERSION_MINOR 2
#define NGI_VERSION_PATCH 0
/* major * 10000 + minor * 100 + patch, as ngi_version() returns it for the library actually loaded. */
#define NGI_VERSION (NGI_VERSION_MAJOR * 10000 + NGI_VERSION_MINOR * 100 + NGI_VERSION_PATCH)

#ifdef __cplusplus
extern "C" {
#endif

/* The application's OpenCL objects, without including <CL/cl.h>: cl_mem is `struct _cl_mem *` etc. */
struct _cl_context;
struct _cl_device_id;
struct _cl_command_queue;
struct _cl_mem;
struct _cl_event;

/* Every enum is int-sized (its *_MAX_ENUM member is INT_MAX, as in Vulkan) and, in C++, has the fixed underlying
 * type int: any int a caller passes is a value of the type, so an out-of-range one is a refused argument
 * (NGI_ERROR_INVALID_ARGUMENT), never undefined behaviour inside the library. */
#ifdef __cplusplus
#define NGI_ENUM(name) enum name : int
#else
#define NGI_ENUM(name) enum name
#endif

typedef NGI_ENUM(ngi_status) {
    NGI_OK = 0,
    NGI_ERROR_INVALID_ARGUMENT = 1, /* the call's own arguments: a NULL pointer, a value out of range, a size or
                                       device buffer smaller than the call needs, a handle of another type */
    NGI_ERROR_INPUT = 2,            /* bad content: a file, model file, scene spec or frame; a shape the model does
                                       not take; an image descriptor that does not fit; a cl_mem of another context */
    NGI_ERROR_OPENCL = 3,           /* an OpenCL call failed; see ngi_last_cl_error() */
    NGI_ERROR_OUT_OF_MEMORY = 4,    /* host or device memory exhausted (also CL_OUT_OF_RESOURCES, ...) */
    NGI_ERROR_INVALID_HANDLE = 5,   /* a NULL handle, or one whose last reference was released */
    NGI_ERROR_INTERNAL = 6,         /* anything else: a bug in ngi */
    NGI_STATUS_MAX_ENUM = 0x7FFFFFFF
} ngi_status;

typedef struct ngi_device ngi_device;
typedef struct ngi_model ngi_model;
typedef struct ngi_buffer ngi_buffer;
typedef struct ngi_pipeline ngi_pipeline;
typedef struct ngi_display ngi_display;     /* a view's GI at display resolution, with its history */
typedef struct ngi_frame ngi_frame;         /* a frame's features on the host (one camera cluster) */
typedef struct ngi_ao ngi_ao;               /* seed 001's ambient-occlusion network */
typedef struct ngi_voxels ngi_voxels;       /* seed 004: a voxel scene's surface voxels (field, LTF, shading) */
typedef struct ngi_neural_gi ngi_neural_gi; /* seed 002's Neural GI renderer */

/* --- version and errors ------------------------------------------------------------------------------------- */
NGI_API int ngi_version(void);              /* NGI_VERSION of the loaded library */
NGI_API const char* ngi_status_name(ngi_status status); /* "NGI_OK", ... */
NGI_API const char* ngi_last_error(void);   /* "" after a successful call */
NGI_API int ngi_last_cl_error(void);        /* the CL error code of the last NGI_ERROR_OPENCL, else 0 */
/* Called on the failing thread for every failure, before the call returns (NULL: none). Process-wide. */
typedef void (*ngi_error_callback)(void* user, ngi_status status, const char* message);
NGI_API void ngi_set_error_callback(ngi_error_callback callback, void* user);

/* --- devices -------------------------------------------------------------------------------------------------- */
typedef NGI_ENUM(ngi_device_property) {
    NGI_DEVICE_NAME = 0,           /* string */
    NGI_DEVICE_PLATFORM = 1,       /* string: the OpenCL platform's name */
    NGI_DEVICE_VENDOR = 2,         /* string */
    NGI_DEVICE_DRIVER_VERSION = 3, /* string */
    NGI_DEVICE_IS_GPU = 10,        /* integer 0/1 */
    NGI_DEVICE_IS_CPU = 11,        /* integer 0/1 */
    NGI_DEVICE_FP16 = 12,          /* integer 0/1: cl_khr_fp16 */
    NGI_DEVICE_GLOBAL_MEM_BYTES = 13,
    NGI_DEVICE_MAX_ALLOC_BYTES = 14,
    NGI_DEVICE_LOCAL_MEM_BYTES = 15,
    NGI_DEVICE_COMPUTE_UNITS = 16,
    NGI_DEVICE_PLATFORM_INDEX = 17, /* the "P" of a "P:D" spec; -1 for a device from ngi_device_from_opencl that
                                       the platform enumeration does not list */
    NGI_DEVICE_DEVICE_INDEX = 18,
    NGI_DEVICE_PROPERTY_MAX_ENUM = 0x7FFFFFFF
} ngi_device_property;

/* Every OpenCL device of every platform, index 0 .. count - 1 (in "P:D" order). */
NGI_API ngi_status ngi_device_count(int* count);
/* A string property of listed device `index` into buf (size bytes, NUL-terminated); *needed (may be NULL) receives
 * the size the whole string needs, NUL included. A buf too small gets a truncated string and NGI_ERROR_INVALID_ARGUMENT. */
NGI_API ngi_status ngi_device_list_string(int index, ngi_device_property property, char* buf, size_t size,
                                          size_t* needed);
NGI_API ngi_status ngi_device_list_integer(int index, ngi_device_property property, long long* value);

/* spec: "cpu", "gpu", "P:D", a platform name ("pocl", "rusticl"), or NULL/"" for $NGI_DEVICE, else the first GPU,
 * else the first CPU. */
NGI_API ngi_status ngi_device_open(const char* spec, ngi_device** out);
/* A device on the application's own context, device and in-order queue: ngi enqueues all its work on `queue`.
 * The three objects are retained until the device's last reference (and everything made from it) is released. */
NGI_API ngi_status ngi_device_from_opencl(struct _cl_context* context, struct _cl_device_id* device,
                                          struct _cl_command_queue* queue, ngi_device** out);
NGI_API ngi_status ngi_device_string(const ngi_device* device, ngi_device_property property, char* buf, size_t size,
                                     size_t* needed);
NGI_API ngi_status ngi_device_integer(const ngi_device* device, ngi_device_property property, long long* value);
/* The OpenCL objects the device runs on (not retained for the caller); any of the pointers may be NULL. */
NGI_API ngi_status ngi_device_opencl(const ngi_device* device, struct _cl_context** context,
                                     struct _cl_command_queue** queue);
/* Waits for everything enqueued on the device's queue. */
NGI_API ngi_status ngi_device_sync(ngi_device* device);
/* An event that completes when everything enqueued so far has; the caller releases it with clReleaseEvent. */
NGI_API ngi_status ngi_device_marker(ngi_device* device, struct _cl_event** event);
/* Host <-> device transfers since the device was created (device-to-device copies are not counted). */
NGI_API ngi_status ngi_device_host_transfers(const ngi_device* device, long long* uploads, long long* downloads);
NGI_API ngi_status ngi_device_retain(ngi_device* device);
NGI_API ngi_status ngi_device_release(ngi_device* device);  /* NULL is accepted and ignored */

/* --- device buffers ------------------------------------------------------------------------------------------- */
/* A new device buffer of `bytes` (> 0) owned by ngi. */
NGI_API ngi_status ngi_buffer_new(ngi_device* device, size_t bytes, ngi_buffer** out);
/* Borrows bytes [offset, offset + bytes) of the application's `mem` (of the device's context; retained until the
 * buffer's last release, never freed by ngi). A non-zero offset must be a multiple of CL_DEVICE_MEM_BASE_ADDR_ALIGN.
 * Known limit: `mem` must be a cl_mem. ngi hands it to the ICD loader, which dispatches through the object's first
 * pointer before any driver can say CL_INVALID_MEM_OBJECT: a pointer to anything else is undefined behaviour there
 * (a crash in the loader on Debian's ocl-icd), the one argument ngi cannot check (docs/RELIABILITY.md). NULL and
 * handles of another context are refused. */
NGI_API ngi_status ngi_buffer_wrap(ngi_device* device, struct _cl_mem* mem, size_t offset, size_t bytes,
                                   ngi_buffer** out);
NGI_API ngi_status ngi_buffer_size(const ngi_buffer* buffer, size_t* bytes);
/* Blocking copies between host memory and bytes [offset, offset + bytes) of the buffer. */
NGI_API ngi_status ngi_buffer_write(ngi_buffer* buffer, size_t offset, const void* src, size_t bytes);
NGI_API ngi_status ngi_buffer_read(const ngi_buffer* buffer, size_t offset, void* dst, size_t bytes);
NGI_API ngi_status ngi_buffer_retain(ngi_buffer* buffer);
NGI_API ngi_status ngi_buffer_release(ngi_buffer* buffer);

/* --- models --------------------------------------------------------------------------------------------------- */
typedef NGI_ENUM(ngi_bn_mode) {
    NGI_BN_FROM_FILE = 0,  /* what the model file says */
    NGI_BN_RUNNING = 1,    /* running statistics (eval mode) */
    NGI_BN_PER_IMAGE = 2,  /* statistics of each image (train mode, batch 1) */
    NGI_BN_MODE_MAX_ENUM = 0x7FFFFFFF
} ngi_bn_mode;
typedef NGI_ENUM(ngi_dropout) {
    NGI_DROPOUT_FROM_FILE = 0,
    NGI_DROPOUT_OFF = 1,
    NGI_DROPOUT_SEEDED = 2, /* the seeded, reproducible mask of docs/MODEL_FORMAT.md */
    NGI_DROPOUT_MAX_ENUM = 0x7FFFFFFF
} ngi_dropout;

/* path: a model file, or a shipped model's name ("ssgi_surround", "gi_surround_n64_ngf16": the names of the zoo,
 * searched in $NGI_MODEL_PATH, then the installed models; an unknown name is NGI_ERROR_INPUT listing the known ones). */
NGI_API ngi_status ngi_model_load(ngi_device* device, const char* path, ngi_model** out);
/* The file a model name (or path) stands for, as ngi_model_load resolves it, into buf (ngi_device_list_string's
 * rules for buf, size and *needed). */
NGI_API ngi_status ngi_model_resolve(const char* name_or_path, char* buf, size_t size, size_t* needed);
/* Cold start (ngi/warmup.hpp): runs `model` (a frame rung: an image generator whose input the surround pipeline
 * makes, or an ssgi rung: ngi_model_traits NGI_INPUT_IMAGE, or no network) twice on a synthetic frame at face size n on `device`, and through a display view of display_size^2 pixels when display_size
 * > 0, so that every OpenCL program and work-group size its frames need is built into the program caches (ngi's
 * folder, ngi_program_cache_dir, and $POCL_CACHE_DIR on PoCL): later processes start fast. report may be NULL.
 * NGI_ERROR_INPUT for another model or a cache folder that cannot be written (checked before any work). */
typedef struct ngi_warmup_report {
    int programs_built;      /* compiled from source by this call (and written to the cache) */
    int programs_from_cache; /* loaded from the cache by this call */
    double first_frame_ms;   /* the warm-up frame, builds included */
    double second_frame_ms;  /* the same frame again: what a frame costs once warm */
} ngi_warmup_report;
NGI_API ngi_status ngi_device_warmup(ngi_device* device, ngi_model* model, int n, int display_size,
                                     ngi_warmup_report* report);
/* ngi's program cache folder ($NGI_CACHE_DIR, else $XDG_CACHE_HOME/ngi, else ~/.cache/ngi) into buf
 * (ngi_device_list_string's rules for buf, size and *needed). */
NGI_API ngi_status ngi_program_cache_dir(char* buf, size_t size, size_t* needed);
NGI_API ngi_status ngi_model_load_with_options(ngi_device* device, const char* path, ngi_bn_mode bn_mode,
                                               ngi_dropout dropout, ngi_model** out);
/* Any pointer may be NULL. */
NGI_API ngi_status ngi_model_channels(const ngi_model* model, int* input_nc, int* output_nc, int* num_downs);
/* What a generator's decoded output is (the model file's "output_mode", docs/MODEL_FORMAT.md). */
typedef NGI_ENUM(ngi_output_mode) {
    NGI_OUTPUT_LIGHTMAP = 0, /* the front view's whole lightmap, direct + indirect (the thesis's; the default) */
    NGI_OUTPUT_INDIRECT = 1, /* indirect light only: the pipeline adds the frame's front direct light (planes 7-9
                                of face 0, NaN and negative -> 0, +Inf -> FLT_MAX, the sum saturating at FLT_MAX)
                                to make the lightmap; ngi_pipeline_run / _enqueue do it with no extra argument */
    NGI_OUTPUT_SSGI_RESIDUAL = 2, /* a correction of the SSGI rung named in the file: the pipeline runs that gather,
                                     feeds it to the network and adds the output to it before decoding (issue 45;
                                     docs/CONVENTIONS.md section 8); only ngi_pipeline_run / _enqueue can decode it */
    NGI_OUTPUT_MODE_MAX_ENUM = 0x7FFFFFFF
} ngi_output_mode;
/* The model's output mode into *mode (not NULL). */
NGI_API ngi_status ngi_model_output_mode(const ngi_model* model, ngi_output_mode* mode);
/* The model file's family. */
typedef NGI_ENUM(ngi_family) {
    NGI_FAMILY_PIX2PIX_UNET = 0,     /* image generators (surround, single view, the ladder) */
    NGI_FAMILY_DEEPILLUMINATION = 1,
    NGI_FAMILY_MLP = 2,              /* per-item networks (the AO MLPs: see also ngi_ao_*) */
    NGI_FAMILY_VOXEL_SH = 3,         /* seed 004: [V, 10] voxel attributes -> [V, 27] SH (see ngi_voxels_predict_sh) */
    NGI_FAMILY_NEURAL_GI = 4,        /* seed 002: [1, 18, H, W] -> [1, 3, H, W] (see ngi_neural_gi_run) */
    NGI_FAMILY_GRAPH = 5,            /* a converted graph (python3 -m ngi.convert; docs/MODEL_FORMAT.md "graph") */
    NGI_FAMILY_SSGI = 6,             /* a screen-space GI rung: no network, runs on frames (ngi_pipeline_*) */
    NGI_FAMILY_OTHER = 7,            /* a family this header does not name (added to the library after it, e.g.
                                        pixel_cnn): a new family reaches the C ABI as this first */
    NGI_FAMILY_MAX_ENUM = 0x7FFFFFFF
} ngi_family;
NGI_API ngi_status ngi_model_family(const ngi_model* model, ngi_family* family);
/* What a model takes (the family's traits, docs/MODEL_FORMAT.md "family"): what to choose by instead of the family,
 * which also answers for a family this header does not name (NGI_FAMILY_OTHER). */
typedef NGI_ENUM(ngi_model_input) {
    NGI_INPUT_IMAGE = 0, /* images: input_nc x height x width (families pix2pix_unet, deepillumination, neural_gi,
                            graph with layout "nchw", pixel_cnn; ssgi's frames) */
    NGI_INPUT_ITEMS = 1, /* a per-item network: ngi_model_run_items, or height x width items stored planar (mlp,
                            voxel_sh, graph with layout "nc") */
    NGI_MODEL_INPUT_MAX_ENUM = 0x7FFFFFFF
} ngi_model_input;
/* Any pointer may be NULL. *has_network: 0 for a rung with no network and no tensors (ssgi): ngi_model_run and
 * _enqueue refuse it, ngi_pipeline_* run it. *output_keeps_size: 0 when the network decides its output's size (it
 * may resample: family graph); ngi_model_run then refuses an output that is not output_nc x height x width. */
NGI_API ngi_status ngi_model_traits(const ngi_model* model, ngi_model_input* input, int* has_network,
                                    int* output_keeps_size);
/* input: input_nc x height x width floats (CHW, batch 1, input_bytes >= that many bytes); output: output_nc x height
 * x width floats. height and width must be positive multiples of 2^num_downs. A per-item network (NGI_INPUT_ITEMS)
 * takes height x width items stored planar ([input_nc][items] -> [output_nc][items], as ngi_model_enqueue; voxel_sh:
 * the voxels of one scene). NGI_ERROR_INPUT when the network's output has another size (output_keeps_size 0).
 * Blocking. */
NGI_API ngi_status ngi_model_run(ngi_model* model, const float* input, size_t input_bytes, int height, int width,
                                 float* output, size_t output_bytes);
/* A per-item network (NGI_INPUT_ITEMS): `count` items stored by item, [count][input_nc] -> [count][output_nc]
 * (row-major, as Model::run takes them; voxel_sh: the count voxels of one scene, e.g. ngi_voxels_attributes);
 * NGI_ERROR_INPUT for an image model. Blocking. */
NGI_API ngi_status ngi_model_run_items(ngi_model* model, const float* input, size_t input_bytes, int count,
                                       float* output, size_t output_bytes);
/* The same as ngi_model_run on device buffers, asynchronous (ngi_device_sync waits): no host transfer. */
NGI_API ngi_status ngi_model_enqueue(ngi_model* model, ngi_buffer* input, ngi_buffer* output, int height, int width);
/* Input values the last run/enqueue replaced before the first layer (NaN -> 0; +-Inf and values far outside the
 * model's input range -> its nearer end; docs/CONVENTIONS.md section 7); 0 before any run. May block. */
NGI_API ngi_status ngi_model_sanitized_inputs(ngi_model* model, int* count);
NGI_API ngi_status ngi_model_retain(ngi_model* model);
NGI_API ngi_status ngi_model_release(ngi_model* model);

/* --- the surround pipeline: frame planes -> lightmap / final image / display image ----------------------------
 * Frame planes: float32 [face][16][N][N], faces in the order front, back, left, right, up, down (a single-view model
 * reads the front face only and accepts 1 face), 16 planes per face: albedo RGB 0-2, normal XYZ 3-5, depth 6,
 * direct RGB 7-9, emission RGB 10-12, env RGB 13-15. Outputs: N x N x 3 planar float32 each. */
typedef NGI_ENUM(ngi_global_view_mode) {
    NGI_GLOBAL_VIEW_THESIS = 0,
    NGI_GLOBAL_VIEW_EQUIRECT = 1,
    NGI_GLOBAL_VIEW_MODE_MAX_ENUM = 0x7FFFFFFF
} ngi_global_view_mode;
typedef NGI_ENUM(ngi_lumination_transfer) {
    NGI_TRANSFER_REINHARD = 0,
    NGI_TRANSFER_CLAMP = 1,
    NGI_TRANSFER_MAX_ENUM = 0x7FFFFFFF
} ngi_lumination_transfer;
typedef NGI_ENUM(ngi_tone_curve) {
    NGI_TONE_ACES = 0,
    NGI_TONE_REINHARD = 1,
    NGI_TONE_CLAMP = 2,
    NGI_TONE_CURVE_MAX_ENUM = 0x7FFFFFFF
} ngi_tone_curve;
typedef NGI_ENUM(ngi_frame_flags) {
    NGI_FRAME_EMISSION = 1, /* the emission planes hold data */
    NGI_FRAME_ENV = 2,      /* the env planes hold data */
    NGI_FRAME_FLAGS_MAX_ENUM = 0x7FFFFFFF
} ngi_frame_flags;

/* n: face size, even, 2..2048. */
NGI_API ngi_status ngi_pipeline_new(ngi_device* device, int n, ngi_global_view_mode mode,
                                    ngi_lumination_transfer transfer, ngi_pipeline** out);
/* Bytes of the frame planes for `faces` (1 or 6) faces of this pipeline: faces * 16 * N * N * 4. */
NGI_API ngi_status ngi_pipeline_frame_bytes(const ngi_pipeline* pipeline, int faces, size_t* bytes);
/* The front camera of the next frames (world space; default look (0, 0, -1), up (0, 1, 0)). */
NGI_API ngi_status ngi_pipeline_set_camera(ngi_pipeline* pipeline, const float look[3], const float up[3]);
/* The display transform of the next frames (default: 0 EV, ACES, sRGB on). exposure_ev in [-64, 64]. */
NGI_API ngi_status ngi_pipeline_set_tonemap(ngi_pipeline* pipeline, float exposure_ev, ngi_tone_curve curve, int srgb);
/* Device in, device out, asynchronous, no host transfer. flags: ngi_frame_flags. Any output may be NULL (not made).
 * The lightmap is the model's decoded output, plus the front direct light for an NGI_OUTPUT_INDIRECT model (so the
 * planes' direct planes are read in either mode: the network input needs them too). */
NGI_API ngi_status ngi_pipeline_enqueue(ngi_pipeline* pipeline, ngi_model* model, ngi_buffer* planes, int faces,
                                        unsigned flags, ngi_buffer* lightmap, ngi_buffer* final_image,
                                        ngi_buffer* display);
/* Host in, host out, blocking: one upload and one download. planes_bytes must be at least
 * ngi_pipeline_frame_bytes(faces). Each output pointer may be NULL (not made); its size in bytes must be at least
 * N * N * 3 * 4. */
NGI_API ngi_status ngi_pipeline_run(ngi_pipeline* pipeline, ngi_model* model, const float* planes, size_t planes_bytes,
                                    int faces, unsigned flags, float* lightmap, size_t lightmap_bytes,
                                    float* final_image, size_t final_bytes, float* display, size_t display_bytes);
/* --- frames as an engine holds them: one image descriptor per face and feature --------------------------------
 * Each image is N x N, stored in host memory or a device buffer with its own format, channel count, byte offset and
 * strides (ngi/image_desc.hpp has the rules); ngi gathers it on the device (one kernel per image; host images are
 * uploaded in one transfer first). Example: a G-buffer of RGBA16F render targets (depth R32F), one per feature, each
 * holding the six faces in GL rows [face N, face N + N), read back with glReadPixels (rows bottom-up, `pitch[k]`
 * bytes apart) into mapped pixel buffers `target[k]`:
 *
 *     ngi_image_desc images[36] = {0};                  // zeroed = absent; a scale of 0 is taken as 1
 *     for (int face = 0; face < 6; ++face)
 *         for (int k = 0; k < NGI_FEATURE_COUNT; ++k) {
 *             ngi_image_desc* d = &images[face * NGI_FEATURE_COUNT + k];
 *             int depth = k == NGI_FEATURE_DEPTH;
 *             d->host = target[k];
 *             d->host_bytes = target_bytes[k];
 *             d->format = depth ? NGI_FORMAT_F32 : NGI_FORMAT_F16;
 *             d->channels = depth ? 1 : 4;               // RGBA: the first 3 are read
 *             d->width = d->height = n;
 *             d->row_stride = pitch[k];
 *             d->offset = (size_t)face * n * pitch[k];   // the face's bottom row (GL order)
 *             d->bottom_up = 1;
 *         }
 *     status = ngi_pipeline_run_images(pipeline, model, images, lightmap, lightmap_bytes, NULL, 0, NULL, 0);
 *
 * samples/gl/gbuffer_pass.cpp does the same in C++; tests/c/test_c_api.c checks descriptors against frame planes. */
typedef NGI_ENUM(ngi_pixel_format) {
    NGI_FORMAT_F32 = 0,       /* float32 */
    NGI_FORMAT_F16 = 1,       /* IEEE half (no cl_khr_fp16 needed) */
    NGI_FORMAT_U8_UNORM = 2,  /* uint8 / 255 */
    NGI_FORMAT_U8_SRGB = 3,   /* uint8 / 255 through the sRGB EOTF (e.g. albedo in an RGBA8_SRGB target) */
    NGI_FORMAT_U16_UNORM = 4, /* uint16 / 65535 (RGBA16, D16) */
    NGI_FORMAT_S16_SNORM = 5, /* int16 / 32767, -32768 read as -1 (e.g. RG16_SNORM octahedral normals) */
    NGI_FORMAT_R11G11B10F = 6,    /* packed, one 32-bit word per pixel: R bits 0-10, G 11-21, B 22-31 (unsigned small
                                     floats: GL_R11F_G11F_B10F, DXGI R11G11B10_FLOAT); channels 3, channel_stride 0 */
    NGI_FORMAT_RGB10A2_UNORM = 7, /* packed, one 32-bit word per pixel: R bits 0-9, G 10-19, B 20-29, A 30-31 (unorm:
                                     GL_RGB10_A2, DXGI R10G10B10A2_UNORM); channels 4, channel_stride 0 */
    NGI_PIXEL_FORMAT_MAX_ENUM = 0x7FFFFFFF
} ngi_pixel_format;
typedef NGI_ENUM(ngi_normal_encoding) {
    NGI_NORMAL_XYZ = 0,         /* three channels x, y, z */
    NGI_NORMAL_OCTAHEDRAL = 1,  /* two channels (x, y) in [-1, 1] after scale and bias: the octahedral map */
    NGI_NORMAL_ENCODING_MAX_ENUM = 0x7FFFFFFF
} ngi_normal_encoding;
typedef NGI_ENUM(ngi_depth_encoding) {
    NGI_DEPTH_LINEAR = 0,       /* planar depth in metres (ngi's own) */
    NGI_DEPTH_PERSPECTIVE = 1,  /* window depth in [0, 1] of a perspective projection (near_m, far_m, reversed_z): a
                                   depth attachment as rendered; the cleared far value means "no surface" */
    NGI_DEPTH_ENCODING_MAX_ENUM = 0x7FFFFFFF
} ngi_depth_encoding;
typedef NGI_ENUM(ngi_feature) {
    NGI_FEATURE_ALBEDO = 0, NGI_FEATURE_NORMAL = 1, NGI_FEATURE_DEPTH = 2, NGI_FEATURE_DIRECT = 3,
    NGI_FEATURE_EMISSION = 4, NGI_FEATURE_ENV = 5, NGI_FEATURE_COUNT = 6,
    NGI_FEATURE_MAX_ENUM = 0x7FFFFFFF
} ngi_feature;
typedef struct ngi_image_desc {
    const void* host;        /* host memory, or NULL */
    size_t host_bytes;       /* bytes readable from host */
    ngi_buffer* buffer;      /* or a device buffer (exactly one of host / buffer; both NULL = the image is absent) */
    ngi_pixel_format format;
    int channels;            /* stored per pixel, 1..4; albedo, normal, direct, emission, env read 3, depth 1 */
    int width, height;       /* the pipeline's N x N */
    size_t offset;           /* bytes to channel 0 of the first stored row's first pixel */
    size_t pixel_stride;     /* bytes between pixels of a row; 0 = channels x value size */
    size_t row_stride;       /* bytes between stored rows; 0 = width x pixel_stride */
    size_t channel_stride;   /* bytes between a pixel's channels; 0 = the value size (interleaved) */
    int bottom_up;           /* 1: the first stored row is the image's bottom (OpenGL) */
    float scale, bias;       /* value = decoded x scale + bias; a scale of 0 is taken as 1 (a zeroed descriptor reads
                                values as stored) */
} ngi_image_desc;
/* How an image encodes its normals or depth, beside its descriptor (a separate struct: ngi_image_desc's layout is
 * part of the ABI). Zeroed = ngi's own: xyz world-space normals, linear depth in metres. */
typedef struct ngi_image_encoding {
    ngi_normal_encoding normal_encoding;  /* normals only */
    float normal_to_world[9];  /* normals only: row-major 3 x 3 taking a stored (e.g. view-space) normal to world
                                  space; all zero = the identity */
    ngi_depth_encoding depth_encoding;    /* depth only; unorm / snorm / packed depth needs NGI_DEPTH_PERSPECTIVE */
    float near_m, far_m;     /* NGI_DEPTH_PERSPECTIVE: 0 < near_m < far_m in metres, far_m = INFINITY for an
                                infinite far plane */
    int reversed_z;          /* NGI_DEPTH_PERSPECTIVE: 1 = reversed Z (window depth 1 at near, 0 at far) */
} ngi_image_encoding;
/* images: 36 descriptors, images[face * 6 + feature] (faces front, back, left, right, up, down; ngi_feature order).
 * A surround model reads all six faces, a single-view model the front face. Emission and env are optional: given for
 * every face read, or for none. The camera is ngi_pipeline_set_camera's. A descriptor that does not fit is an
 * NGI_ERROR_INPUT naming the face and feature, and nothing is enqueued. */
NGI_API ngi_status ngi_pipeline_enqueue_images(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                               ngi_buffer* lightmap, ngi_buffer* final_image, ngi_buffer* display);
NGI_API ngi_status ngi_pipeline_run_images(ngi_pipeline* pipeline, ngi_model* model, const ngi_image_desc* images,
                                           float* lightmap, size_t lightmap_bytes, float* final_image,
                                           size_t final_bytes, float* display, size_t display_bytes);
/* The same with each image's encoding: encodings[i] goes with images[i] (36 entries, or NULL for ngi's own), e.g. a
 * GL depth attachment as rendered (NGI_DEPTH_PERSPECTIVE) and octahedral view-space normals. */
NGI_API ngi_status ngi_pipeline_enqueue_images_encoded(ngi_pipeline* pipeline, ngi_model* model,
                                                       const ngi_image_desc* images,
                                                       const ngi_image_encoding* encodings, ngi_buffer* lightmap,
                                                       ngi_buffer* final_image, ngi_buffer* display);
NGI_API ngi_status ngi_pipeline_run_images_encoded(ngi_pipeline* pipeline, ngi_model* model,
                                                   const ngi_image_desc* images, const ngi_image_encoding* encodings,
                                                   float* lightmap, size_t lightmap_bytes, float* final_image,
                                                   size_t final_bytes, float* display, size_t display_bytes);
NGI_API ngi_status ngi_pipeline_retain(ngi_pipeline* pipeline);
NGI_API ngi_status ngi_pipeline_release(ngi_pipeline* pipeline);

/* --- display resolution: the pipeline's N x N lightmap at the application's S x S, stable over frames ----------
 * (ngi/display.hpp, docs/CONVENTIONS.md section 20). The display's camera is the pipeline's front camera (90 degrees,
 * square, same centre). One handle per view: it keeps the previous frame's result for the temporal pass. */
typedef NGI_ENUM(ngi_display_upsampler) {
    NGI_DISPLAY_JBU = 0,      /* joint bilateral: guided by the display's normals and positions */
    NGI_DISPLAY_BILINEAR = 1, /* for comparison */
    NGI_DISPLAY_UPSAMPLER_MAX_ENUM = 0x7FFFFFFF
} ngi_display_upsampler;
/* size: S, 2..16384; temporal: non-zero accumulates over frames (defaults of DisplaySettings otherwise). */
NGI_API ngi_status ngi_display_new(ngi_device* device, int size, ngi_display_upsampler upsampler, int temporal,
                                   ngi_display** out);
/* The next frame stands alone (after a cut, a teleport, a scene change). */
NGI_API ngi_status ngi_display_reset(ngi_display* display);
/* Device in, device out, asynchronous. low_planes: the frame planes the pipeline ran (face 0 read, n x n);
 * low_lightmap: its lightmap (ngi_pipeline_enqueue's, n * n * 3 floats); display_planes: one face of frame planes at
 * S x S (albedo, normal, depth, direct; emission and env as `flags` say); position, look, up: the camera (world
 * space). Each output, when not NULL, receives S * S * 3 planar floats; the tone map is ngi_pipeline's default. */
NGI_API ngi_status ngi_display_enqueue(ngi_display* display, int n, ngi_buffer* low_planes, ngi_buffer* low_lightmap,
                                       ngi_buffer* display_planes, unsigned flags, const float position[3],
                                       const float look[3], const float up[3], ngi_buffer* lightmap,
                                       ngi_buffer* final_image, ngi_buffer* display_image);
NGI_API ngi_status ngi_display_retain(ngi_display* display);
NGI_API ngi_status ngi_display_release(ngi_display* display);
/* --- files ---------------------------------------------------------------------------------------------------- */
/* A frame folder (docs/CONVENTIONS.md: <face>_<feature>.exr, camera.json) into frame planes of `faces` (1 or 6) faces.
 * Call with planes = NULL to learn *n and *bytes; then with a buffer of at least *bytes bytes. *flags receives the
 * ngi_frame_flags present; look and up (each 3 floats, may be NULL) the front camera. */
NGI_API ngi_status ngi_read_frame_planes(const char* folder, int faces, float* planes, size_t bytes, int* n,
                                         size_t* needed, unsigned* flags, float look[3], float up[3]);
/* Writes a planar float image (channels x height x width) to `path`: .exr (float), .png (8-bit, values clamped to
 * [0, 1], linear), .npy (float32), by extension. The file appears whole or not at all. */
NGI_API ngi_status ngi_write_image(const char* path, const float* data, size_t bytes, int width, int height,
                                   int channels);
/* --- frames as objects: what the Neural GI renderer and voxel shading read ---------------------------------------
 * A frame holds every feature of its faces on the host, the front camera (look, up) and, optionally, the camera
 * cluster's position (world metres) and a rectangular area light (ngi/area_light.hpp). */
NGI_API ngi_status ngi_frame_read(const char* folder, ngi_frame** out);
/* From frame planes (the layout above; faces 1 = the front face only, or 6; flags: ngi_frame_flags) of face size
 * n (2..2048) and the front camera. planes_bytes >= faces * 16 * n * n * 4. */
NGI_API ngi_status ngi_frame_from_planes(int n, const float* planes, size_t planes_bytes, int faces, unsigned flags,
                                         const float look[3], const float up[3], ngi_frame** out);
/* The cluster centre in world metres (finite). */
NGI_API ngi_status ngi_frame_set_position(ngi_frame* frame, const float position[3]);
/* The area light the frame was lit with: the rectangle centre + s half_u + t half_v (s, t in [-1, 1]), orthogonal
 * half edges, radiance >= 0 (all 0 = no light). */
NGI_API ngi_status ngi_frame_set_area_light(ngi_frame* frame, const float centre[3], const float half_u[3],
                                            const float half_v[3], const float radiance[3]);
/* Any pointer may be NULL. faces: 6, or 1 when only the front face is present; flags: ngi_frame_flags present;
 * has_position / has_area_light: 0 or 1. */
NGI_API ngi_status ngi_frame_info(const ngi_frame* frame, int* n, int* faces, unsigned* flags, int* has_position,
                                  int* has_area_light);
/* The frame's planes of `faces` faces (1 or 6) into planes (bytes >= faces * 16 * n * n * 4); absent optional
 * features are 0. */
NGI_API ngi_status ngi_frame_planes(const ngi_frame* frame, int faces, float* planes, size_t bytes);
NGI_API ngi_status ngi_frame_retain(ngi_frame* frame);
NGI_API ngi_status ngi_frame_release(ngi_frame* frame);

/* --- ambient occlusion (seed 001, ngi/ao.hpp): an "mlp" model file with "ao" metadata --------------------------- */
NGI_API ngi_status ngi_ao_load(ngi_device* device, const char* path, ngi_ao** out);
/* Any pointer may be NULL. trained_radius_px: the ring radius of the training images, trained_size their height;
 * face_normals: 1 if the network was trained on voxel face normals, 0 for smooth normals (the default). */
NGI_API ngi_status ngi_ao_info(const ngi_ao* ao, float* trained_radius_px, int* trained_size, int* face_normals);
/* normals: 3 x height x width floats (object-space unit normals, zero = background), normals_bytes >= that;
 * result: height x width accessibility in [0, 1] (1 = unoccluded, 1 on the background). radius_px: the ring
 * radius in pixels (0 = the seed's inference), or negative for the trained radius scaled to `height`. Blocking. */
NGI_API ngi_status ngi_ao_run(ngi_ao* ao, const float* normals, size_t normals_bytes, int height, int width,
                              float radius_px, float* result, size_t result_bytes);
/* The same on device buffers, asynchronous. */
NGI_API ngi_status ngi_ao_enqueue(ngi_ao* ao, ngi_buffer* normals, ngi_buffer* result, int height, int width,
                                  float radius_px);
NGI_API ngi_status ngi_ao_retain(ngi_ao* ao);
NGI_API ngi_status ngi_ao_release(ngi_ao* ao);

/* --- the voxel field and the light-transition function (seed 004, ngi/voxel_field.hpp, ngi/voxel_gi.hpp) --------
 * A voxels object is one scene's surface voxels on a device, lit at one time of day: V voxels in increasing dense
 * id. Per-voxel arrays are row-major: attributes [V][10], SH [V][3][9], lighting [V][3] (irradiance / pi). */
typedef NGI_ENUM(ngi_face) {
    NGI_FACE_FRONT = 0, NGI_FACE_BACK = 1, NGI_FACE_LEFT = 2, NGI_FACE_RIGHT = 3, NGI_FACE_UP = 4, NGI_FACE_DOWN = 5,
    NGI_FACE_MAX_ENUM = 0x7FFFFFFF
} ngi_face;
typedef NGI_ENUM(ngi_ltf_variant) {
    NGI_LTF_PHYSICAL = 0,   /* radiosity between voxels (both cosines, area / (pi r^2)), optionally with visibility */
    NGI_LTF_AS_WRITTEN = 1, /* seed 004's Eq. 23-30 (one cosine, normalized 1 / r^2, no visibility) */
    NGI_LTF_VARIANT_MAX_ENUM = 0x7FFFFFFF
} ngi_ltf_variant;
typedef NGI_ENUM(ngi_voxel_field_kind) {
    NGI_FIELD_SH = 0,       /* [V][3][9] SH coefficients of incident radiance */
    NGI_FIELD_LIGHTING = 1, /* [V][3] lighting at the voxel, used as is */
    NGI_VOXEL_FIELD_KIND_MAX_ENUM = 0x7FFFFFFF
} ngi_voxel_field_kind;
/* The ground truth's settings (ngi::VoxelFieldSettings); NULL = NGI_VOXEL_FIELD_DEFAULTS. */
typedef struct ngi_voxel_field_settings {
    int directions;    /* SH projection directions per voxel: a perfect square, 1..2^20 */
    int sun_rays;      /* rays over the sun's disc per voxel, 1..2^20 */
    int point_samples; /* lighting samples at the probe point and per exposed face, 1..2^20 */
    int max_bounces;   /* bounces, 0..64 (0: direct light only) */
    int rr_start;      /* bounces before Russian roulette, >= 0 */
    unsigned seed;
} ngi_voxel_field_settings;
#define NGI_VOXEL_FIELD_DEFAULTS {1024, 64, 256, 8, 2, 0u}

/* scene: a scene spec ("cornell:seed=5", a .vox or mesh path; docs/RENDERER.md); hours: time of day 0..24, or
 * negative for the scene's default time. */
NGI_API ngi_status ngi_voxels_new(ngi_device* device, const char* scene, float hours, ngi_voxels** out);
/* Any pointer may be NULL. grid: the scene's blocks per axis (X, Y, Z). */
NGI_API ngi_status ngi_voxels_info(const ngi_voxels* voxels, int* count, int grid[3], float* hours);
/* attributes [V][10] (centre xyz, albedo rgb, emission rgb, dense id): a voxel_sh model's input. */
NGI_API ngi_status ngi_voxels_attributes(const ngi_voxels* voxels, float* attributes, size_t bytes);
/* The path-traced ground truth: sh [V][27], direct [V][3] and full lighting [V][3] at the probe points. Any output
 * may be NULL (not all three). Blocking; costs about V * (directions + sun_rays + 8 point_samples) rays. */
NGI_API ngi_status ngi_voxels_field(ngi_voxels* voxels, const ngi_voxel_field_settings* settings, float* sh,
                                    size_t sh_bytes, float* direct, size_t direct_bytes, float* lighting,
                                    size_t lighting_bytes);
/* A voxel_sh model's SH field [V][27] for these voxels (NGI_ERROR_INPUT when the scene's grid is not the one the
 * model was trained on). */
NGI_API ngi_status ngi_voxels_predict_sh(ngi_voxels* voxels, ngi_model* model, float* sh, size_t sh_bytes);
/* The LTF: lighting [V][3] after `bounces` (0..64) bounces from direct [V][3]. visibility = 1 (NGI_LTF_PHYSICAL
 * only) traces the voxel-to-voxel visibility first (V <= 32768; V^2 / 2 segments); 0 = every pair visible. */
NGI_API ngi_status ngi_voxels_ltf(ngi_voxels* voxels, const float* direct, size_t direct_bytes, int bounces,
                                  ngi_ltf_variant variant, int visibility, float* lighting, size_t lighting_bytes);
/* A frame of this scene (all six faces' features, no reference) seen from `position` (the camera cluster's centre,
 * recorded in the frame) with the front camera look / up: n x n per face (2..2048), feature_spp >= 1. */
NGI_API ngi_status ngi_voxels_render_frame(ngi_voxels* voxels, const float position[3], const float look[3],
                                           const float up[3], int n, int feature_spp, unsigned seed, ngi_frame** out);
/* Probe shading: the lighting (3 x n x n, irradiance / pi) of `face` of a frame of this scene from a per-voxel field
 * (kind NGI_FIELD_SH: [V][27]; NGI_FIELD_LIGHTING: [V][3]). camera_position NULL: the frame's position. */
NGI_API ngi_status ngi_voxels_shade(ngi_voxels* voxels, const ngi_frame* frame, const float camera_position[3],
                                    ngi_face face, const float* field, size_t field_bytes, ngi_voxel_field_kind kind,
                                    float* lighting, size_t lighting_bytes);
NGI_API ngi_status ngi_voxels_retain(ngi_voxels* voxels);
NGI_API ngi_status ngi_voxels_release(ngi_voxels* voxels);

/* --- Neural GI (seed 002, ngi/neural_gi.hpp) ---------------------------------------------------------------------- */
NGI_API ngi_status ngi_neural_gi_new(ngi_device* device, ngi_neural_gi** out);
/* Runs a neural_gi model (with a scene box) on a frame's front face: indirect and lighting (= direct + indirect),
 * 3 x n x n each, either may be NULL (not both). The frame needs its position and area light. upsample: 1, or K > 1
 * to run the network at n / K and upsample (n / K a multiple of 2^num_downs). sanitized_inputs (may be NULL): values
 * replaced on the way in: NaN/Inf in the front face's albedo, normal, depth and direct light, plus input values the
 * model's guard replaced (0 for a sound frame). Blocking. */
NGI_API ngi_status ngi_neural_gi_run(ngi_neural_gi* renderer, ngi_model* model, const ngi_frame* frame, int upsample,
                                     float* indirect, size_t indirect_bytes, float* lighting, size_t lighting_bytes,
                                     int* sanitized_inputs);
NGI_API ngi_status ngi_neural_gi_retain(ngi_neural_gi* renderer);
NGI_API ngi_status ngi_neural_gi_release(ngi_neural_gi* renderer);

#ifdef __cplusplus
}
#endif

#endif /* NGI_H */
