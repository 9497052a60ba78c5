// What a mesh file's reader hands to mesh_io.cpp: one reader per format (mesh_obj.cpp: OBJ + .mtl through
// tinyobjloader; mesh_ply.cpp: ngi's own PLY reader; mesh_gltf.cpp: glTF 2.0 / GLB through tinygltf), each the only
// parser of its format. A reader checks what its format states (indices in range, sizes against the bytes present,
// material values) and returns the file as parts, materials and instances; mesh_io.cpp triangulates, joins identical
// vertices, applies the instances' transforms, checks the limits and builds the LoadedMesh (ngi/mesh.hpp).
// Library-internal.
#pragma once
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace ngi::detail {

enum class MeshFormat { Obj, Ply, Gltf };

// A material as it colours its triangles, checked by its reader (finite, no negative component, emission within
// kMaxEmission after any strength). `has_colour` false: the file gives no colour of its own (vertex colours or
// ngi's default decide).
struct MeshMaterial {
    bool has_colour = false;
    glm::vec3 albedo{1.0f};    // linear
    glm::vec3 emission{0.0f};  // linear radiance
};

// One piece of a file within which identical vertices are joined: an OBJ's run of faces of one group and material,
// a PLY file, a glTF primitive. Vertices are as the file gives them (before any node transform); `normals`,
// `colours` and `texcoords` are empty or hold one entry per position. Colours: sRGB for OBJ and PLY, linear for
// glTF (mesh_io converts). Texture coordinates only keep apart vertices the file keeps apart (ngi reads no texture).
struct MeshPart {
    std::vector<glm::vec3> positions, normals, colours;
    std::vector<glm::vec2> texcoords;
    std::vector<std::uint32_t> corners;  // polygon after polygon, indices into positions (checked by the reader)
    std::vector<std::uint32_t> sizes;    // corners of each polygon, each >= 3
    std::size_t dropped_primitives = 0;  // points and line segments (no area)
    int material = -1;                   // index into MeshFile::materials; -1: the format's default
};

// A part placed in the scene: glTF's node tree flattened (one entry per node and primitive); OBJ and PLY place
// each part once, untransformed.
struct MeshInstance {
    std::size_t part = 0;
    glm::mat4 transform{1.0f};
};

struct MeshFile {
    MeshFormat format = MeshFormat::Obj;
    std::vector<MeshPart> parts;
    std::vector<MeshMaterial> materials;
    std::vector<MeshInstance> instances;
    MeshMaterial default_material;  // for parts with material -1
};

// The files a mesh names (an OBJ's material libraries, a glTF's external buffers), read by ngi's rule: regular files
// only, together with the mesh within kMaxMeshFileBytes. parse_mesh reads none (`enabled` false).
class MeshSidecars {
public:
    MeshSidecars(std::string mesh_name, bool enabled, std::uint64_t used)
        : mesh_name_(std::move(mesh_name)), enabled_(enabled), used_(used) {}
    bool enabled() const { return enabled_; }
    // The bytes of `path`, read once; throws InputError naming the mesh for a path that is not a readable regular
    // file or that would take the files past kMaxMeshFileBytes.
    const std::string& read(const std::string& path);

private:
    std::string mesh_name_;
    bool enabled_;
    std::uint64_t used_;
    std::map<std::string, std::string> files_;  // node-based: stable references
};

// "load mesh <name>: <what>" as an InputError.
[[noreturn]] void mesh_fail(const std::string& name, const std::string& what);
// A number as %g.
std::string mesh_number(double v);
// `s` for an error message: control characters and bytes beyond ASCII as \xNN, at most 40 characters.
std::string mesh_printable(const std::string& s);
// Checks a material's colour components (finite, >= 0) and its emission x strength against kMaxEmission, naming
// `where` ("material 'red'", "glTF material 0"); returns the emission times the strength.
glm::vec3 checked_emission(const std::string& name, const std::string& where, glm::vec3 emission, double strength);
void check_colour(const std::string& name, const std::string& what, glm::vec3 c);

// The readers. `bytes` is the whole file, `name` stands for it in errors.
MeshFile read_obj(const std::string& bytes, const std::string& name, MeshSidecars& sidecars);
MeshFile read_ply(const std::string& bytes, const std::string& name);
MeshFile read_gltf(const std::string& bytes, const std::string& name, bool binary, MeshSidecars& sidecars);

}  // namespace ngi::detail
