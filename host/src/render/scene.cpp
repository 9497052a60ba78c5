// VoxelScene basics and the scene spec strings of the CLI.
#include <algorithm>
#include <charconv>

#include "io/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/scene.hpp"

namespace ngi {

VoxelScene::VoxelScene(glm::ivec3 s, std::string n) : name(std::move(n)), size(s) {
    if (glm::any(glm::lessThan(s, glm::ivec3(1)))) throw Error("VoxelScene: size must be positive");
    voxels.assign(std::size_t(s.x) * s.y * s.z, 0);
    camera.region_lo = glm::vec3(0.0f);
    camera.region_hi = glm::vec3(s);
}

void VoxelScene::fill(glm::ivec3 lo, glm::ivec3 hi, std::uint8_t m) {
    lo = glm::max(lo, glm::ivec3(0));
    hi = glm::min(hi, size);
    for (int z = lo.z; z < hi.z; ++z)
        for (int y = lo.y; y < hi.y; ++y)
            for (int x = lo.x; x < hi.x; ++x) voxels[index({x, y, z})] = m;
}

std::uint8_t VoxelScene::add_material(const Material& m) {
    if (palette.size() >= std::size_t(kMaxMaterials))
        throw Error("scene " + name + ": more than " + std::to_string(kMaxMaterials - 1) + " materials");
    palette.push_back(m);
    return std::uint8_t(palette.size() - 1);
}

std::size_t VoxelScene::solid_count() const {
    return std::size_t(std::count_if(voxels.begin(), voxels.end(), [](std::uint8_t v) { return v != 0; }));
}

namespace {

bool has_vox_extension(const std::string& spec) {
    std::string lower = spec;
    std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return lower.size() > 4 && lower.compare(lower.size() - 4, 4, ".vox") == 0;
}

// "family[:seed=S]" -> (family, seed), validated.
std::pair<std::string, std::uint32_t> parse_family_spec(const std::string& spec) {
    const auto colon = spec.find(':');
    const std::string family = spec.substr(0, colon);
    const auto& families = scene_families();
    if (std::find(families.begin(), families.end(), family) == families.end()) {
        std::string list;
        for (const auto& f : families) list += (list.empty() ? "" : ", ") + f;
        throw InputError("scene '" + spec + "': unknown family '" + family + "' (" + list + ", or a .vox file)");
    }
    std::uint32_t seed = 0;
    if (colon == std::string::npos) return {family, seed};
    const std::string rest = spec.substr(colon + 1);
    for (std::size_t pos = 0; pos <= rest.size();) {
        const auto comma = std::min(rest.find(',', pos), rest.size());
        const std::string item = rest.substr(pos, comma - pos);
        const auto eq = item.find('=');
        const std::string key = item.substr(0, eq), value = eq == std::string::npos ? "" : item.substr(eq + 1);
        if (key != "seed") throw InputError("scene '" + spec + "': unknown option '" + key + "' (expected seed=N)");
        const auto r = std::from_chars(value.data(), value.data() + value.size(), seed);
        if (value.empty() || r.ec != std::errc() || r.ptr != value.data() + value.size())
            throw InputError("scene '" + spec + "': seed must be an unsigned 32-bit integer, got '" + value + "'");
        pos = comma + 1;
    }
    return {family, seed};
}

}  // namespace

std::string scene_spec_name(const std::string& spec) {
    if (has_vox_extension(spec)) return spec;
    const auto [family, seed] = parse_family_spec(spec);
    return family + ":seed=" + std::to_string(seed);
}

VoxelScene make_scene(const std::string& spec) {
    if (has_vox_extension(spec)) {
        detail::require_readable_file(spec);  // the .vox reader streams: a directory or device fails inside it
        return load_vox(spec);
    }
    const auto [family, seed] = parse_family_spec(spec);
    return generate_scene(family, seed);
}

}  // namespace ngi
