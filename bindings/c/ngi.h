/* ngi C API: open a device, load a generator, run it. Every call returns an ngi_status; on failure
 * ngi_last_error() returns the message (thread-local, valid until the next failing call on that thread),
 * which names the operation, the file or tensor and, for OpenCL failures, the CL error name. */
#ifndef NGI_H
#define NGI_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum ngi_status {
    NGI_OK = 0,
    NGI_ERROR_INVALID_ARGUMENT = 1, /* a NULL pointer or impossible size passed to the API */
    NGI_ERROR_INPUT = 2,            /* bad user input: file, tensor shape, device spec */
    NGI_ERROR_OPENCL = 3,           /* an OpenCL call failed; see ngi_last_cl_error() */
    NGI_ERROR_INTERNAL = 4          /* anything else (out of memory, ...) */
} ngi_status;

typedef struct ngi_device ngi_device;
typedef struct ngi_model ngi_model;

const char* ngi_last_error(void);
int ngi_last_cl_error(void); /* the CL error code of the last NGI_ERROR_OPENCL, else 0 */

/* spec: "cpu", "gpu", "P:D" or NULL/"" for $NGI_DEVICE, else the first GPU, else the first CPU. */
ngi_status ngi_device_open(const char* spec, ngi_device** out);
const char* ngi_device_name(const ngi_device* device);
void ngi_device_release(ngi_device* device);

ngi_status ngi_model_load(ngi_device* device, const char* path, ngi_model** out);
ngi_status ngi_model_channels(const ngi_model* model, int* input_nc, int* output_nc, int* num_downs);
/* input: input_nc x height x width floats (CHW, batch 1); output: output_nc x height x width floats.
 * height and width must be multiples of 2^num_downs. */
ngi_status ngi_model_run(ngi_model* model, const float* input, int height, int width, float* output);
/* Input values the last successful ngi_model_run replaced before the first layer (NaN -> 0; +-Inf and values far
 * outside the model's input range -> its nearer end; docs/CONVENTIONS.md section 7); 0 before any run. */
ngi_status ngi_model_sanitized_inputs(const ngi_model* model, int* count);
void ngi_model_release(ngi_model* model);

#ifdef __cplusplus
}
#endif

#endif /* NGI_H */
