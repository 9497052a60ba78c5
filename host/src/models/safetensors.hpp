// Reader for the .safetensors format: u64 little-endian header length, JSON header, raw little-endian data.
// F32 and F16 tensors are returned as float32. Every structural problem is an InputError naming the file.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace ngi::detail {

struct StoredTensor {
    std::vector<int> shape;
    std::string dtype;        // as stored: "F32" or "F16"
    std::vector<float> data;  // converted to float32
};

struct SafetensorsFile {
    std::map<std::string, StoredTensor> tensors;
    std::map<std::string, std::string> metadata;  // __metadata__ (string -> string, per the format)
};

SafetensorsFile read_safetensors(const std::string& path);
// The same from the file's bytes; `path` only names the file in error messages.
SafetensorsFile parse_safetensors(const std::string& bytes, const std::string& path);

}  // namespace ngi::detail
