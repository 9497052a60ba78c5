// libFuzzer target for the MagicaVoxel .vox loader (host/src/render/vox.cpp): the input bytes are a .vox file.
// ngi::Error (InputError for a bad file) is the expected outcome of most inputs; anything else -- a crash, a
// sanitizer report, std::bad_alloc, a hang, memory past -rss_limit_mb -- is a bug. Seeds: fuzz/corpus/vox/
// (fuzz/make_vox_seeds.py), dictionary: fuzz/vox.dict. Run e.g.
//   fuzz_vox -runs=1000000 -rss_limit_mb=2048 -timeout=10 -max_len=65536 -dict=fuzz/vox.dict WORK fuzz/corpus/vox
#include <cstddef>
#include <cstdint>
#include <string>

#include "ngi/error.hpp"
#include "ngi/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    try {
        const ngi::VoxelScene s = ngi::parse_vox(bytes, "fuzz.vox");
        // A loaded scene must be one the renderer takes: within the budgets, every block a valid palette index.
        if (glm::any(glm::greaterThan(s.size, glm::ivec3(ngi::kMaxVoxAxis))) || s.voxels.size() > ngi::kMaxVoxBlocks ||
            s.voxels.size() != std::size_t(s.size.x) * s.size.y * s.size.z)
            __builtin_trap();
        for (std::uint8_t v : s.voxels)
            if (v >= s.palette.size()) __builtin_trap();
    } catch (const ngi::Error&) {
        // a clean refusal
    }
    return 0;
}
