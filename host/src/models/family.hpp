// Model families (docs/ARCHITECTURE.md "Models"): what Model dispatches to. Each family is a front-end file,
// models/<family>_family.cpp, defining one ModelFamily: its name, the parser of its config and its loader, which
// builds the FamilyRunner that Model's methods call. family_registry.cpp lists the families, once; nothing else
// compares family names to choose what to do with a model file: the code outside models/ reads the traits each
// parser sets (ModelConfig::input, ::has_network, ::output_keeps_size). Library-internal.
#pragma once
#include <CL/cl.h>

#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "models/safetensors.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/model.hpp"

namespace ngi::detail {

class Context;
struct ModelFamily;

// The family's traits for one file (ModelConfig::input, ::has_network, ::output_keeps_size: what the code outside
// models/ chooses by instead of the family's name). Part of what a parse returns, not constants of ModelFamily,
// because they may depend on the file (graph's input follows its layout); optional, so that a parser that forgets
// one makes every load of its family fail (apply_family_traits, and the every-family test in
// tests/test_model_file.cpp) instead of the family silently passing for an image network by ModelConfig's defaults.
// A parser sets all three: parsed.traits = {.input = ..., .has_network = ..., .output_keeps_size = ...}.
struct FamilyTraits {
    std::optional<ModelInput> input;
    std::optional<bool> has_network;
    std::optional<bool> output_keeps_size;
};

// What a family's parser returns.
struct FamilyConfig {
    ModelConfig config;  // the fields the family has, the others at their defaults; json and traits set by the registry
    FamilyTraits traits;  // set by the parser, copied into `config` by the registry
    // Metadata the public config does not hold, for the library's own readers (ModelAccess::ao reads the "ao" object
    // of an mlp); null when the family keeps none.
    nlohmann::json internal;
    const ModelFamily* family = nullptr;  // set by the registry
};

// A loaded model's network: what Model::run, Model::enqueue, Model::sanitized_inputs and the surround pipeline's
// ModelAccess::enqueue do for its family. `cfg` is the model's config (with ModelOptions applied).
class FamilyRunner {
public:
    virtual ~FamilyRunner() = default;
    // Host in, host out, in the family's shapes (ngi/model.hpp); InputError naming what it takes otherwise.
    virtual Tensor run(Context& ctx, const ModelConfig& cfg, const Tensor& input, RunInfo* info) = 0;
    // Device in, device out, asynchronous: the buffers checked against the family's sizes and the model's device.
    virtual void enqueue(const Device& device, const ModelConfig& cfg, const DeviceBuffer& input,
                         const DeviceBuffer& output, int height, int width) = 0;
    // The surround pipeline's generator on raw buffers whose sizes and context the caller guarantees; families that
    // are no image generator refuse.
    virtual void enqueue_frame(Context& ctx, const ModelConfig& cfg, cl_mem in, std::size_t in_offset, cl_mem out,
                               std::size_t out_offset, int height, int width) = 0;
    // Input values the guard replaced in the last enqueue (RunInfo::sanitized_inputs); blocks.
    virtual int sanitized_inputs(Context& ctx) = 0;
};

struct ModelFamily {
    std::string_view name;  // the metadata's "family"
    // The config of a file of this family from its parsed metadata object: every field the family reads checked for
    // its JSON type and range (models/config_fields.hpp), and the traits (FamilyTraits) set; InputError naming the
    // file and the field otherwise.
    FamilyConfig (*parse)(const nlohmann::json& metadata, const std::string& path);
    // Model::load after the parse: `options` applied to `config` or refused, the tensors of `file` checked against
    // the config, the network built on the device. InputError naming the file otherwise.
    std::unique_ptr<FamilyRunner> (*load)(Context& ctx, ModelConfig& config, const SafetensorsFile& file,
                                          const std::string& path, const ModelOptions& options);
};

// ---- the registry (family_registry.cpp) -------------------------------------------------------------------------

// The family named `name`; nullptr when there is none.
const ModelFamily* find_model_family(std::string_view name);
// Every family, in the registry's order.
std::span<const ModelFamily* const> model_families();
// Every family's name, in the registry's order: "pix2pix_unet, deepillumination, ...".
std::string model_family_names();
// Parses the metadata text (once; a key repeated in one object is refused) and hands it to the family its "family"
// names. InputError naming the file: malformed JSON, not an object, no or an unknown family, or the family's own.
FamilyConfig parse_family_config(const std::string& json, const std::string& path);
// parse_family_config's public config: what Model::load reads (the tests and fuzz targets call it directly).
ModelConfig parse_model_config(const std::string& json, const std::string& path);
// Copies parsed.traits into parsed.config; ngi::Error naming `family` and the trait (a bug of that family's parser,
// not of the file) when the parser left one unset. parse_family_config calls it after every parse.
void apply_family_traits(FamilyConfig& parsed, std::string_view family);

// ---- what the loaders and runners share (family.cpp) ------------------------------------------------------------

// ModelOptions::bn_mode and ::dropout, when set, replace the file's values in `config`.
void apply_network_options(ModelConfig& config, const ModelOptions& options);
// "load model <path>: mlp_path applies to the mlp family, this is <family>" when options.mlp_path is set.
void refuse_mlp_path(const ModelOptions& options, const std::string& path, const ModelConfig& config);
// Runs `build`, adding " (file <path>)" to an InputError's message.
template <class F>
auto naming_file(const std::string& path, F&& build) -> decltype(build()) {
    try {
        return build();
    } catch (const InputError& e) {
        throw InputError(std::string(e.what()) + " (file " + path + ")");
    }
}
// A buffer of Model::enqueue: present, on `device`, at least `need` bytes, writable when written. `what`: "input" or
// "output".
void check_enqueue_buffer(const DeviceBuffer& b, const Device& device, std::size_t need, bool write, const char* what);
// height x width items (what: "items", "voxels") in 1 .. 2^30, for the families that take planar items.
void check_enqueue_items(int height, int width, const char* what);

}  // namespace ngi::detail
