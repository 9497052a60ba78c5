// The gather's settings of family ssgi and of a network that corrects it (models/ssgi_config.hpp).
#include "models/ssgi_config.hpp"

#include "models/float_field.hpp"
#include "ngi/error.hpp"

namespace ngi::detail {

namespace {

const char* const kGatherFieldNames = "view, cluster_level, bounces, near_factor, min_distance, visibility_steps, thickness";

}  // namespace

void read_ssgi_gather_fields(const nlohmann::json& j, const std::string& what, ModelConfig::Ssgi& s) {
    auto fail = [&](const std::string& key, const std::string& rule) {
        const std::string got = j.contains(key) ? ", got " + j[key].dump() : " (missing)";
        return InputError(what + "field '" + key + "' must be " + rule + got.substr(0, 120));
    };
    auto integer = [&](const char* key, long long lo, long long hi, int fallback) {
        if (!j.contains(key)) return fallback;
        const nlohmann::json& v = j[key];
        if (!v.is_number_integer() || v.get<long long>() < lo || v.get<long long>() > hi ||
            (v.is_number_unsigned() && v.get<unsigned long long>() > (unsigned long long)hi))
            throw fail(key, "an integer in " + std::to_string(lo) + ".." + std::to_string(hi));
        return int(v.get<long long>());
    };
    auto number = [&](const char* key, double lo, double hi, float fallback) {
        if (!j.contains(key)) return fallback;
        const nlohmann::json& v = j[key];
        const std::string rule = "a number in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
        if (!v.is_number() || !float32_representable(v.get<double>()) || v.get<double>() < lo || v.get<double>() > hi)
            throw fail(key, rule);
        return float(v.get<double>());
    };
    if (j.contains("view")) {
        if (!j["view"].is_string() || (j["view"] != "surround" && j["view"] != "front"))
            throw fail("view", "\"surround\" (senders on all six faces) or \"front\" (the front face only)");
        s.view = j["view"].get<std::string>();
    }
    s.cluster_level = integer("cluster_level", 0, kSsgiMaxClusterLevel, s.cluster_level);
    s.bounces = integer("bounces", 1, kSsgiMaxBounces, s.bounces);
    s.near_factor = number("near_factor", 0.0, 1e3, s.near_factor);
    s.min_distance = number("min_distance", 0.0, 1e3, s.min_distance);
    s.visibility_steps = integer("visibility_steps", 0, kSsgiMaxVisibilitySteps, s.visibility_steps);
    s.thickness = number("thickness", 0.0, 1e3, s.thickness);
}

const char* ssgi_gather_field_names() { return kGatherFieldNames; }

ModelConfig::Ssgi parse_ssgi_gather(const nlohmann::json& j, const std::string& what) {
    if (!j.is_object())
        throw InputError(what + "field 'ssgi' must be an object of the gather's settings (" + kGatherFieldNames + ")");
    const std::string inner = what + "'ssgi': ";
    for (const auto& item : j.items()) {
        const std::string& k = item.key();
        if (k != "view" && k != "cluster_level" && k != "bounces" && k != "near_factor" && k != "min_distance" &&
            k != "visibility_steps" && k != "thickness")
            throw InputError(inner + "field '" + k.substr(0, 80) + "' is not a setting of the gather (" +
                             kGatherFieldNames + ")");
    }
    ModelConfig::Ssgi s;
    read_ssgi_gather_fields(j, inner, s);
    return s;
}

}  // namespace ngi::detail
