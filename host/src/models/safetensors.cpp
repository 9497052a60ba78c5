#include "models/safetensors.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <climits>
#include <nlohmann/json.hpp>

#include "base/checked_size.hpp"
#include "base/half.hpp"
#include "base/file_util.hpp"
#include "ngi/error.hpp"
#include "ngi/tensor.hpp"

namespace ngi::detail {

SafetensorsFile read_safetensors(const std::string& path) {
    return parse_safetensors(read_file(path, "load model"), path);
}

SafetensorsFile parse_safetensors(const std::string& bytes, const std::string& path) {
    const std::string what = "load model " + path + ": ";
    if (bytes.size() < 8) throw InputError(what + "file is " + std::to_string(bytes.size()) + " bytes, too short for a safetensors header");
    std::uint64_t header_len = 0;
    for (int i = 7; i >= 0; --i) header_len = header_len << 8 | static_cast<unsigned char>(bytes[i]);
    if (header_len > bytes.size() - 8)
        throw InputError(what + "header length " + std::to_string(header_len) + " runs beyond the end of the file (" +
                         std::to_string(bytes.size()) + " bytes): truncated or not a safetensors file");
    // The format pads the header with spaces only (0x20). nlohmann's parser stops at a NUL as at the end of its
    // input, so NUL padding (or a NUL inside the header) used to pass: a file with bytes after its JSON that are
    // not whitespace is not what a safetensors writer produces.
    if (const void* nul = std::memchr(bytes.data() + 8, '\0', std::size_t(header_len)))
        throw InputError(what + "the JSON header holds a NUL byte at offset " +
                         std::to_string(static_cast<const char*>(nul) - bytes.data()) +
                         " (the header may be padded with spaces only): not a safetensors file");
    nlohmann::json header;
    try {
        header = nlohmann::json::parse(bytes.begin() + 8, bytes.begin() + 8 + std::ptrdiff_t(header_len));
    } catch (const nlohmann::json::exception& e) {
        throw InputError(what + "malformed JSON header: " + e.what());
    }
    if (!header.is_object()) throw InputError(what + "JSON header is not an object");
    const std::size_t data_start = 8 + header_len, data_size = bytes.size() - data_start;

    SafetensorsFile file;
    std::uint64_t data_end = 0;  // where the last tensor's data ends
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
            // Each dimension and offset is checked as a JSON integer in range before conversion: get<int> would
            // silently truncate 2^32 + 4 to 4, and get<uint64_t> would wrap -1 to 2^64 - 1.
            const nlohmann::json& shape = entry.at("shape");
            if (!shape.is_array()) throw InputError(tw + "shape must be an array of integers");
            for (const auto& d : shape) {
                if (!d.is_number_integer() || d.get<std::int64_t>() < 0 || d.get<std::int64_t>() > INT32_MAX ||
                    (d.is_number_unsigned() && d.get<std::uint64_t>() > std::uint64_t(INT32_MAX)))
                    throw InputError(tw + "shape " + shape.dump() + ": every dimension must be an integer in 0.." +
                                     std::to_string(INT32_MAX));
                t.shape.push_back(int(d.get<std::int64_t>()));
            }
            const nlohmann::json& off = entry.at("data_offsets");
            if (!off.is_array() || off.size() != 2 || !off[0].is_number_unsigned() || !off[1].is_number_unsigned())
                throw InputError(tw + "data_offsets must be [begin, end], two non-negative integers");
            const std::uint64_t offsets[2] = {off[0].get<std::uint64_t>(), off[1].get<std::uint64_t>()};
            std::size_t elem = t.dtype == "F32" ? 4 : t.dtype == "F16" ? 2 : 0;
            if (!elem) throw InputError(tw + "dtype " + t.dtype + " is not supported (F32 or F16)");
            if (offsets[1] < offsets[0]) throw InputError(tw + "data_offsets must be [begin, end] with begin <= end");
            if (offsets[1] > data_size)
                throw InputError(tw + "data ends at byte " + std::to_string(offsets[1]) + " but the file has only " +
                                 std::to_string(data_size) + " data bytes: the file is truncated");
            // Checked multiplication: a shape whose byte count overflows must not pass as a small span.
            const auto need = checked_byte_count(t.shape, elem, data_size);
            if (!need || offsets[1] - offsets[0] != *need)
                throw InputError(tw + "data_offsets span " + std::to_string(offsets[1] - offsets[0]) + " bytes, shape " +
                                 shape_string(t.shape) + " of " + t.dtype + " needs " +
                                 (need ? std::to_string(*need) : "more than the file's " + std::to_string(data_size)));
            data_end = std::max<std::uint64_t>(data_end, offsets[1]);
            const std::size_t n = std::size_t(*need / elem);
            const char* p = bytes.data() + data_start + offsets[0];
            t.data.resize(n);
            std::size_t bad = n;  // the first value that is not finite
            if (elem == 4) {
                std::memcpy(t.data.data(), p, n * 4);
                for (std::size_t i = 0; i < n && bad == n; ++i)
                    if (!std::isfinite(t.data[i])) bad = i;
            } else {
                bad = halves_to_floats(reinterpret_cast<const unsigned char*>(p), n, t.data.data());
            }
            if (bad < n)
                throw InputError(tw + "value " + std::to_string(bad) + " is not finite (" + std::to_string(t.data[bad]) +
                                 "): the weights are corrupt");
            file.tensors.emplace(name, std::move(t));
        } catch (const nlohmann::json::exception& e) {
            throw InputError(tw + "bad header entry: " + e.what());
        }
    }
    // The data buffer ends with the last tensor (the format: "entirely indexed"). Bytes after it were accepted
    // before: a file with something appended (a second file concatenated, a download that did not stop) is not
    // what its header describes.
    if (data_end != data_size)
        throw InputError(what + std::to_string(data_size - data_end) + " trailing bytes after the last tensor's data " +
                         "(the tensors end at data byte " + std::to_string(data_end) + " of " +
                         std::to_string(data_size) + "): not a safetensors file as written, or corrupted");
    return file;
}

}  // namespace ngi::detail
