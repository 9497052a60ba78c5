// libFuzzer target for the MagicaVoxel .vox loader (host/src/render/vox.cpp) and, with NGI_FUZZ_VOX_CAMERA=1, the
// host-side scene preparation the renderer runs next: the input bytes are a .vox file. With that variable a file
// that loads goes on to the default camera path of `ngi render` / a dataset (make_camera_path, "auto" = the orbit
// around the model for a .vox scene; scenes up to 256 blocks per axis), which needs no OpenCL device. ngi::Error (InputError for a bad file, or a scene with no room for the camera) is the expected
// outcome of most inputs; anything else -- a crash, a sanitizer report, std::bad_alloc, a hang, memory past
// -rss_limit_mb -- is a bug, and so is a loaded scene over budget, a bad palette index or a non-finite camera.
// Mutations are structure-aware (fuzz/vox_mutator.hpp: chunk-level edits that keep the file well-formed, plus
// libFuzzer's byte mutations for a share of them). Seeds: fuzz/corpus/vox/ (fuzz/make_vox_seeds.py), dictionary:
// fuzz/vox.dict. Run e.g.
//   fuzz_vox -runs=1000000 -rss_limit_mb=2048 -timeout=10 -max_len=65536 -dict=fuzz/vox.dict WORK fuzz/corpus/vox
// NGI_FUZZ_VOX_STATS=1 prints at exit how many inputs reached each stage (parsed into a scene, camera placed) and
// the most common refusals: the measure of the mutator's reach in docs/RELIABILITY.md. Compiled with -DNGI_VOX_BYTE_MUTATIONS_ONLY, the target
// has no custom mutator (libFuzzer's default byte mutations: the baseline of that measurement).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "ngi/camera_path.hpp"
#include "ngi/error.hpp"
#include "ngi/scene.hpp"
#include "vox_mutator.hpp"

namespace {

struct Stats {
    bool on = false;
    bool camera = false;  // NGI_FUZZ_VOX_CAMERA: also run the camera path
    unsigned long long inputs = 0, scenes = 0, cameras = 0;
    std::map<std::string, unsigned long long> errors;  // refusal message without its numbers -> inputs
};

Stats& stats() {
    static Stats* s = [] {
        auto* st = new Stats;
        st->on = std::getenv("NGI_FUZZ_VOX_STATS") != nullptr;
        st->camera = std::getenv("NGI_FUZZ_VOX_CAMERA") != nullptr;
        if (st->on)
            std::atexit([] {
                const Stats& t = stats();
                std::fprintf(stderr, "fuzz_vox stats: inputs %llu, loaded into a scene %llu (%.1f %%), camera placed %llu (%.1f %%)\n",
                             t.inputs, t.scenes, t.inputs ? 100.0 * double(t.scenes) / double(t.inputs) : 0.0,
                             t.cameras, t.inputs ? 100.0 * double(t.cameras) / double(t.inputs) : 0.0);
                std::vector<std::pair<unsigned long long, std::string>> top;
                for (const auto& [what, n] : t.errors) top.emplace_back(n, what);
                std::sort(top.rbegin(), top.rend());
                for (std::size_t i = 0; i < top.size() && i < 12; ++i)
                    std::fprintf(stderr, "fuzz_vox stats: %8llu  %s\n", top[i].first, top[i].second.c_str());
            });
        return st;
    }();
    return *s;
}

bool finite(glm::vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

}  // namespace

#ifndef NGI_VOX_BYTE_MUTATIONS_ONLY
extern "C" std::size_t LLVMFuzzerCustomMutator(std::uint8_t* data, std::size_t size, std::size_t max_size,
                                               unsigned int seed) {
    return ngi::fuzz::vox::mutate(data, size, max_size, seed);
}

extern "C" std::size_t LLVMFuzzerCustomCrossOver(const std::uint8_t* data1, std::size_t size1,
                                                 const std::uint8_t* data2, std::size_t size2, std::uint8_t* out,
                                                 std::size_t max_out_size, unsigned int seed) {
    return ngi::fuzz::vox::cross_over(data1, size1, data2, size2, out, max_out_size, seed);
}
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    Stats& st = stats();
    ++st.inputs;
    const std::string bytes(reinterpret_cast<const char*>(data), size);
    try {
        const ngi::VoxelScene s = ngi::parse_vox(bytes, "fuzz.vox");
        // A loaded scene must be one the renderer takes: within the budgets, every block a valid palette index.
        if (glm::any(glm::greaterThan(s.size, glm::ivec3(ngi::kMaxVoxAxis))) || s.voxels.size() > ngi::kMaxVoxBlocks ||
            s.voxels.size() != std::size_t(s.size.x) * s.size.y * s.size.z)
            __builtin_trap();
        for (std::uint8_t v : s.voxels)
            if (v >= s.palette.size()) __builtin_trap();
        for (const ngi::Material& m : s.palette)
            if (!finite(m.albedo) || !finite(m.emission)) __builtin_trap();
        ++st.scenes;
        // With NGI_FUZZ_VOX_CAMERA set: the renderer's default camera for this scene (one frame of `ngi render`:
        // two keyframes). Every pose of the path must be finite: a NaN camera renders a black frame without an
        // error. Opt-in because it is the slow part: ~27 ms per loaded scene under ASan (up to 8 orbit attempts of
        // ~15,000 rays each), which takes the target from ~150 to ~50 inputs/s on structure-mutated inputs (measured
        // on a 596-input corpus: 3.9 s of CPU without it, 12.1 s with it), below the ~200/s a default fuzz stage
        // wants. Only for scenes up to kCameraAxis blocks per axis: the orbit's cost also grows with the grid
        // (a full scan, rays of up to X + Y + Z cells); the path search is the same code at every size.
        constexpr int kCameraAxis = 256;
        if (!st.camera || glm::any(glm::greaterThan(s.size, glm::ivec3(kCameraAxis)))) return 0;
        const ngi::CameraPath path = ngi::make_camera_path(s, ngi::CameraPathKind::Auto, 1, 0u);
        if (path.keys.size() < 2) __builtin_trap();
        for (int f = 0; f < path.frame_count(); ++f) {
            const ngi::CameraPose p = path.at(float(f));
            if (!finite(p.position) || !finite(p.look) || !finite(p.up)) __builtin_trap();
        }
        ++st.cameras;
    } catch (const ngi::Error& e) {
        // a clean refusal
        if (st.on) {
            std::string what;
            for (const char* c = e.what(); *c && what.size() < 90; ++c)
                if (!(*c >= '0' && *c <= '9') && *c != '-') what += *c;
            ++st.errors[what];
        }
    }
    return 0;
}
