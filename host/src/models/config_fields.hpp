// What every family's config parser shares (docs/MODEL_FORMAT.md "Config"): typed readers of the metadata object
// that check each field's JSON type and range before converting it (get<int> would truncate 2^32 + 4 to 4, get<float>
// turns 1e300 into inf) and name the file and the key in every error; "format_version"; and the one check of the keys
// against the fields a family knows ("required", or a family that refuses unknown keys). Library-internal.
#pragma once
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "ngi/error.hpp"

namespace ngi::detail {

// The newest docs/MODEL_FORMAT.md version this reader understands; files of a newer version are refused.
inline constexpr int kModelFormatVersion = 1;
// Channel counts (input_nc, output_nc, 8 * ngf) above this are refused as corrupt configs.
inline constexpr int kMaxChannels = 65536;

// Whether v is a JSON integer in lo..hi (an unsigned one beyond LLONG_MAX is not).
bool is_integer_in(const nlohmann::json& v, long long lo, long long hi);

// The start of every config error: "load model <path>: metadata 'ngi': ".
std::string config_what(const std::string& path);

// A family parser's view of its metadata object.
class ConfigFields {
public:
    // got_limit: how many characters of ", got <value>" an error quotes.
    ConfigFields(const nlohmann::json& j, const std::string& path, std::size_t got_limit = 120);
    const nlohmann::json& json() const { return j_; }
    const std::string& what() const { return what_; }
    bool has(const std::string& key) const { return j_.contains(key); }
    const nlohmann::json& at(const std::string& key) const { return j_.at(key); }

    // what + "field '<key>' must be <rule>, got <value>" (or " (missing)").
    InputError fail(const std::string& key, const std::string& rule) const;
    // Absent: `fallback`, or "must be present" when required.
    long long integer(const char* key, long long lo, long long hi, long long fallback, bool required) const;
    // A finite number in the range, representable in float32 (models/float_field.hpp).
    float number(const char* key, double lo, double hi, bool lo_open, bool hi_open, float fallback) const;
    // One of `allowed` (any string when empty).
    std::string string(const char* key, const std::vector<std::string>& allowed, const std::string& fallback,
                       bool required) const;
    // [lo, hi]: finite, |v| <= 1e30, lo < hi also in float32. Absent: `out` unchanged.
    void range(const char* key, float* out) const;
    // "format_version": absent means 1; a newer one is refused with "update ngi", others outside 1..newest.
    void format_version() const;

private:
    const nlohmann::json& j_;
    std::string what_;
    std::size_t got_limit_;
};

// How a family treats metadata keys it does not know.
enum class UnknownFields {
    ignore,  // ignored (a newer writer may add hints); "required" lists the fields no reader may ignore
    refuse,  // refused: the family's config is closed
};

// The keys of the metadata against `known`, the fields the family reads. With UnknownFields::refuse every key must
// be known ("field '<key>' is not a field of family <family> (<listing>)"). In both cases a "required" key, when the
// family knows it, must be a list of field names the family knows ("... which this reader does not know: the file
// needs a newer ngi").
void check_fields(const ConfigFields& f, const std::vector<std::string_view>& known,
                  UnknownFields unknown = UnknownFields::ignore, const std::string& family = "",
                  const std::string& listing = "");

}  // namespace ngi::detail
