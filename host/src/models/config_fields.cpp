// The shared readers and checks of every family's config (models/config_fields.hpp).
#include "models/config_fields.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <sstream>

#include "models/float_field.hpp"

namespace ngi::detail {

bool is_integer_in(const nlohmann::json& v, long long lo, long long hi) {
    if (!v.is_number_integer()) return false;
    if (v.is_number_unsigned() && v.get<std::uint64_t>() > std::uint64_t(LLONG_MAX)) return false;
    const long long x = v.get<long long>();
    return x >= lo && x <= hi;
}

std::string config_what(const std::string& path) { return "load model " + path + ": metadata 'ngi': "; }

ConfigFields::ConfigFields(const nlohmann::json& j, const std::string& path, std::size_t got_limit)
    : j_(j), what_(config_what(path)), got_limit_(got_limit) {}

InputError ConfigFields::fail(const std::string& key, const std::string& rule) const {
    const auto it = j_.find(key);
    const std::string got = it != j_.end() ? ", got " + it->dump() : " (missing)";
    return InputError(what_ + "field '" + key + "' must be " + rule + got.substr(0, got_limit_));
}

long long ConfigFields::integer(const char* key, long long lo, long long hi, long long fallback, bool required) const {
    if (!j_.contains(key)) {
        if (required) throw fail(key, "present");
        return fallback;
    }
    const nlohmann::json& v = j_.at(key);
    const std::string rule = "an integer in " + std::to_string(lo) + ".." + std::to_string(hi);
    if (!v.is_number_integer() || (v.is_number_unsigned() && v.get<std::uint64_t>() > std::uint64_t(hi)))
        throw fail(key, rule);
    const long long x = v.get<long long>();
    if (x < lo || x > hi) throw fail(key, rule);
    return x;
}

float ConfigFields::number(const char* key, double lo, double hi, bool lo_open, bool hi_open, float fallback) const {
    if (!j_.contains(key)) return fallback;
    const nlohmann::json& v = j_.at(key);
    auto fmt = [](double x) {
        std::ostringstream o;
        o << x;
        return o.str();
    };
    const std::string rule = std::string("a number in ") + (lo_open ? "(" : "[") + fmt(lo) + ", " + fmt(hi) +
                             (hi_open ? ")" : "]");
    if (!v.is_number()) throw fail(key, rule);
    const double x = v.get<double>();
    if (!std::isfinite(x) || x < lo || x > hi || (lo_open && x == lo) || (hi_open && x == hi)) throw fail(key, rule);
    if (!float32_representable(x)) throw fail(key, rule + " and " + kFloat32Rule);
    return float(x);
}

std::string ConfigFields::string(const char* key, const std::vector<std::string>& allowed,
                                 const std::string& fallback, bool required) const {
    if (!j_.contains(key)) {
        if (required) throw fail(key, "present");
        return fallback;
    }
    std::string rule = "a string";
    for (std::size_t i = 0; i < allowed.size(); ++i) rule += (i ? " | \"" : ": \"") + allowed[i] + "\"";
    if (!j_.at(key).is_string()) throw fail(key, rule);
    const std::string s = j_.at(key).get<std::string>();
    if (!allowed.empty() && std::find(allowed.begin(), allowed.end(), s) == allowed.end()) throw fail(key, rule);
    return s;
}

void ConfigFields::range(const char* key, float* out) const {
    if (!j_.contains(key)) return;
    const nlohmann::json& v = j_.at(key);
    if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number())
        throw fail(key, "[lo, hi], two finite numbers with lo < hi");
    const double lo = v[0].get<double>(), hi = v[1].get<double>();
    if (!std::isfinite(lo) || !std::isfinite(hi) || !(lo < hi) || std::abs(lo) > 1e30 || std::abs(hi) > 1e30)
        throw fail(key, "[lo, hi], two finite numbers with lo < hi");
    // In float32 too: [1e-300, 2e-300] is [0, 0] there, and the scaling divides by hi - lo.
    if (!float32_representable(lo) || !float32_representable(hi) || !(float(lo) < float(hi)))
        throw fail(key, std::string("[lo, hi] with lo < hi, both ") + kFloat32Rule + " and still lo < hi there");
    out[0] = float(lo);
    out[1] = float(hi);
}

void ConfigFields::format_version() const {
    if (j_.contains("format_version") && j_.at("format_version").is_number_integer() &&
        j_.at("format_version").get<long long>() > kModelFormatVersion)
        throw InputError(what_ + "field 'format_version' is " + j_.at("format_version").dump() +
                         ", newer than the newest this reader knows (" + std::to_string(kModelFormatVersion) +
                         "): update ngi");
    integer("format_version", 1, kModelFormatVersion, 1, false);  // absent: 1 (hand-written test files)
}

void check_fields(const ConfigFields& f, const std::vector<std::string_view>& known, UnknownFields unknown,
                  const std::string& family, const std::string& listing) {
    auto is_known = [&](const std::string& k) { return std::find(known.begin(), known.end(), k) != known.end(); };
    if (unknown == UnknownFields::refuse)
        for (const auto& item : f.json().items())
            if (!is_known(item.key()))
                throw InputError(f.what() + "field '" + item.key().substr(0, 80) + "' is not a field of family " +
                                 family + " (" + listing + ")");
    // "required": the fields a writer says no reader may ignore. A required one this reader does not know means the
    // file needs a newer ngi.
    if (!f.has("required")) return;
    const nlohmann::json& r = f.at("required");
    if (!r.is_array()) throw f.fail("required", "a list of field names");
    for (const auto& name : r) {
        if (!name.is_string()) throw f.fail("required", "a list of field names");
        const std::string n = name.get<std::string>();
        if (!is_known(n))
            throw InputError(f.what() + "field 'required' lists '" + n.substr(0, 80) +
                             "', which this reader does not know: the file needs a newer ngi");
    }
}

}  // namespace ngi::detail
