// Frame folders (host/src/io/frame_io.cpp read_frame): which files exist, EXR vs PNG, sizes and channel counts
// across faces, sanitizing, camera.json. The input edits a valid base folder (frame_folder_format.hpp) kept in one
// per-process folder under /dev/shm: before each input the files the previous input touched are restored.
#include <signal.h>
#include <unistd.h>

#include <cerrno>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>

#include "frame_folder_format.hpp"
#include "fuzz_common.hpp"
#include "io/file_util.hpp"
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
    for (std::size_t i = 0; i + 3 <= size;) {
        const std::string& name = names[data[i] % names.size()];
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
    });
}
