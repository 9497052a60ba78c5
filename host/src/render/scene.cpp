// VoxelScene basics and the scene spec strings of the CLI.
#include <algorithm>
#include <charconv>

#include "ngi/error.hpp"
#include "ngi/scene.hpp"
#include "render/mesh_scene.hpp"

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
    // Every loader's materials pass here (procedural, .vox, meshes): the one place the bound holds for all.
    for (int k = 0; k < 3; ++k)
        if (!(m.emission[k] >= 0.0f && m.emission[k] <= kMaxEmission))  // also false for NaN
            throw InputError("scene " + name + ": material " + std::to_string(palette.size()) + ": emission (" +
                             std::to_string(m.emission.r) + ", " + std::to_string(m.emission.g) + ", " +
                             std::to_string(m.emission.b) + ") is not in [0, " + std::to_string(int(kMaxEmission)) +
                             "] (the bound of ngi/material.hpp)");
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

struct FamilySpec {
    std::string family;
    std::uint32_t seed = 0;
    bool floor = false;  // mesh families: a floor of blocks under the object
};

// "family[:key=value,...]" -> FamilySpec, validated: seed=N for every family, floor=0|1 for the mesh families.
FamilySpec parse_family_spec(const std::string& spec) {
    const auto colon = spec.find(':');
    FamilySpec out;
    out.family = spec.substr(0, colon);
    const auto& families = scene_families();
    if (std::find(families.begin(), families.end(), out.family) == families.end()) {
        std::string list;
        for (const auto& f : families) list += (list.empty() ? "" : ", ") + f;
        throw InputError("scene '" + spec + "': unknown family '" + out.family + "' (" + list +
                         ", or a .vox or mesh file: .obj, .ply, .gltf, .glb)");
    }
    const bool mesh = detail::is_mesh_family(out.family);
    if (colon == std::string::npos) return out;
    const std::string rest = spec.substr(colon + 1);
    for (std::size_t pos = 0; pos <= rest.size();) {
        const auto comma = std::min(rest.find(',', pos), rest.size());
        const std::string item = rest.substr(pos, comma - pos);
        const auto eq = item.find('=');
        const std::string key = item.substr(0, eq), value = eq == std::string::npos ? "" : item.substr(eq + 1);
        if (key == "seed") {
            const auto r = std::from_chars(value.data(), value.data() + value.size(), out.seed);
            if (value.empty() || r.ec != std::errc() || r.ptr != value.data() + value.size())
                throw InputError("scene '" + spec + "': seed must be an unsigned 32-bit integer, got '" + value + "'");
        } else if (key == "floor" && mesh) {
            if (value != "0" && value != "1")
                throw InputError("scene '" + spec + "': floor must be 0 or 1, got '" + value + "'");
            out.floor = value == "1";
        } else {
            throw InputError("scene '" + spec + "': unknown option '" + key + "' (expected " +
                             (mesh ? "seed=N, floor=0|1)" : "seed=N)"));
        }
        pos = comma + 1;
    }
    return out;
}

std::string canonical_name(const FamilySpec& f) {
    return f.family + ":seed=" + std::to_string(f.seed) + (f.floor ? ",floor=1" : "");
}

}  // namespace

std::string scene_spec_name(const std::string& spec) {
    if (has_vox_extension(spec) || is_mesh_path(spec)) return spec;
    return canonical_name(parse_family_spec(spec));
}

VoxelScene make_scene(const std::string& spec) {
    if (has_vox_extension(spec)) return load_vox(spec);  // read_file's rule: regular files only, never blocks
    if (is_mesh_path(spec)) return detail::mesh_scene(load_mesh(spec), spec, false);
    const FamilySpec f = parse_family_spec(spec);
    if (detail::is_mesh_family(f.family))
        return detail::mesh_family_scene(f.family, f.seed, f.floor, canonical_name(f));
    return generate_scene(f.family, f.seed);
}

}  // namespace ngi
