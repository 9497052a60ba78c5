#include "models/ssgi_config.hpp"

#include <set>

#include "models/float_field.hpp"
#include "models/unet.hpp"
#include "ngi/error.hpp"

namespace ngi::detail {

namespace {

const char* const kGatherFields = "view, cluster_level, bounces, near_factor, min_distance, visibility_steps, thickness";

// Reads the gather's settings present in `j` into `s` (absent ones keep their defaults); `what` starts every error.
void read_gather_fields(const nlohmann::json& j, const std::string& what, ModelConfig::Ssgi& s) {
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

}  // namespace

ModelConfig::Ssgi parse_ssgi_gather(const nlohmann::json& j, const std::string& what) {
    if (!j.is_object())
        throw InputError(what + "field 'ssgi' must be an object of the gather's settings (" + kGatherFields + ")");
    const std::string inner = what + "'ssgi': ";
    for (const auto& item : j.items()) {
        const std::string& k = item.key();
        if (k != "view" && k != "cluster_level" && k != "bounces" && k != "near_factor" && k != "min_distance" &&
            k != "visibility_steps" && k != "thickness")
            throw InputError(inner + "field '" + k.substr(0, 80) + "' is not a setting of the gather (" +
                             kGatherFields + ")");
    }
    ModelConfig::Ssgi s;
    read_gather_fields(j, inner, s);
    return s;
}

ModelConfig parse_ssgi_config(const nlohmann::json& j, const std::string& path) {
    const std::string what = "load model " + path + ": metadata 'ngi': ";
    auto fail = [&](const std::string& key, const std::string& rule) {
        const std::string got = j.contains(key) ? ", got " + j[key].dump() : " (missing)";
        return InputError(what + "field '" + key + "' must be " + rule + got.substr(0, 120));
    };
    ModelConfig c;
    c.family = "ssgi";
    if (j.contains("format_version")) {
        const nlohmann::json& v = j["format_version"];
        if (v.is_number_integer() && v.get<long long>() > kModelFormatVersion)
            throw InputError(what + "field 'format_version' is " + v.dump() + ", newer than the newest this reader "
                             "knows (" + std::to_string(kModelFormatVersion) + "): update ngi");
        if (!v.is_number_integer() || v.get<long long>() < 1)
            throw fail("format_version", "an integer in 1.." + std::to_string(kModelFormatVersion));
    }
    read_gather_fields(j, what, c.ssgi);
    // No network: nothing is read from or written to a tensor. The pipeline's output is 3 channels of light; an
    // indirect part is added to the frame's direct light, as an "indirect" generator's is.
    c.input_nc = 0;
    c.output_nc = 3;
    c.output_mode = "indirect";
    if (j.contains("output_mode") && j["output_mode"] != "indirect")
        throw fail("output_mode", "\"indirect\" (ssgi adds its light to the frame's direct light)");
    if (j.contains("source")) {
        if (!j["source"].is_string()) throw fail("source", "a string");
        c.source = j["source"].get<std::string>();
    }
    static const std::set<std::string> kKnown = {"format_version", "family", "view", "cluster_level", "bounces",
                                                 "near_factor", "min_distance", "visibility_steps", "thickness",
                                                 "output_mode", "source", "comment"};
    for (const auto& item : j.items())
        if (!kKnown.count(item.key()))
            throw InputError(what + "field '" + item.key().substr(0, 80) + "' is not a field of family ssgi (" +
                             kGatherFields + ", output_mode, source, comment)");
    return c;
}

}  // namespace ngi::detail
