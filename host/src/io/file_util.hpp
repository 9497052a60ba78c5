// Whole-file reads and crash-safe whole-file writes, shared by the image readers and writers. Library-internal.
#pragma once
#include <string>

namespace ngi::detail {

// Throws InputError("read <path>: cannot open file: it is a directory / a device") for paths that a std::ifstream
// would open and then fail on with a std::ios_base::failure or read forever (/dev/zero). Absent files pass: the
// reader's own open reports them.
void require_readable_file(const std::string& path);

// The whole file (require_readable_file first; a file larger than memory is an InputError, not a bad_alloc). Throws InputError("read <path>: cannot open file: <reason>") when it cannot be read.
std::string read_file(const std::string& path);

// A name next to `path` that no other writer in any process uses: "<path>.tmp-<pid>-<n>".
std::string temp_name(const std::string& path);

// Writes `bytes` to temp_name(path), then renames it to `path` (atomic on POSIX within one file system).
// On any failure the temporary is removed and InputError("write <path>: ...") is thrown.
void write_file_atomic(const std::string& path, const std::string& bytes);

// Lower-case extension including the dot: ".exr" for "a/B.EXR", "" when there is none.
std::string lower_extension(const std::string& path);

}  // namespace ngi::detail
