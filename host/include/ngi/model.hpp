// A trained generator loaded from an ngi model file (.safetensors + architecture metadata) and run on a Device.
// A Model is used by one thread at a time; several Models may run on one Device from different threads.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/tensor.hpp"

namespace ngi {

namespace detail { struct ModelAccess; }

// What Model::run takes (ModelConfig::input).
enum class ModelInput {
    image,  // [1, input_nc, H, W] NCHW images (the generators, neural_gi, pixel_cnn, graph layout "nchw")
    items,  // a per-item network: [N, input_nc] item lists (mlp, voxel_sh, graph layout "nc"); Model::enqueue takes
            // height x width items stored planar. mlp and graph also take [1, input_nc, H, W] (one item per pixel)
};

// The architecture config stored as JSON in the file's __metadata__["ngi"] (docs/MODEL_FORMAT.md).
struct ModelConfig {
    std::string family;              // "pix2pix_unet" | "deepillumination" | "mlp" | "voxel_sh" | "neural_gi" | "graph" | "ssgi" | ...
    // The family's traits: what the library, the bindings and the CLI choose by, instead of comparing `family` with
    // a name (docs/ARCHITECTURE.md "Models"). Every family's parser sets all three for the file it reads (the
    // registry refuses a config whose parser forgot one); the defaults are those of a plain image network, for
    // configs built by hand.
    ModelInput input = ModelInput::image;  // graph: follows its layout ("nc": items)
    // false: no network and no tensors (family ssgi): Model::run and Model::enqueue refuse the model, and the
    // surround pipeline runs the SSGI gather of its `ssgi` section on the frame instead.
    bool has_network = true;
    // false: the output's H x W is the network's own, not the input's (family graph: its nodes may stride, pool or
    // resize); Model::run sizes the output, and Model::enqueue's output buffer must hold what the network writes.
    bool output_keeps_size = true;
    int input_nc = 0, output_nc = 0;
    std::vector<std::string> input_layout;  // channel names, may be empty
    float input_range[2] = {-1.0f, 1.0f};
    float output_range[2] = {-1.0f, 1.0f};
    // What the decoded output is (family pix2pix_unet; docs/MODEL_FORMAT.md, docs/CONVENTIONS.md section 8):
    // "lightmap" (the thesis's; default) the front view's whole lightmap, direct + indirect; "indirect" indirect
    // light only, and the pipeline adds the frame's front direct light to make the lightmap (so front_lightmap
    // needs the frame). At the top, not in `unet`: the pipeline reads it for every family (ssgi's is "indirect").
    std::string output_mode = "lightmap";
    std::string source;
    std::string json;                // the metadata exactly as stored

    // The sections below are the network's parts, each read by the families built from it (as tiny-cuda-nn
    // composes a network from an encoding and a network config); a family's parser fills the sections it reads
    // and leaves the others at their defaults:
    //   unet      pix2pix_unet, deepillumination, neural_gi (its neural buffer)
    //   encoding  mlp, neural_gi (graph's frequency_encode nodes read the same JSON object)
    //   mlp       mlp
    //   voxel_sh, neural_gi, graph, ssgi: that family's own section (ssgi's also for output_mode "ssgi_residual").

    // A pix2pix-style U-Net generator's fields (docs/MODEL_FORMAT.md "Config"). ngf == 0: the model has no U-Net,
    // and then num_downs is 0 too (its inputs' H and W need be multiples of 2^num_downs = 1 only).
    struct UNet {
        int ngf = 0, num_downs = 0;
        std::string bn_mode = "running"; // "running" (eval-mode statistics) | "per_image" (train-mode, batch 1)
        float bn_eps = 1e-5f;
        std::string dropout = "off";     // "off" | "seeded"
        float dropout_p = 0.5f;
        std::uint32_t dropout_seed = 0;
        float leaky_slope = 0.2f;
    } unet;

    // The optional per-item frequency encoding before the first dense layer (the file's "encoding" object;
    // docs/CONVENTIONS.md section 13).
    struct Encoding {
        int bands = 0, first_exponent = 0;  // bands = 0: no encoding
        bool pi = true, include_input = true;
        std::string order = "band";  // "band" (NeRF, Neural GI Eq. 3) | "component" (tiny-cuda-nn)
    } encoding;

    // family "mlp": a network evaluated per item (pixel of an NCHW image, or row of an [N, C] point list): the
    // `encoding` above, then these dense layers (docs/MODEL_FORMAT.md "mlp", docs/CONVENTIONS.md section 13). The
    // file's bn_mode / dropout keys are checked and have nothing to act on.
    struct Mlp {
        struct Layer {
            int out = 0;
            std::string activation = "none";  // none | relu | leaky_relu | tanh | sigmoid | exp
            float slope = 0.01f;              // leaky_relu only
        };
        std::vector<Layer> layers;
    } mlp;

    // family "voxel_sh" (seed 004): the 27 SH coefficients ([3][9], docs/CONVENTIONS.md section 14) of the light
    // each occupied voxel receives, from its 10 raw attributes (docs/MODEL_FORMAT.md "voxel_sh"). Model::run takes
    // [V, 10] and returns [V, 27] in lighting units: the standardization below runs on the device.
    struct VoxelSh {
        std::string architecture;                 // "mlp" | "set" | "resnet"
        int grid[3] = {0, 0, 0};                  // X, Y, Z of the scenes it was trained on
        std::vector<int> hidden;                  // mlp: hidden widths (tanh); then linear -> 27
        std::vector<int> phi, rho;                // set: per-voxel phi widths (tanh); rho's hidden widths (tanh)
        int width = 0, blocks = 0;                // resnet: width W, residual blocks h = h + tanh(W h + b)
        std::vector<double> input_lo, input_hi;   // [10]: x' = 2 (x - lo) / (hi - lo) - 1 (0 where hi == lo)
        std::vector<double> output_mean, output_std;  // [27]: y = mean + std * y'
        // The per-voxel inputs hold absolute positions and ids: throws InputError naming both sizes unless
        // (x, y, z) is the training grid.
        void check_grid(int x, int y, int z) const;
    } voxel_sh;

    // family "neural_gi" (seed 002, docs/MODEL_FORMAT.md "neural_gi"): per scene, [1, 18, H, W] assembled inputs
    // -> [1, 3, H, W] indirect light (>= 0). The neural buffer is a pix2pix U-Net (the `unet` section; linear
    // output, buffer_channels); the encoding is the `encoding` section; the MLP takes
    // [encoded inputs, buffer] through `mlp_depth` ReLU layers of `mlp_width`, the input concatenated again before
    // layer `skip_layer`, then a linear layer to RGB decoded by exp(min(x, 88)).
    struct NeuralGi {
        int buffer_channels = 0;
        int mlp_width = 0, mlp_depth = 0, skip_layer = 0;
        // The scene's bounding box (world metres) that positions are normalized with: 2 (p - min) / (max - min) - 1.
        // A model is trained for one scene; running it on frames (NeuralGiRenderer) needs the box.
        bool has_scene_box = false;
        float scene_min[3] = {0, 0, 0}, scene_max[3] = {0, 0, 0};
    } neural_gi;

    // family "graph" (docs/MODEL_FORMAT.md "graph"; python3 -m ngi.convert writes it from an ONNX file): a list of
    // nodes (conv2d, conv_transpose2d, dense, concat, activation, affine, add, mul, frequency_encode, nan_to_num) over
    // named tensors, built on the graph ops; the loader validates the list (models/graph_config.cpp).
    // layout "nchw": Model::run takes [1, input_nc, H, W]; "nc": [N, input_nc] items (or [1, input_nc, H, W], per
    // pixel), as the mlp family.
    struct GraphFamily {
        std::string layout = "nchw";
    } graph;

    // family "ssgi" (docs/MODEL_FORMAT.md "ssgi", docs/CONVENTIONS.md section 19): no network and no tensors. The
    // surround pipeline gathers the light the cluster's faces send to the front face (one bounce, or more by iterating
    // over the faces) and adds it to the frame's direct light, as for output_mode "indirect". Model::run and
    // Model::enqueue refuse it: it runs on frames (SurroundPipeline::run / enqueue and every API built on them).
    struct Ssgi {
        std::string view = "surround";  // "surround": senders on all six faces; "front": the front face alone
        int cluster_level = 3;          // far senders grouped in blocks of 2^level x 2^level texels (0: none)
        float near_factor = 4.0f;       // a block whose mean position is closer than this many standard
                                        // deviations of its positions is replaced by its quarters, and a quarter
                                        // that close by its texels
        float min_distance = 0.5f;      // metres: closer sender-receiver pairs are skipped
        int bounces = 1;                // 2+: each further bounce first gathers at every sender face
        int visibility_steps = 0;       // > 0: each pair's segment is marched through the faces' depth in this
                                        // many samples and blocked pairs send nothing; 0: no visibility test
        float thickness = 0.0f;         // how far a surface is assumed to extend behind what the faces see, as a
                                        // fraction of its depth (a sample farther behind it is free); 0: unbounded
    } ssgi;
};

// Overrides of the file's settings; an empty string keeps the file's value.
struct ModelOptions {
    std::string bn_mode;   // ModelConfig::unet's (a family without a U-Net refuses or ignores them)
    std::string dropout;
    std::string mlp_path;  // family "mlp": "fused" | "dense" | "" (auto: fused when it fits the device)
};

struct LayerTiming {
    std::string name, kind;
    double ms = 0, gflop = 0;  // device time (the sum of its kernels'), useful work
    int launches = 0;          // kernels it enqueued: each costs the device's launch overhead
};

struct RunInfo {
    // Input values replaced before the first layer: NaN -> 0; +-Inf and finite values beyond input_range by
    // more than 1/1024 of its width (e.g. 3.4e38, which would overflow to Inf and NaN inside the network) -> the
    // nearer end of input_range. Values within that margin pass unchanged (rounding at the range's ends).
    int sanitized_inputs = 0;
    std::vector<LayerTiming> layers; // per graph node, when the device was opened with profiling
    std::size_t arena_bytes = 0;     // planned peak of intermediate tensors
    std::size_t naive_bytes = 0;     // what one buffer per tensor would need
    std::size_t scratch_bytes = 0;   // im2col / cols scratch, shared by all nodes
    std::size_t weight_bytes = 0;    // packed weights on the device
};

class Model {
public:
    static Model load(const Device& device, const std::string& path, const ModelOptions& options = {});
    Model(Model&&) noexcept;
    Model& operator=(Model&&) noexcept;
    ~Model();

    const ModelConfig& config() const;
    // input: [1, input_nc, H, W] with H and W multiples of 2^unet.num_downs. Returns [1, output_nc, H, W].
    // Family "mlp": [1, input_nc, H, W] (per pixel) -> [1, output_nc, H, W], or [N, input_nc] -> [N, output_nc].
    // Family "voxel_sh": [V, 10] raw voxel attributes (one scene) -> [V, 27] SH coefficients.
    // Family "neural_gi": [1, 18, H, W] assembled inputs -> [1, 3, H, W] indirect light.
    // Family "graph": [1, input_nc, H, W] -> [1, output_nc, H', W'] (layout "nchw"); layout "nc" also [N, input_nc]
    // -> [N, output_nc].
    // The graph for each new H x W is built and planned on first use and reused afterwards.
    Tensor run(const Tensor& input, RunInfo* info = nullptr);

    // Device in, device out, asynchronous: `input` holds [1, input_nc, height, width] float32 (NCHW) from byte 0,
    // `output` receives [1, output_nc, height, width]; both at least that large and on this model's device
    // (InputError otherwise). Families "mlp" and "voxel_sh" take height x width items, planar (voxel_sh: [10, V]
    // -> [27, V] for one scene of V = height x width voxels). Returns once enqueued on the device's in-order queue:
    // no host transfer, nothing waited for (Device::finish() or Device::marker() wait). `input` is only read (the
    // guard works on a copy).
    void enqueue(const DeviceBuffer& input, const DeviceBuffer& output, int height, int width);
    // Input values the guard replaced in the last enqueue() (see RunInfo::sanitized_inputs). Blocks: it reads a
    // counter back from the device.
    int sanitized_inputs();

private:
    friend struct detail::ModelAccess;
    struct Impl;
    explicit Model(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

// --- Shipped models by name (README "Use ngi from your project", models/README.md) -------------------------------
// A model name is the name of a rung with a file in a models folder's zoo.json ("surround_n64_ngf16",
// "shipped_surround_n64_ngf32"), or the stem of a .safetensors file in that folder or one of its subfolders
// ("surround", "single_view", "voxel_sh_set", "ao_bunny_32x16", "neural_gi_room"). Folders searched, in order:
//   1. each entry of $NGI_MODEL_PATH (':'-separated; the override);
//   2. the installed models of the binary holding ngi's code (the program, libngi_c.so or the Python module):
//      <prefix>/share/ngi/models found relative to it (a relocated prefix works), or models/ beside it (pip);
//   3. <configured install prefix>/share/ngi/models, then /usr/local/share/ngi/models and /usr/share/ngi/models;
//   4. the source tree's models/ (a build tree; only if the build enabled NGI_SOURCE_MODELS_FALLBACK).
// A folder that does not exist is skipped; the first folder that has a name wins.
std::vector<std::string> model_search_path();
// Every known name with its file, sorted by name (the first folder of model_search_path() holding it wins).
// Throws InputError naming the file when a searched folder's zoo.json is not readable JSON of the zoo format.
std::vector<std::pair<std::string, std::string>> model_names();
// The file to load for `name_or_path`: unchanged when it is an existing file or looks like a path (contains '/' or
// ends in ".safetensors"; Model::load then reports a missing file); otherwise the file of that model name. Throws
// InputError "model '<name>': not a file and not a known model name (searched: ...); known names: ..." for an
// unknown name.
std::string resolve_model(const std::string& name_or_path);

}  // namespace ngi
