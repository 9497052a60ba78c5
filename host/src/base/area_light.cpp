// Validation of the rectangular area light (ngi/area_light.hpp). In core's base/: frame folders (ngi_io) record the
// light, the renderer checks it before every frame and the pipeline reads neural GI frames that carry it.
#include "ngi/area_light.hpp"
#include "ngi/material.hpp"

#include <cmath>

#include "base/vec_text.hpp"
#include "ngi/error.hpp"

namespace ngi {
namespace {

std::string text(glm::vec3 v) { return detail::vec_text(v); }

}  // namespace

void check_area_light(const AreaLight& l, const std::string& operation) {
    const std::string what = operation + ": area light ";
    const std::pair<const char*, glm::vec3> fields[] = {
        {"centre", l.centre}, {"half_u", l.half_u}, {"half_v", l.half_v}, {"radiance", l.radiance}};
    for (const auto& [name, v] : fields)
        for (int k = 0; k < 3; ++k)
            if (!std::isfinite(v[k])) throw InputError(what + name + " " + text(v) + " is not finite");
    // Lengths in double: a finite float edge near FLT_MAX would overflow a float dot product.
    auto length = [](glm::vec3 v) { return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z); };
    const double lu = length(l.half_u), lv = length(l.half_v);
    if (!(lu > 1.0e-6)) throw InputError(what + "half_u " + text(l.half_u) + " is degenerate (zero area)");
    if (!(lv > 1.0e-6)) throw InputError(what + "half_v " + text(l.half_v) + " is degenerate (zero area)");
    const double cosine =
        (double(l.half_u.x) * l.half_v.x + double(l.half_u.y) * l.half_v.y + double(l.half_u.z) * l.half_v.z) /
        (lu * lv);
    if (std::abs(cosine) > kAreaLightMaxEdgeCosine)
        throw InputError(what + "half_u " + text(l.half_u) + " and half_v " + text(l.half_v) +
                         " are not orthogonal (cosine " + std::to_string(cosine) + "; a rectangle needs 0)");
    for (int k = 0; k < 3; ++k)
        if (l.radiance[k] < 0.0f) throw InputError(what + "radiance " + text(l.radiance) + " is negative");
    for (int k = 0; k < 3; ++k)  // the bound every emitter has (ngi/material.hpp): the tracer's sums stay finite
        if (l.radiance[k] > kMaxEmission)
            throw InputError(what + "radiance " + text(l.radiance) + " exceeds the emission bound of " +
                             std::to_string(int(kMaxEmission)));
}

}  // namespace ngi
