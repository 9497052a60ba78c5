#include <cstdint>
#include <cstring>
#include <regex>

#include "io/file_util.hpp"
#include "io/half.hpp"
#include "ngi/error.hpp"
#include "ngi/tensor.hpp"

namespace ngi {

std::string shape_string(const std::vector<int>& shape) {
    std::string s = "[";
    for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + "]";
}

Tensor read_npy(const std::string& path) {
    const std::string bytes = detail::read_file(path);
    const std::string what = "read " + path + ": ";
    if (bytes.size() < 10 || bytes.compare(0, 6, "\x93NUMPY") != 0) throw InputError(what + "not a .npy file");
    const int major = static_cast<unsigned char>(bytes[6]);
    std::size_t header_len = 0, pos = 0;
    if (major == 1) {
        header_len = static_cast<unsigned char>(bytes[8]) | static_cast<unsigned char>(bytes[9]) << 8;
        pos = 10;
    } else if (major == 2 || major == 3) {
        if (bytes.size() < 12) throw InputError(what + "truncated header");
        std::uint32_t l = 0;
        std::memcpy(&l, bytes.data() + 8, 4);
        header_len = l;
        pos = 12;
    } else {
        throw InputError(what + "unsupported .npy version " + std::to_string(major));
    }
    if (pos + header_len > bytes.size()) throw InputError(what + "header length beyond the end of the file");
    const std::string header = bytes.substr(pos, header_len);
    pos += header_len;

    std::smatch m;
    if (!std::regex_search(header, m, std::regex("'descr':\\s*'([^']*)'")))
        throw InputError(what + "header has no 'descr'");
    const std::string descr = m[1];
    if (std::regex_search(header, m, std::regex("'fortran_order':\\s*(True|False)")) && m[1] == "True")
        throw InputError(what + "Fortran-ordered arrays are not supported; save with np.ascontiguousarray");
    if (!std::regex_search(header, m, std::regex("'shape':\\s*\\(([^)]*)\\)")))
        throw InputError(what + "header has no 'shape'");
    Tensor t;
    const std::string dims = m[1];
    const std::regex number("\\d+");
    for (std::sregex_iterator it(dims.begin(), dims.end(), number), end; it != end; ++it)
        t.shape.push_back(std::stoi(it->str()));
    const std::size_t n = Tensor::element_count(t.shape);
    std::size_t elem = 0;
    if (descr == "<f4" || descr == "|f4") elem = 4;
    else if (descr == "<f8") elem = 8;
    else if (descr == "<f2") elem = 2;
    else throw InputError(what + "dtype '" + descr + "' is not supported (use float32 little-endian, '<f4')");
    if (bytes.size() - pos < n * elem)
        throw InputError(what + "truncated: shape " + shape_string(t.shape) + " needs " + std::to_string(n * elem) +
                         " data bytes, the file has " + std::to_string(bytes.size() - pos));
    t.data.resize(n);
    const char* p = bytes.data() + pos;
    for (std::size_t i = 0; i < n; ++i) {
        if (elem == 4) std::memcpy(&t.data[i], p + 4 * i, 4);
        else if (elem == 8) { double d; std::memcpy(&d, p + 8 * i, 8); t.data[i] = float(d); }
        else { std::uint16_t h; std::memcpy(&h, p + 2 * i, 2); t.data[i] = detail::half_to_float(h); }
    }
    return t;
}

void write_npy(const std::string& path, const Tensor& t) {
    if (Tensor::element_count(t.shape) != t.data.size())
        throw InputError("write " + path + ": tensor shape " + shape_string(t.shape) + " does not match its " +
                         std::to_string(t.data.size()) + " values");
    std::string dims;
    for (int d : t.shape) dims += std::to_string(d) + ", ";
    if (t.shape.size() > 1) dims.erase(dims.size() - 2);  // "(3,)" for 1-D, "(1, 3)" otherwise
    else if (!t.shape.empty()) dims.pop_back();
    std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + dims + "), }";
    // Pad so the data starts at a multiple of 64 bytes (numpy's own convention), ending with '\n'.
    const std::size_t total = (10 + header.size() + 1 + 63) / 64 * 64;
    header.append(total - 10 - header.size() - 1, ' ');
    header += '\n';
    std::string bytes("\x93NUMPY\x01\x00", 8);  // magic + version 1.0 (explicit length: it contains a NUL)
    bytes += char(header.size() & 0xff);
    bytes += char((header.size() >> 8) & 0xff);
    bytes += header;
    bytes.append(reinterpret_cast<const char*>(t.data.data()), t.data.size() * sizeof(float));
    detail::write_file_atomic(path, bytes);  // unique temporary + rename: no partial file, no writer collisions
}

}  // namespace ngi
