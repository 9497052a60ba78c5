// The model families, listed once (models/family.hpp), and the dispatch of a config to its family.
//
// An explicit list, not self-registering files: ngi_core is a static library, and the linker drops an object file
// nothing references, so a family whose file only held a static registrar would silently vanish from applications.
// Listing the families here references each family's object (and the families are constant-initialized: no
// static-initialization order to get wrong, and a unity build sees one list).
#include <algorithm>
#include <iterator>

#include "base/json_strict.hpp"
#include "models/config_fields.hpp"
#include "models/family.hpp"

// A new family: its front-end file (models/<family>_family.cpp) defines `extern constinit const ModelFamily k<Name>Family`
// (its parser setting the family's traits, models/family.hpp FamilyTraits), and one line here names it. The order is
// the order error messages list the families in.
#define NGI_MODEL_FAMILIES(X)  \
    X(kPix2pixUnetFamily)      \
    X(kDeepIlluminationFamily) \
    X(kMlpFamily)              \
    X(kVoxelShFamily)          \
    X(kNeuralGiFamily)         \
    X(kGraphFamily)            \
    X(kSsgiFamily)             \
    X(kPixelCnnFamily)

namespace ngi::detail {

#define NGI_DECLARE_FAMILY(name) extern const ModelFamily name;
NGI_MODEL_FAMILIES(NGI_DECLARE_FAMILY)
#undef NGI_DECLARE_FAMILY

namespace {

#define NGI_LIST_FAMILY(name) &name,
constexpr const ModelFamily* kModelFamilies[] = {NGI_MODEL_FAMILIES(NGI_LIST_FAMILY)};
#undef NGI_LIST_FAMILY

// A config whose "family" is missing, not a string or no family's name: the format version is judged first (a newer
// file's family may be one this reader does not know yet), then the family.
[[noreturn]] void refuse_family(const nlohmann::json& j, const std::string& path) {
    const ConfigFields f(j, path);
    f.format_version();
    if (!f.has("family")) throw f.fail("family", "present");
    if (!f.at("family").is_string())  // the families of the one parser before issue 49, as its message listed them
        throw f.fail("family", "a string: \"pix2pix_unet\" | \"deepillumination\" | \"mlp\" | \"neural_gi\"");
    throw InputError(f.what() + "family '" + f.at("family").get<std::string>() + "' is not supported (" +
                     model_family_names() + ")");
}

}  // namespace

const ModelFamily* find_model_family(std::string_view name) {
    const auto it = std::find_if(std::begin(kModelFamilies), std::end(kModelFamilies),
                                 [&](const ModelFamily* f) { return f->name == name; });
    return it == std::end(kModelFamilies) ? nullptr : *it;
}

std::span<const ModelFamily* const> model_families() { return kModelFamilies; }

std::string model_family_names() {
    std::string s;
    for (const ModelFamily* f : model_families()) s += (s.empty() ? "" : ", ") + std::string(f->name);
    return s;
}

FamilyConfig parse_family_config(const std::string& text, const std::string& path) {
    const std::string what = config_what(path);
    nlohmann::json j;
    try {
        j = parse_json_unique_keys(text, what);  // {"bn_eps": 1e-5, "bn_eps": 0.5} is not a config
    } catch (const nlohmann::json::exception& e) {
        throw InputError(what + "malformed JSON: " + e.what());
    }
    if (!j.is_object()) throw InputError(what + "the config is not a JSON object");
    const auto name = j.find("family");
    const ModelFamily* family =
        name != j.end() && name->is_string() ? find_model_family(name->get<std::string>()) : nullptr;
    if (!family) refuse_family(j, path);
    FamilyConfig c = family->parse(j, path);
    apply_family_traits(c, family->name);
    c.config.json = text;
    c.family = family;
    return c;
}

void apply_family_traits(FamilyConfig& parsed, std::string_view family) {
    auto unset = [&](const char* trait) {
        return Error("model family " + std::string(family) + ": its parser did not set the trait '" + trait +
                     "' (models/family.hpp FamilyTraits); a bug in the library, not in the file");
    };
    const FamilyTraits& t = parsed.traits;
    if (!t.input) throw unset("input");
    if (!t.has_network) throw unset("has_network");
    if (!t.output_keeps_size) throw unset("output_keeps_size");
    parsed.config.input = *t.input;
    parsed.config.has_network = *t.has_network;
    parsed.config.output_keeps_size = *t.output_keeps_size;
}

ModelConfig parse_model_config(const std::string& text, const std::string& path) {
    return parse_family_config(text, path).config;
}

}  // namespace ngi::detail
