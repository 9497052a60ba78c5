// Family "graph" (docs/MODEL_FORMAT.md "graph"; what python3 -m ngi.convert writes from an ONNX file): its config
// (the node list by graph_config.cpp, ranges, layout), and the runner of the graph built by graph_model.cpp: layout
// "nc" also takes [N, C] items, and an output that resamples is sized from the graph.
#include <cfloat>

#include "models/config_fields.hpp"
#include "models/family.hpp"
#include "models/float_field.hpp"
#include "models/graph_model.hpp"
#include "models/graph_runner.hpp"
#include "ops/gemm_selfcheck.hpp"

namespace ngi::detail {

namespace {

FamilyConfig parse_graph(const nlohmann::json& j, const std::string& path) {
    const ConfigFields f(j, path);
    const std::string& what = f.what();
    auto fail = [&](const std::string& key, const std::string& rule) { return f.fail(key, rule); };
    FamilyConfig parsed;
    ModelConfig& c = parsed.config;
    c.family = "graph";
    f.format_version();
    const GraphDesc d = parse_graph_desc(j, what);
    c.input_nc = d.input_nc;
    c.output_nc = d.nodes[d.output - 1].out_channels;
    c.graph.layout = d.layout;
    // Its nodes decide the output's size (strides, pools, resizes; not analysed here, so never assumed to keep it).
    parsed.traits = {.input = d.layout == "nc" ? ModelInput::items : ModelInput::image, .has_network = true,
                     .output_keeps_size = false};
    if (j.contains("output_nc") && !(is_integer_in(j["output_nc"], 1, kMaxChannels) && j["output_nc"] == c.output_nc))
        throw fail("output_nc", "the graph output's channel count (" + std::to_string(c.output_nc) + ")");
    // An imported network's inputs have no known range: the guard replaces only NaN (-> 0) and +-Inf.
    c.input_range[0] = -FLT_MAX;
    c.input_range[1] = FLT_MAX;
    for (const char* key : {"input_range", "output_range"}) {
        if (!j.contains(key)) continue;
        const nlohmann::json& v = j[key];
        const std::string rule = std::string("[lo, hi], two numbers with lo < hi, both ") + kFloat32Rule;
        if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number()) throw fail(key, rule);
        const double lo = v[0].get<double>(), hi = v[1].get<double>();
        if (!float32_representable(lo) || !float32_representable(hi) || !(float(lo) < float(hi))) throw fail(key, rule);
        float* out = std::string(key) == "input_range" ? c.input_range : c.output_range;
        out[0] = float(lo);
        out[1] = float(hi);
    }
    if (j.contains("input_layout") && !read_input_layout(j["input_layout"], c.input_nc, c.input_layout))
        throw fail("input_layout", input_layout_rule(c.input_nc));
    c.source = f.string("source", {}, c.source, false);
    if (j.contains("output_mode") && j["output_mode"] != "lightmap")
        throw fail("output_mode", "\"lightmap\" (only family pix2pix_unet has another output mode)");
    if (j.contains("training") && !j["training"].is_object()) throw fail("training", "an object");
    check_fields(f, {"format_version", "family", "input_nc", "output_nc", "graph", "input_range", "output_range",
                     "input_layout", "source", "training", "required", "onnx", "output_mode"});
    return parsed;
}

class GraphFamilyRunner : public GraphRunner {
public:
    explicit GraphFamilyRunner(GraphModelOps ops) : ops_(std::move(ops)) {}

    Tensor run(Context& ctx, const ModelConfig& c, const Tensor& input, RunInfo* info) override {
        if (c.graph.layout == "nc" && input.shape.size() == 2) return run_items(ctx, c, input, info);
        return GraphRunner::run(ctx, c, input, info);
    }
    // The pipeline sizes its buffers as [output_nc, height, width]; an imported graph may resample.
    void enqueue_frame(Context& ctx, const ModelConfig& cfg, cl_mem in, std::size_t in_offset, cl_mem out,
                       std::size_t out_offset, int height, int width) override {
        const Graph& g = graph(ctx, cfg, height, width);
        if (!(g.output_shape() == Shape{cfg.output_nc, height, width}))
            throw InputError("the surround pipeline needs an output of the input's size (" + std::to_string(height) +
                             "x" + std::to_string(width) + "); this graph model gives " + to_string(g.output_shape()));
        GraphRunner::enqueue_frame(ctx, cfg, in, in_offset, out, out_offset, height, width);
    }

protected:
    std::unique_ptr<Graph> build_graph(const ModelConfig&, int height, int width) const override {
        return build_graph_model_graph(ops_, height, width);
    }
    std::size_t weight_bytes() const override { return ops_.weight_bytes; }
    std::size_t output_bytes(Context& ctx, const ModelConfig& cfg, int height, int width) override {
        return graph(ctx, cfg, height, width).output_bytes();
    }

private:
    // Layout "nc": [N, C] items, transposed to the planar [C, 1, N] image the graph runs on and back.
    Tensor run_items(Context& ctx, const ModelConfig& c, const Tensor& input, RunInfo* info) {
        if (input.shape[1] != c.input_nc || input.shape[0] < 1 || input.shape[0] > (1 << 30))
            throw InputError("run model: input tensor is " + shape_string(input.shape) + ", expected [N, " +
                             std::to_string(c.input_nc) + "] with N in 1 .. 2^30 (or [1, " +
                             std::to_string(c.input_nc) + ", H, W] per pixel)");
        if (input.data.size() != Tensor::element_count(input.shape))
            throw InputError("run model: input tensor has " + std::to_string(input.data.size()) +
                             " values for shape " + shape_string(input.shape));
        const int n = input.shape[0], ci = c.input_nc, co = c.output_nc;
        Tensor planar({1, ci, 1, n});
        for (int i = 0; i < n; ++i)
            for (int k = 0; k < ci; ++k) planar.data[std::size_t(k) * n + i] = input.data[std::size_t(i) * ci + k];
        const Tensor y = GraphRunner::run(ctx, c, planar, info);
        Tensor out({n, co});
        for (int i = 0; i < n; ++i)
            for (int k = 0; k < co; ++k) out.data[std::size_t(i) * co + k] = y.data[std::size_t(k) * n + i];
        return out;
    }

    GraphModelOps ops_;
};

std::unique_ptr<FamilyRunner> load_graph(Context& ctx, ModelConfig& cfg, const SafetensorsFile& file,
                                         const std::string& path, const ModelOptions& options) {
    if (!options.bn_mode.empty() || !options.dropout.empty())
        throw InputError("load model " + path + ": bn_mode and dropout apply to the U-Net families; an imported "
                         "graph runs as exported (inference batch norm folded in, no dropout)");
    refuse_mlp_path(options, path, cfg);
    return naming_file(path, [&] {
        const GemmSelection& gemm = gemm_selection(ctx);
        return std::make_unique<GraphFamilyRunner>(
            build_graph_model_ops(ctx, cfg, file, gemm.params, gemm.conv_params));
    });
}

}  // namespace

extern constinit const ModelFamily kGraphFamily{"graph", &parse_graph, &load_graph};

}  // namespace ngi::detail
