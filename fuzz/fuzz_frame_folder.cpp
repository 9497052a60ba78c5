// Frame folders (host/src/io/frame_io.cpp read_frame): which files exist, EXR vs PNG, sizes and channel counts
// across faces, sanitizing, camera.json. The input edits a valid base folder (frame_folder_format.hpp) kept in one
// per-process folder under /dev/shm: before each input the files the previous input touched are restored. Edits
// may write EXR images of extreme values (NaN, +-Inf, +-FLT_MAX, +-65504, denormals, negative depth, ...); a frame
// that reads must then be finite everywhere, and its FrameReadStats must count, per file, exactly the NaN and Inf
// values of the image written there (alpha channels are dropped unread): a non-finite value that survives
// sanitizing, or a replacement the report does not count, is a crash.
#include <signal.h>
#include <unistd.h>

#include <cerrno>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>

#include "frame_folder_format.hpp"
#include "fuzz_common.hpp"
#include "base/file_util.hpp"
#include "ngi/image_io.hpp"

namespace fs = std::filesystem;

namespace {

struct State {
    fs::path dir;
    std::map<std::string, std::string> base;  // file name -> bytes of the base frame
    std::set<std::string> touched;            // changed by the previous input
};

void put(const fs::path& p, const std::string& bytes) {
    std::FILE* f = std::fopen(p.c_str(), "wb");
    if (!f || std::fwrite(bytes.data(), 1, bytes.size(), f) != bytes.size()) std::abort();
    std::fclose(f);
}

State& state() {
    static State* s = [] {
        auto* st = new State;
        const fs::path shm = "/dev/shm";
        st->dir = (fs::is_directory(shm) ? shm : fs::temp_directory_path()) /
                  ("ngi-fuzz-frame-" + std::to_string(::getpid()));
        // libFuzzer leaves without running atexit handlers when interrupted or crashing: remove the folders of
        // earlier runs whose process is gone.
        std::error_code ec;
        for (const auto& e : fs::directory_iterator(st->dir.parent_path(), ec)) {
            const std::string n = e.path().filename().string(), prefix = "ngi-fuzz-frame-";
            if (n.rfind(prefix, 0) == 0 && ::kill(std::atoi(n.c_str() + prefix.size()), 0) != 0 && errno == ESRCH)
                fs::remove_all(e.path(), ec);
        }
        fs::remove_all(st->dir);
        ngi::write_frame(st->dir.string(), ngi::fuzz::base_frame());
        for (const auto& e : fs::directory_iterator(st->dir))
            st->base[e.path().filename().string()] = ngi::detail::read_file(e.path().string());
        std::atexit([] { std::error_code ec; fs::remove_all(state().dir, ec); });
        return st;
    }();
    return *s;
}

// Channels of the feature a frame file holds ("front_depth.exr" -> 1); 3 for reference.exr and anything else.
int feature_channels_of(const std::string& name) {
    for (int fi = 0; fi < ngi::kFeatureCount; ++fi)
        for (int k = 0; k < ngi::kFaceCount; ++k)
            if (name.rfind(std::string(ngi::face_name(ngi::Face(k))) + "_" + ngi::feature_name(ngi::Feature(fi)) + ".", 0) == 0)
                return ngi::feature_channels(ngi::Feature(fi));
    return 3;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    State& st = state();
    for (const auto& name : st.touched) {  // back to the base frame
        auto it = st.base.find(name);
        if (it != st.base.end()) put(st.dir / name, it->second);
        else fs::remove(st.dir / name);
    }
    st.touched.clear();
    const auto& names = ngi::fuzz::frame_file_names();
    // File name -> NaN + Inf values an extreme record wrote there (in the channels read_frame keeps); erased when a
    // later record of the input replaces that file again.
    std::map<std::string, std::size_t> non_finite;
    for (std::size_t i = 0; i + 3 <= size;) {
        if (data[i] & 0x80) {  // an extreme record
            if (i + 4 > size) break;
            const std::string& name = names[(data[i] & 0x7f) % names.size()];
            const int channels = feature_channels_of(name);
            const ngi::fuzz::ExtremeImage e = ngi::fuzz::extreme_image(data[i + 1], data[i + 2], data[i + 3], channels);
            ngi::write_exr((st.dir / name).string(), e.image, e.half ? ngi::ExrPixelType::Half : ngi::ExrPixelType::Float);
            std::size_t n = 0;
            for (std::size_t k = 0; k < e.image.plane() * std::size_t(std::min(channels, e.image.channels)); ++k)
                n += !std::isfinite(e.image.data[k]);
            // An EXR under a .png name is never decoded as one: refused if the feature takes PNG, else not read at
            // all (normal, depth): no count to expect. camera.json likewise fails as JSON.
            if (name.ends_with(".exr")) non_finite[name] = n;
            else non_finite.erase(name);
            st.touched.insert(name);
            i += 4;
            continue;
        }
        const std::string& name = names[data[i] % names.size()];
        non_finite.erase(name);
        const std::size_t len = std::min<std::size_t>(data[i + 1] | std::size_t(data[i + 2]) << 8, size - i - 3);
        i += 3;
        if (len == 0) fs::remove(st.dir / name);
        else put(st.dir / name, std::string(reinterpret_cast<const char*>(data + i), len));
        st.touched.insert(name);
        i += len;
    }
    return ngi::fuzz::expect_ngi_errors_only([&] {
        ngi::FrameReadStats stats;
        const ngi::Frame f = ngi::read_frame(st.dir.string(), &stats);
        if (f.n < 1) __builtin_trap();
        // Sanitizing leaves every value finite ...
        auto finite = [](const ngi::Image& img) {
            for (float v : img.data)
                if (!std::isfinite(v)) return false;
            return true;
        };
        for (const auto& feature : f.faces)
            for (const ngi::Image& img : feature)
                if (!finite(img)) __builtin_trap();
        if (f.reference && !finite(*f.reference)) __builtin_trap();
        // ... and the report counts each file's replaced values: every file of the folder was read (else read_frame
        // would have refused it), so each extreme image's NaN and Inf values are in its entry, no more, no fewer.
        std::map<std::string, std::size_t> reported;
        for (const ngi::SanitizedFile& s : stats.sanitized) reported[s.file] += s.nan + s.inf;
        for (const auto& [name, n] : non_finite) {
            const auto it = reported.find(name);
            if ((it == reported.end() ? 0 : it->second) != n) __builtin_trap();
        }
    });
}
