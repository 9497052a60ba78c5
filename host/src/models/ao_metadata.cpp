// The "ao" object of an AO network's model file (models/ao_metadata.hpp).
#include "models/ao_metadata.hpp"

#include <cmath>

#include "models/float_field.hpp"
#include "ngi/error.hpp"

namespace ngi::detail {

AoMetadata parse_ao_metadata(const nlohmann::json& a, const std::string& what) {
    auto fail = [&](const std::string& why) { return InputError(what + why); };
    if (!a.is_object()) throw fail("no \"ao\" object in the metadata");
    if (!a.contains("neighbours") || !a["neighbours"].is_number_integer() ||
        a["neighbours"].get<long long>() != kAoNeighbours)
        throw fail("field 'ao.neighbours' must be 16");
    // float32-representable too: a radius of 1e-300 is 0 in float, the seed's "no neighbours" inference.
    if (!a.contains("radius_px") || !a["radius_px"].is_number() || !std::isfinite(a["radius_px"].get<double>()) ||
        a["radius_px"].get<double>() < 0 || a["radius_px"].get<double>() > 1024 ||
        !float32_representable(a["radius_px"].get<double>()))
        throw fail(std::string("field 'ao.radius_px' must be a number in 0..1024 ") + kFloat32Rule);
    if (!a.contains("at_size") || !a["at_size"].is_number_integer() || a["at_size"].get<long long>() < 1 ||
        a["at_size"].get<long long>() > 65536)
        throw fail("field 'ao.at_size' must be an integer in 1..65536");
    AoMetadata m;
    if (a.contains("normals")) {
        if (!a["normals"].is_string() || (a["normals"] != "smooth" && a["normals"] != "face"))
            throw fail("field 'ao.normals' must be \"smooth\" or \"face\"");
        m.normals = a["normals"].get<std::string>();
    }
    m.radius_px = a["radius_px"].get<float>();
    m.at_size = a["at_size"].get<int>();
    return m;
}

}  // namespace ngi::detail
