// Whole-file reads and crash-safe whole-file writes, shared by the image readers and writers. Library-internal;
// applications get read_file and temp_name as ngi::read_input_file and ngi::staging_name (ngi/files.hpp).
#pragma once
#include <cstdint>
#include <string>

#include "ngi/files.hpp"

namespace ngi::detail {

// ngi's one rule for opening an input file: only a regular file is read. Throws InputError("<op> <path>: cannot
// open file: it is a directory / a device / a FIFO / not a regular file") for anything else that exists, judged
// by stat(), which never blocks: a FIFO would block an open() forever waiting for a writer, a device such as
// /dev/zero never ends, a directory opens but cannot be read. Absent files pass: the reader's own open reports them.
// read_file applies the same rule to the descriptor it opened (O_NONBLOCK, fstat), so a file swapped for a FIFO
// between the two checks cannot block either. A reader that hands a path to a library (OpenEXR) calls
// this first.
void require_readable_file(const std::string& path, const std::string& op = "read");

// Largest file read_file accepts (ngi/files.hpp, the one definition).
inline constexpr std::uint64_t kMaxFileBytes = kMaxInputFileBytes;

// The whole file. Throws InputError("<op> <path>: ...") when it cannot be read, is not a regular file (a
// directory, a FIFO, a device such as /dev/zero) or is larger than max_bytes or the host-memory limit
// (ngi/host_memory.hpp). `op` is the message's verb ("read", "load model", "dataset config").
std::string read_file(const std::string& path, const std::string& op = "read", std::uint64_t max_bytes = kMaxFileBytes);

// A name next to `path` that no other writer in any process uses: "<path>.tmp-<pid>-<n>", with the last component
// of <path> shortened so that the name stays within NAME_MAX (255 bytes) however long `path`'s own name is.
std::string temp_name(const std::string& path);

// Writes `bytes` to temp_name(path), then renames it to `path` (atomic on POSIX within one file system).
// On any failure the temporary is removed and InputError("write <path>: ...") is thrown.
void write_file_atomic(const std::string& path, const std::string& bytes);

// Lower-case extension including the dot: ".exr" for "a/B.EXR", "" when there is none.
std::string lower_extension(const std::string& path);

}  // namespace ngi::detail
