// ngi::warm_up (ngi/warmup.hpp): one synthetic frame through the whole frame path, to fill the program caches.
#include "ngi/warmup.hpp"

#include <chrono>
#include <fstream>
#include <optional>
#include <system_error>
#include <unistd.h>

#include "ngi/display.hpp"
#include "ngi/error.hpp"
#include "ngi/pipeline.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "runtime/context.hpp"

namespace ngi {

namespace {

using Clock = std::chrono::steady_clock;

// A plausible frame: a wall 5 m ahead on every face, lit; every feature present (so emission and env programs
// are built too).
Frame synthetic_frame(int n) {
    Frame f;
    f.n = n;
    const float fill[kFeatureCount] = {0.5f, 0.0f, 5.0f, 1.0f, 0.0f, 0.1f};
    for (int fi = 0; fi < kFeatureCount; ++fi)
        for (int face = 0; face < kFaceCount; ++face) {
            Image im(n, n, feature_channels(Feature(fi)), fill[fi]);
            if (Feature(fi) == Feature::Normal)
                for (std::size_t i = 2 * im.plane(); i < 3 * im.plane(); ++i) im.data[i] = 1.0f;
            f.get(Feature(fi), Face(face)) = std::move(im);
        }
    return f;
}

// The cache folder must take a file: created if missing, a probe written and removed.
void check_cache_writable(const std::filesystem::path& dir) {
    std::error_code ec;
    std::filesystem::create_directories(dir, ec);
    if (ec) throw InputError("warm up: cannot create the program cache folder " + dir.string() + ": " + ec.message());
    const std::filesystem::path probe = dir / (".warmup-probe-" + std::to_string(::getpid()));
    bool ok = false;
    {
        std::ofstream out(probe, std::ios::binary);
        ok = out && out.write("ngi", 3) && out.flush();
    }
    std::filesystem::remove(probe, ec);
    if (!ok)
        throw InputError("warm up: the program cache folder " + dir.string() +
                         " is not writable (set NGI_CACHE_DIR to a folder this process may write)");
}

}  // namespace

std::filesystem::path program_cache_dir() { return detail::cache_dir(); }

WarmUpReport warm_up(const Device& device, Model& model, int n, int display_size) {
    const ModelConfig& c = model.config();
    // A frame rung: an SSGI rung (no network) or an image network; the pipeline's own checks (its input channels,
    // below) refuse an image network it cannot feed.
    if (c.has_network && c.input != ModelInput::image)
        throw InputError("warm up: model family '" + c.family + "' takes items, not images: it is not a frame rung "
                         "(an image generator or an ssgi rung); warm it up by running one of its own inputs");
    if (display_size < 0 || (display_size > 0 && display_size < n))
        throw InputError("warm up: display size " + std::to_string(display_size) + " is not 0 (none) or at least N = " +
                         std::to_string(n));
    const int faces = [&] {  // InputError for a network whose input the pipeline cannot make
        try {
            return detail::frame_faces(c);
        } catch (const InputError& e) {
            throw InputError(std::string("warm up: ") + e.what());
        }
    }();
    WarmUpReport r;
    const std::filesystem::path dir = program_cache_dir();
    r.cache_dir = dir.string();
    check_cache_writable(dir);

    detail::Context& ctx = detail::context_of(device);
    const detail::Context::ProgramCounts before = ctx.program_counts();
    SurroundPipeline pipeline(device, n);  // InputError for a face size it refuses
    const Frame frame = synthetic_frame(n);
    const std::vector<float> planes = pack_frame_planes(frame, faces);
    DeviceBuffer in = DeviceBuffer::allocate(device, planes.size() * sizeof(float));
    in.upload(planes.data(), in.bytes());
    const std::size_t out_bytes = 3 * std::size_t(n) * n * sizeof(float);
    FrameOutputs outs;
    outs.lightmap = DeviceBuffer::allocate(device, out_bytes);
    outs.final_image = DeviceBuffer::allocate(device, out_bytes);
    outs.display = DeviceBuffer::allocate(device, out_bytes);
    const FrameDesc desc = FrameDesc::of(frame, faces);

    std::optional<DisplayView> view;
    DeviceBuffer hi_in;
    FrameDesc hi_desc;
    FrameOutputs shown;
    if (display_size > 0) {
        const Frame hi = synthetic_frame(display_size);
        const std::vector<float> hi_planes = pack_frame_planes(hi, 1);
        hi_in = DeviceBuffer::allocate(device, hi_planes.size() * sizeof(float));
        hi_in.upload(hi_planes.data(), hi_in.bytes());
        hi_desc = FrameDesc::of(hi, 1);
        const std::size_t hi_bytes = 3 * std::size_t(display_size) * display_size * sizeof(float);
        shown.lightmap = DeviceBuffer::allocate(device, hi_bytes);
        shown.final_image = DeviceBuffer::allocate(device, hi_bytes);
        shown.display = DeviceBuffer::allocate(device, hi_bytes);
        view.emplace(device, display_size);
    }
    // Twice: the first frame builds (or loads) the programs, the second has the temporal pass's history to read. The
    // first asks for the preprocessing counters as well: an ssgi rung runs that kernel only then.
    for (double* ms : {&r.first_frame_ms, &r.second_frame_ms}) {
        const auto t0 = Clock::now();
        PreprocessStats stats;
        pipeline.enqueue(model, in, desc, outs, ms == &r.first_frame_ms ? &stats : nullptr);
        if (view) view->enqueue(n, in, outs.lightmap, hi_in, hi_desc, glm::vec3(0.0f), shown);
        device.finish();
        *ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    }
    const detail::Context::ProgramCounts after = ctx.program_counts();
    r.programs_built = after.built - before.built;
    r.programs_from_cache = after.from_cache - before.from_cache;
    return r;
}

}  // namespace ngi
