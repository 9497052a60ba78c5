// Family "voxel_sh" (seed 004, docs/MODEL_FORMAT.md "voxel_sh"): per occupied voxel of one scene, 10 raw attributes
// in, 27 SH coefficients out. Its config (architecture, training grid, standardization, widths) and the runner over
// VoxelShRunner (models/voxel_sh_model.hpp).
#include <algorithm>
#include <climits>
#include <cmath>
#include <set>

#include "models/config_fields.hpp"
#include "models/family.hpp"
#include "models/float_field.hpp"
#include "models/voxel_sh_model.hpp"
#include "ops/gemm_selfcheck.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

namespace {

constexpr int kMaxWidth = 4096;
constexpr int kMaxHiddenLayers = 64, kMaxSetLayers = 16, kMaxBlocks = 256;
constexpr int kMaxGridSide = 65536;
constexpr long long kMaxGridCells = 1LL << 24;  // voxel ids are exact in float32 up to 2^24
constexpr double kMaxStat = 1e30;
const char* const kArchitectures[] = {"mlp", "set", "resnet"};
const char* const kDefaultLayout[kVoxelShInputs] = {"x", "y", "z", "albedo.r", "albedo.g", "albedo.b",
                                                    "emission.r", "emission.g", "emission.b", "id"};

FamilyConfig parse_voxel_sh(const nlohmann::json& metadata, const std::string& path) {
    const std::string what = config_what(path);
    // voxel_sh ignores keys it does not know, but an indirect output mode must not pass unnoticed.
    if (metadata.contains("output_mode") && metadata["output_mode"] != "lightmap")
        throw InputError(what + "field 'output_mode' is " + metadata["output_mode"].dump().substr(0, 80) +
                         "; only family pix2pix_unet has an output mode other than \"lightmap\"");
    nlohmann::json j = metadata;  // a copy: the checks below look fields up with operator[] (null when missing)
    const ConfigFields f(j, path, 160);
    auto fail = [&](const std::string& key, const std::string& rule) { return f.fail(key, rule); };
    // Integers are checked before conversion (get<int> would truncate 2^32 + 4 to 4).
    auto is_int_in = [](const nlohmann::json& v, long long lo, long long hi) {
        if (!v.is_number_integer()) return false;
        if (v.is_number_unsigned() && v.get<std::uint64_t>() > std::uint64_t(LLONG_MAX)) return false;
        const long long x = v.get<long long>();
        return x >= lo && x <= hi;
    };
    auto integer = [&](const char* key, long long lo, long long hi) {
        if (!j.contains(key) || !is_int_in(j[key], lo, hi))
            throw fail(key, "an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
        return int(j[key].get<long long>());
    };
    auto widths = [&](const char* key, std::size_t min_len, std::size_t max_len) {
        const std::string rule = "a list of " + std::to_string(min_len) + ".." + std::to_string(max_len) +
                                 " layer widths, integers in 1.." + std::to_string(kMaxWidth);
        if (!j.contains(key) || !j[key].is_array() || j[key].size() < min_len || j[key].size() > max_len)
            throw fail(key, rule);
        std::vector<int> w;
        for (const auto& v : j[key]) {
            if (!is_int_in(v, 1, kMaxWidth)) throw fail(key, rule);
            w.push_back(int(v.get<long long>()));
        }
        return w;
    };
    auto numbers = [&](const char* key, std::size_t n, double lo) {
        const std::string rule = "a list of " + std::to_string(n) + " finite numbers in [" +
                                 (lo == 0 ? std::string("0") : "-1e30") + ", 1e30], each " + kFloat32Rule;
        if (!j.contains(key) || !j[key].is_array() || j[key].size() != n) throw fail(key, rule);
        std::vector<double> v;
        for (const auto& x : j[key]) {
            if (!x.is_number()) throw fail(key, rule);
            const double d = x.get<double>();
            // float32 too: an output_std of 1e-300 is 0 there, and every output would be the mean.
            if (!std::isfinite(d) || d < lo || d > kMaxStat || !float32_representable(d)) throw fail(key, rule);
            v.push_back(d);
        }
        return v;
    };

    FamilyConfig parsed;
    ModelConfig& c = parsed.config;
    c.family = "voxel_sh";
    // One scene's voxels: [V, 10] by Model::run, planar [10, V] by Model::enqueue (no per-pixel images).
    parsed.traits = {.input = ModelInput::items, .has_network = true, .output_keeps_size = true};
    f.format_version();
    c.input_nc = kVoxelShInputs;
    c.output_nc = kVoxelShOutputs;
    if (j.contains("input_nc")) integer("input_nc", kVoxelShInputs, kVoxelShInputs);
    if (j.contains("output_nc")) integer("output_nc", kVoxelShOutputs, kVoxelShOutputs);

    ModelConfig::VoxelSh& v = c.voxel_sh;
    if (!j.contains("architecture") || !j["architecture"].is_string() ||
        std::none_of(std::begin(kArchitectures), std::end(kArchitectures),
                     [&](const char* a) { return j["architecture"] == a; }))
        throw fail("architecture", "one of \"mlp\", \"set\", \"resnet\"");
    v.architecture = j["architecture"].get<std::string>();

    const std::string grid_rule = "[X, Y, Z], three integers in 1.." + std::to_string(kMaxGridSide) +
                                  " with X Y Z <= 2^24 (voxel ids exact in float32)";
    if (!j.contains("grid") || !j["grid"].is_array() || j["grid"].size() != 3) throw fail("grid", grid_rule);
    long long cells = 1;
    for (int k = 0; k < 3; ++k) {
        if (!is_int_in(j["grid"][k], 1, kMaxGridSide)) throw fail("grid", grid_rule);
        v.grid[k] = int(j["grid"][k].get<long long>());
        cells *= v.grid[k];
    }
    if (cells > kMaxGridCells) throw fail("grid", grid_rule);

    v.input_lo = numbers("input_lo", kVoxelShInputs, -kMaxStat);
    v.input_hi = numbers("input_hi", kVoxelShInputs, -kMaxStat);
    for (int k = 0; k < kVoxelShInputs; ++k) {
        const double span = v.input_hi[k] - v.input_lo[k];
        // hi == lo: a constant channel, standardized to 0. Otherwise 2 / span must be a float.
        if (span < 0 || (span > 0 && 2.0 / span > kMaxStat))
            throw InputError(what + "fields 'input_lo', 'input_hi': channel " + std::to_string(k) + " has lo " +
                             std::to_string(v.input_lo[k]) + ", hi " + std::to_string(v.input_hi[k]) +
                             "; needs lo == hi or 2e-30 <= hi - lo");
    }
    v.output_mean = numbers("output_mean", kVoxelShOutputs, -kMaxStat);
    v.output_std = numbers("output_std", kVoxelShOutputs, 0.0);

    // The width fields of the architecture; those of another one are refused (a file that says both is ambiguous).
    std::set<std::string> arch_keys;
    if (v.architecture == "mlp") {
        v.hidden = widths("hidden", 1, kMaxHiddenLayers);
        arch_keys = {"hidden"};
    } else if (v.architecture == "set") {
        v.phi = widths("phi", 1, kMaxSetLayers);
        v.rho = widths("rho", 1, kMaxSetLayers);
        arch_keys = {"phi", "rho"};
    } else {
        v.width = integer("width", 1, kMaxWidth);
        v.blocks = integer("blocks", 0, kMaxBlocks);
        arch_keys = {"width", "blocks"};
    }
    for (const char* k : {"hidden", "phi", "rho", "width", "blocks"})
        if (j.contains(k) && !arch_keys.count(k))
            throw InputError(what + "field '" + k + "' does not belong to architecture \"" + v.architecture + "\"");

    if (j.contains("input_layout")) {
        const nlohmann::json& l = j["input_layout"];
        const std::string rule = "a list of 10 strings (the attribute names), or empty";
        if (!l.is_array() || (!l.empty() && l.size() != std::size_t(kVoxelShInputs))) throw fail("input_layout", rule);
        for (const auto& s : l) {
            if (!s.is_string()) throw fail("input_layout", rule);
            c.input_layout.push_back(s.get<std::string>());
        }
    }
    if (c.input_layout.empty()) c.input_layout.assign(std::begin(kDefaultLayout), std::end(kDefaultLayout));
    c.source = f.string("source", {}, c.source, false);
    if (j.contains("training") && !j["training"].is_object()) throw fail("training", "an object");
    check_fields(f, {"format_version", "family", "architecture", "input_nc", "output_nc", "grid", "input_lo",
                     "input_hi", "output_mean", "output_std", "hidden", "phi", "rho", "width", "blocks", "input_layout",
                     "source", "training", "required", "output_mode"});  // "lightmap" only (checked first)
    return parsed;
}

class VoxelShFamilyRunner : public FamilyRunner {
public:
    VoxelShFamilyRunner(Context& ctx, const ModelConfig& cfg, const SafetensorsFile& file, const std::string& path,
                        const GemmParams& gemm)
        : voxel_sh_(ctx, cfg, file, path, gemm) {}
    Tensor run(Context& ctx, const ModelConfig&, const Tensor& input, RunInfo* info) override {
        enqueued_ = false;
        return voxel_sh_.run(ctx, input, info);
    }
    void enqueue(const Device& device, const ModelConfig& c, const DeviceBuffer& input, const DeviceBuffer& output,
                 int height, int width) override {
        check_enqueue_items(height, width, "voxels");
        const std::size_t items = std::size_t(height) * std::size_t(width) * sizeof(float);
        check_enqueue_buffer(input, device, items * std::size_t(c.input_nc), false, "input");
        check_enqueue_buffer(output, device, items * std::size_t(c.output_nc), true, "output");
        voxel_sh_.enqueue(context_of(device), input.opencl_mem(), output.opencl_mem(), height * width);
        enqueued_ = true;
    }
    void enqueue_frame(Context&, const ModelConfig&, cl_mem, std::size_t, cl_mem, std::size_t, int, int) override {
        throw InputError("the surround pipeline runs image generators; this model is a voxel_sh network");
    }
    int sanitized_inputs(Context& ctx) override { return enqueued_ ? voxel_sh_.sanitized_count(ctx) : 0; }

private:
    VoxelShRunner voxel_sh_;
    bool enqueued_ = false;  // the last call was enqueue (run's guard is counted in RunInfo)
};

std::unique_ptr<FamilyRunner> load_voxel_sh(Context& ctx, ModelConfig& cfg, const SafetensorsFile& file,
                                            const std::string& path, const ModelOptions& options) {
    apply_network_options(cfg, options);
    refuse_mlp_path(options, path, cfg);
    return std::make_unique<VoxelShFamilyRunner>(ctx, cfg, file, path, gemm_selection(ctx).params);
}

}  // namespace

extern constinit const ModelFamily kVoxelShFamily{"voxel_sh", &parse_voxel_sh, &load_voxel_sh};

}  // namespace ngi::detail
