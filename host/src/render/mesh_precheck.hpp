// The cheap structural checks a mesh file passes before assimp parses it. Library-internal (mesh_io.cpp).
// Why: assimp allocates what a file claims (a PLY list of 4e9 indices, a glTF accessor of 1e9 elements with no
// data behind it, a node chain 10^5 deep it recurses through) before it finds out the data is not there. Each check
// here reads only sizes, counts and structure, in one pass over the bytes, and refuses a file whose claims exceed
// ngi's mesh limits (ngi/mesh.hpp) or the bytes actually present, so that what assimp then allocates is bounded by
// the input's size.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace ngi::detail {

// The bytes of a file a glTF names (an external buffer's `uri`, relative to the glTF file), kept alive by the
// caller (mesh_io.cpp hands the same bytes to assimp). Throws InputError when it may not or cannot be read
// (parse_mesh reads nothing but its own bytes).
using SidecarBytes = std::function<const std::string&(const std::string& uri)>;

// Checks `bytes` as the format of `ext` (".obj", ".ply", ".gltf", ".glb"). Throws InputError("load mesh <name>:
// ...") naming the element (a PLY element and its index, an OBJ line, a glTF accessor, buffer or node). Besides
// sizes, vertex indices are checked where assimp would not refuse them itself: OBJ's here in one pass, glTF's by
// reading the index accessors (assimp drops a glTF face with an index out of range, silently).
// What the precheck read that assimp does not give: per glTF material, its KHR_materials_emissive_strength (1 where
// it has none; assimp 5.2.5 ignores the extension).
struct MeshPrecheckFacts {
    std::vector<float> gltf_emissive_strength;
};

void precheck_mesh(const std::string& bytes, const std::string& name, const std::string& ext,
                   const SidecarBytes& sidecar, MeshPrecheckFacts* facts = nullptr);

// Checks the bytes of a material library an OBJ names (`mtllib`) before assimp reads them: a texture statement
// before the first `newmtl` is refused (assimp 5.2.5 writes it through a null material). Throws
// InputError("load mesh <mesh_name>: material library <file> line N: ...").
void precheck_material_library(const std::string& bytes, const std::string& mesh_name, const std::string& file);

}  // namespace ngi::detail
