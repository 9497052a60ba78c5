// Family "ssgi" (docs/MODEL_FORMAT.md "ssgi", docs/CONVENTIONS.md section 19): a rung with no network and no tensors.
// Its config is the gather's settings (models/ssgi_config.hpp), closed to other keys; its runner refuses every
// network call: the surround pipeline runs the gather on frames (host/src/pipeline/ssgi.cpp).
#include "models/config_fields.hpp"
#include "models/family.hpp"
#include "models/ssgi_config.hpp"

namespace ngi::detail {

namespace {

FamilyConfig parse_ssgi(const nlohmann::json& j, const std::string& path) {
    const ConfigFields f(j, path);
    FamilyConfig parsed;
    ModelConfig& c = parsed.config;
    c.family = "ssgi";
    // No network (Model::run and enqueue refuse it: the pipeline runs the gather on the frame's images), and the
    // lightmap it makes has the front face's size.
    parsed.traits = {.input = ModelInput::image, .has_network = false, .output_keeps_size = true};
    f.format_version();
    read_ssgi_gather_fields(j, f.what(), c.ssgi);
    // No network: nothing is read from or written to a tensor. The pipeline's output is 3 channels of light; an
    // indirect part is added to the frame's direct light, as an "indirect" generator's is.
    c.input_nc = 0;
    c.output_nc = 3;
    c.output_mode = "indirect";
    if (j.contains("output_mode") && j["output_mode"] != "indirect")
        throw f.fail("output_mode", "\"indirect\" (ssgi adds its light to the frame's direct light)");
    c.source = f.string("source", {}, c.source, false);
    check_fields(f, {"format_version", "family", "view", "cluster_level", "bounces", "near_factor", "min_distance",
                     "visibility_steps", "thickness", "output_mode", "source", "comment"},
                 UnknownFields::refuse, "ssgi", std::string(ssgi_gather_field_names()) + ", output_mode, source, comment");
    return parsed;
}

// Every network call is refused, naming what runs family ssgi instead.
class SsgiRunner : public FamilyRunner {
public:
    Tensor run(Context&, const ModelConfig&, const Tensor&, RunInfo*) override { throw refusal("run model"); }
    void enqueue(const Device&, const ModelConfig&, const DeviceBuffer&, const DeviceBuffer&, int, int) override {
        throw refusal("enqueue model");
    }
    void enqueue_frame(Context&, const ModelConfig&, cl_mem, std::size_t, cl_mem, std::size_t, int, int) override {
        throw refusal("the surround pipeline's network");
    }
    int sanitized_inputs(Context&) override { return 0; }

private:
    static InputError refusal(const char* what) {
        return InputError(std::string(what) + ": family ssgi has no network; it runs on frames (SurroundPipeline::run "
                          "or enqueue, ngi lightmap, ngi_pipeline_run, Pipeline.run)");
    }
};

std::unique_ptr<FamilyRunner> load_ssgi(Context&, ModelConfig& cfg, const SafetensorsFile&, const std::string& path,
                                        const ModelOptions& options) {
    apply_network_options(cfg, options);
    if (!options.bn_mode.empty() || !options.dropout.empty() || !options.mlp_path.empty())
        throw InputError("load model " + path + ": bn_mode, dropout and mlp_path apply to networks; an ssgi rung "
                         "has none");
    return std::make_unique<SsgiRunner>();
}

}  // namespace

extern constinit const ModelFamily kSsgiFamily{"ssgi", &parse_ssgi, &load_ssgi};

}  // namespace ngi::detail
