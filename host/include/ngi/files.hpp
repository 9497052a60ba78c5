// ngi's rules for reading and staging files, for an application that wants the guarantees of ngi's own readers and
// writers (the CLI uses them for its plan files and its preview image).
#pragma once
#include <cstdint>
#include <string>

namespace ngi {

// Largest file ngi reads: 4 GiB. Every file ngi reads (models, images, frames, configs) is far smaller (the
// thesis-sized generator is ~220 MB); the cap turns a wrong path or a runaway file into a clear error.
inline constexpr std::uint64_t kMaxInputFileBytes = std::uint64_t(4) << 30;

// The whole file, by ngi's one rule for opening inputs: only a regular file is read (a FIFO, a device such as
// /dev/zero or a directory is refused at once, never opened blocking), at most `max_bytes` and within the
// host-memory limit (ngi/host_memory.hpp). Throws InputError("<op> <path>: ...") naming why.
std::string read_input_file(const std::string& path, const std::string& op = "read",
                            std::uint64_t max_bytes = kMaxInputFileBytes);

// A name next to `path` that no other writer in any process uses ("<path>.tmp-<pid>-<n>", the last component
// shortened to stay within NAME_MAX): write there, then rename it to `path` for an all-or-nothing file.
std::string staging_name(const std::string& path);

}  // namespace ngi
