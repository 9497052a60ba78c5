// libFuzzer target for the mesh loader (host/src/render/mesh_io.cpp and the one reader per format behind it:
// mesh_obj.cpp, mesh_ply.cpp, and mesh_gltf.cpp with tinygltf, whose header-only implementation is compiled into the
// instrumented library): the first byte picks the format (0 OBJ, 1 PLY, 2 glTF, 3 GLB: its value mod 4), the rest is
// the file. Runs parse_mesh, the same path as load_mesh after its file read (parse_mesh reads no other file: an OBJ's
// .mtl and a glTF's external buffers are not opened). ngi::Error (InputError for a bad file) is the expected outcome
// of most inputs; anything else -- a crash, a sanitizer report, std::bad_alloc, a hang, an allocation over
// -malloc_limit_mb -- is a bug, and so is a loaded mesh the renderer would refuse. Seeds: fuzz/corpus/mesh/
// (fuzz/make_mesh_seeds.py), dictionary: fuzz/mesh.dict.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz_common.hpp"
#include "ngi/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    ngi::fuzz::remember_input(data, size);
    if (size < 1) return 0;
    static const char* names[4] = {"fuzz.obj", "fuzz.ply", "fuzz.gltf", "fuzz.glb"};
    const std::string bytes = ngi::fuzz::bytes(data + 1, size - 1);
    return ngi::fuzz::expect_ngi_errors_only([&] {
        const ngi::LoadedMesh l = ngi::parse_mesh(bytes, names[data[0] % 4]);
        // What load_mesh returns must pass the renderer's own check, within the palette it promises.
        if (l.materials.empty() || l.materials.size() > 255) __builtin_trap();
        try {
            ngi::validate_mesh(l.mesh, l.materials.size() + 1, "fuzz");
        } catch (const ngi::Error&) {
            __builtin_trap();
        }
        for (const ngi::Material& m : l.materials)
            if (!(glm::all(glm::lessThanEqual(m.albedo, glm::vec3(0.95f))) &&
                  glm::all(glm::greaterThanEqual(m.albedo, glm::vec3(0.0f))) &&
                  glm::all(glm::greaterThanEqual(m.emission, glm::vec3(0.0f)))))
                __builtin_trap();
    });
}
