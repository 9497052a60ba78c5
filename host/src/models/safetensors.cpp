#include "models/safetensors.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include "io/half.hpp"
#include "ngi/error.hpp"
#include "ngi/tensor.hpp"

namespace ngi::detail {

SafetensorsFile read_safetensors(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw InputError("load model " + path + ": cannot open file");
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string what = "load model " + path + ": ";
    if (bytes.size() < 8) throw InputError(what + "file is " + std::to_string(bytes.size()) + " bytes, too short for a safetensors header");
    std::uint64_t header_len = 0;
    for (int i = 7; i >= 0; --i) header_len = header_len << 8 | static_cast<unsigned char>(bytes[i]);
    if (header_len > bytes.size() - 8)
        throw InputError(what + "header length " + std::to_string(header_len) + " runs beyond the end of the file (" +
                         std::to_string(bytes.size()) + " bytes): truncated or not a safetensors file");
    nlohmann::json header;
    try {
        header = nlohmann::json::parse(bytes.begin() + 8, bytes.begin() + 8 + std::ptrdiff_t(header_len));
    } catch (const nlohmann::json::exception& e) {
        throw InputError(what + "malformed JSON header: " + e.what());
    }
    if (!header.is_object()) throw InputError(what + "JSON header is not an object");
    const std::size_t data_start = 8 + header_len, data_size = bytes.size() - data_start;

    SafetensorsFile file;
    for (auto& [name, entry] : header.items()) {
        if (name == "__metadata__") {
            if (!entry.is_object()) throw InputError(what + "__metadata__ is not an object");
            for (auto& [k, v] : entry.items()) {
                if (!v.is_string()) throw InputError(what + "__metadata__." + k + " is not a string");
                file.metadata[k] = v.get<std::string>();
            }
            continue;
        }
        const std::string tw = what + "tensor '" + name + "': ";
        try {
            StoredTensor t;
            t.dtype = entry.at("dtype").get<std::string>();
            t.shape = entry.at("shape").get<std::vector<int>>();
            const auto offsets = entry.at("data_offsets").get<std::vector<std::uint64_t>>();
            std::size_t elem = t.dtype == "F32" ? 4 : t.dtype == "F16" ? 2 : 0;
            if (!elem) throw InputError(tw + "dtype " + t.dtype + " is not supported (F32 or F16)");
            for (int d : t.shape) if (d < 0) throw InputError(tw + "negative dimension in shape " + shape_string(t.shape));
            if (offsets.size() != 2 || offsets[1] < offsets[0])
                throw InputError(tw + "data_offsets must be [begin, end] with begin <= end");
            const std::size_t n = Tensor::element_count(t.shape);
            if (offsets[1] - offsets[0] != n * elem)
                throw InputError(tw + "data_offsets span " + std::to_string(offsets[1] - offsets[0]) + " bytes, shape " +
                                 shape_string(t.shape) + " of " + t.dtype + " needs " + std::to_string(n * elem));
            if (offsets[1] > data_size)
                throw InputError(tw + "data ends at byte " + std::to_string(offsets[1]) + " but the file has only " +
                                 std::to_string(data_size) + " data bytes: the file is truncated");
            const char* p = bytes.data() + data_start + offsets[0];
            t.data.resize(n);
            if (elem == 4) {
                std::memcpy(t.data.data(), p, n * 4);
            } else {
                for (std::size_t i = 0; i < n; ++i) {
                    std::uint16_t h;
                    std::memcpy(&h, p + 2 * i, 2);
                    t.data[i] = half_to_float(h);
                }
            }
            for (std::size_t i = 0; i < n; ++i)
                if (!std::isfinite(t.data[i]))
                    throw InputError(tw + "value " + std::to_string(i) + " is not finite (" + std::to_string(t.data[i]) +
                                     "): the weights are corrupt");
            file.tensors.emplace(name, std::move(t));
        } catch (const nlohmann::json::exception& e) {
            throw InputError(tw + "bad header entry: " + e.what());
        }
    }
    return file;
}

}  // namespace ngi::detail
