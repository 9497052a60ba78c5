#include "io/file_util.hpp"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "ngi/error.hpp"

namespace ngi::detail {

std::string read_file(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec))
        throw InputError("read " + path + ": cannot open file: it is a directory");
    std::FILE* f = std::fopen(path.c_str(), "rb");
    if (!f) throw InputError("read " + path + ": cannot open file: " + std::strerror(errno));
    std::string bytes;
    char chunk[1 << 16];
    std::size_t n = 0;
    while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0) bytes.append(chunk, n);
    const bool failed = std::ferror(f) != 0;
    const int err = errno;
    std::fclose(f);
    if (failed) throw InputError("read " + path + ": read error: " + std::strerror(err));
    return bytes;
}

std::string temp_name(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    return path + ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
}

void write_file_atomic(const std::string& path, const std::string& bytes) {
    const std::string tmp = temp_name(path);
    std::FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw InputError("write " + path + ": cannot create file: " + std::strerror(errno));
    // fclose flushes, so its result counts too: a full disk often shows up only there.
    bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
    int err = ok ? 0 : errno;
    if (std::fclose(f) != 0 && ok) { ok = false; err = errno; }
    std::error_code ec;
    if (!ok) {
        std::filesystem::remove(tmp, ec);
        throw InputError("write " + path + ": write failed: " + std::strerror(err));
    }
    std::filesystem::rename(tmp, path, ec);
    if (ec) {
        const std::string reason = ec.message();
        std::filesystem::remove(tmp, ec);
        throw InputError("write " + path + ": cannot move the finished file into place: " + reason);
    }
}

std::string lower_extension(const std::string& path) {
    std::string ext = std::filesystem::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

}  // namespace ngi::detail
