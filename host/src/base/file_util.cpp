#include "base/file_util.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <new>

#include "ngi/error.hpp"
#include "ngi/files.hpp"
#include "ngi/host_memory.hpp"

namespace ngi::detail {

namespace {

// What a file that is not regular is, for the messages of require_readable_file and read_file.
const char* not_regular_kind(mode_t mode) {
    return S_ISDIR(mode)                   ? "it is a directory"
           : S_ISCHR(mode) || S_ISBLK(mode) ? "it is a device, not a regular file"
           : S_ISFIFO(mode)                 ? "it is a FIFO, not a regular file"
           : S_ISSOCK(mode)                 ? "it is a socket, not a regular file"
                                            : "not a regular file";
}

}  // namespace

void require_readable_file(const std::string& path, const std::string& op) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return;  // absent (or unreachable): the reader's open says why
    if (!S_ISREG(st.st_mode)) throw InputError(op + " " + path + ": cannot open file: " + not_regular_kind(st.st_mode));
}

std::string read_file(const std::string& path, const std::string& op, std::uint64_t max_bytes) {
    const std::string what = op + " " + path + ": ";
    require_readable_file(path, op);  // by stat, before opening anything: no open() of a device or FIFO at all
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer. It changes nothing for the regular
    // files that pass the check below. fstat on the open descriptor (not a stat of the path before opening), so the
    // check and the read see the same file. Only regular files: a directory opens but cannot be read, and
    // /dev/zero or a FIFO never end.
    const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) throw InputError(what + "cannot open file: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        const char* kind = not_regular_kind(st.st_mode);
        ::close(fd);
        throw InputError(what + "cannot open file: " + kind);
    }
    std::FILE* f = ::fdopen(fd, "rb");
    if (!f) {
        const int err = errno;
        ::close(fd);
        throw InputError(what + "cannot open file: " + std::strerror(err));
    }
    auto too_big = [&](std::uint64_t n) {
        return InputError(what + "file is larger (" + std::to_string(n) + " bytes) than the limit of " +
                          std::to_string(max_bytes) + " bytes");
    };
    if (std::uint64_t(st.st_size) > max_bytes) {
        std::fclose(f);
        throw too_big(std::uint64_t(st.st_size));
    }
    try {
        check_host_memory(op + " " + path, std::uint64_t(st.st_size));
    } catch (...) {
        std::fclose(f);
        throw;
    }
    std::string bytes;
    char chunk[1 << 16];
    std::size_t n = 0;
    // The size is checked again while reading: the file may grow after fstat.
    try {
        bytes.reserve(std::size_t(st.st_size));
        while ((n = std::fread(chunk, 1, sizeof chunk, f)) > 0) {
            if (bytes.size() + n > max_bytes) {
                std::fclose(f);
                throw too_big(bytes.size() + n);
            }
            bytes.append(chunk, n);
        }
    } catch (const std::bad_alloc&) {  // a file larger than this machine's memory
        std::fclose(f);
        throw InputError(what + "the file does not fit in memory (" + std::to_string(st.st_size) + " bytes)");
    }
    const bool failed = std::ferror(f) != 0;
    const int err = errno;
    std::fclose(f);
    if (failed) throw InputError(what + "read error: " + std::strerror(err));
    return bytes;
}

std::string temp_name(const std::string& path) {
    static std::atomic<unsigned> counter{0};
    const std::string suffix = ".tmp-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
    // A file name has at most NAME_MAX (255) bytes: an output named with 241..255 bytes is valid, but its staging
    // name with the suffix was not (ENAMETOOLONG, the command failed). The last component is shortened instead;
    // the pid and counter keep the name unique, ".tmp-" keeps it recognizable as a leftover.
    const std::size_t slash = path.find_last_of('/');
    const std::size_t base = slash == std::string::npos ? 0 : slash + 1;
    std::size_t keep = path.size() - base;
    if (keep + suffix.size() > std::size_t(NAME_MAX)) {
        keep = std::size_t(NAME_MAX) - suffix.size();
        // Not inside a UTF-8 sequence: back up over continuation bytes (10xxxxxx) to a character's first byte.
        while (keep > 0 && (static_cast<unsigned char>(path[base + keep]) & 0xc0) == 0x80) --keep;
    }
    return path.substr(0, base + keep) + suffix;
}

void write_file_atomic(const std::string& path, const std::string& bytes) {
    {
        // The rename would replace whatever is there: never a folder, a device (/dev/null, /dev/full) or a fifo.
        std::error_code ec;
        const auto st = std::filesystem::status(path, ec);
        if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
            throw InputError("write " + path + ": exists and is not a regular file; refusing to replace it");
    }
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

namespace ngi {

std::string read_input_file(const std::string& path, const std::string& op, std::uint64_t max_bytes) {
    return detail::read_file(path, op, max_bytes);
}

std::string staging_name(const std::string& path) { return detail::temp_name(path); }

}  // namespace ngi
