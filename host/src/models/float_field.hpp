// Model configs store numbers as JSON doubles; the kernels compute in float32. A config number is usable only if
// the conversion keeps it: a double check alone let bn_eps 1e-300 pass "(0, 1]" and become 0 in float32, and an
// all-zero input then gave NaN everywhere (issue 31). Library-internal.
#pragma once
#include <cfloat>
#include <cmath>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace ngi::detail {

// Whether float(x) stands for x: finite, |x| <= FLT_MAX, and either 0 or at least FLT_MIN (a normal float). A
// nonzero value below FLT_MIN rounds to 0 or to a subnormal, which loses precision and which devices may flush to
// zero (OpenCL does not require single-precision denormals), so a positive field would become 0 on some devices.
inline bool float32_representable(double x) {
    const double a = std::abs(x);
    return std::isfinite(x) && a <= double(FLT_MAX) && (a == 0.0 || a >= double(FLT_MIN));
}

// The rule's words for error messages.
inline constexpr const char* kFloat32Rule = "representable in float32 (0, or 1.2e-38 <= |v| <= 3.4e38)";

// A config's "input_layout": a list of strings, empty or input_nc long (the generator families and the graph
// family). Fills `out` and returns true, or returns false when `v` breaks the rule input_layout_rule() states.
inline std::string input_layout_rule(int input_nc) {
    return "a list of strings, empty or input_nc (" + std::to_string(input_nc) + ") long";
}
inline bool read_input_layout(const nlohmann::json& v, int input_nc, std::vector<std::string>& out) {
    if (!v.is_array() || (!v.empty() && v.size() != std::size_t(input_nc))) return false;
    for (const auto& s : v) {
        if (!s.is_string()) return false;
        out.push_back(s.get<std::string>());
    }
    return true;
}

}  // namespace ngi::detail
