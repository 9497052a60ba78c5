#include <cctype>
#include <charconv>
#include <climits>
#include <cstdint>
#include <cstring>

#include "base/checked_size.hpp"
#include "base/half.hpp"
#include "base/file_util.hpp"
#include "base/npy.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/tensor.hpp"

namespace ngi {

std::string shape_string(const std::vector<int>& shape) {
    std::string s = "[";
    for (std::size_t i = 0; i < shape.size(); ++i) s += (i ? ", " : "") + std::to_string(shape[i]);
    return s + "]";
}

namespace {

// The header is a Python dict literal, e.g. {'descr': '<f4', 'fortran_order': False, 'shape': (1, 3, 64, 64), }.
// A small strict parser (not a regex: libstdc++'s std::regex recurses per character and overflows the stack on
// long headers) that accepts exactly the literals numpy writes: quoted strings, True/False and tuples of
// non-negative integers.
struct NpyHeader {
    std::string descr;
    bool fortran_order = false;
    std::vector<int> shape;
    bool has_descr = false, has_shape = false;
};

NpyHeader parse_npy_header(const std::string& h, const std::string& what) {
    std::size_t i = 0;
    auto fail = [&](const std::string& why) -> void {
        throw InputError(what + "malformed header at byte " + std::to_string(i) + ": " + why);
    };
    auto ws = [&] { while (i < h.size() && std::isspace(static_cast<unsigned char>(h[i]))) ++i; };
    auto expect = [&](char c) {
        ws();
        if (i >= h.size() || h[i] != c) fail(std::string("expected '") + c + "'");
        ++i;
    };
    auto peek = [&](char c) { ws(); return i < h.size() && h[i] == c; };
    auto string = [&] {
        ws();
        if (i >= h.size() || (h[i] != '\'' && h[i] != '"')) fail("expected a quoted string");
        const char q = h[i++];
        const std::size_t end = h.find(q, i);
        if (end == std::string::npos) fail("unterminated string");
        std::string s = h.substr(i, end - i);
        i = end + 1;
        return s;
    };
    NpyHeader r;
    expect('{');
    while (!peek('}')) {
        const std::string key = string();
        expect(':');
        ws();
        if (key == "descr") {
            r.descr = string();
            r.has_descr = true;
        } else if (key == "fortran_order") {
            if (h.compare(i, 4, "True") == 0) { r.fortran_order = true; i += 4; }
            else if (h.compare(i, 5, "False") == 0) { r.fortran_order = false; i += 5; }
            else fail("'fortran_order' must be True or False");
        } else if (key == "shape") {
            expect('(');
            r.shape.clear();
            while (!peek(')')) {
                ws();
                long long v = 0;
                const auto res = std::from_chars(h.data() + i, h.data() + h.size(), v);
                if (res.ec == std::errc::result_out_of_range || (res.ec == std::errc() && (v < 0 || v > INT32_MAX)))
                    fail("shape dimension " + std::string(h.data() + i, res.ptr) + " is not in 0.." +
                         std::to_string(INT32_MAX));
                if (res.ec != std::errc()) fail("shape must be a tuple of non-negative integers");
                i = std::size_t(res.ptr - h.data());
                r.shape.push_back(int(v));
                if (r.shape.size() > 32) fail("shape has more than 32 dimensions");
                if (!peek(',')) break;
                ++i;
            }
            expect(')');
            r.has_shape = true;
        } else {
            fail("unknown key '" + key + "'");
        }
        if (!peek(',')) break;
        ++i;
    }
    expect('}');
    return r;
}

}  // namespace

Tensor read_npy(const std::string& path) { return detail::decode_npy(detail::read_file(path), path); }

namespace detail {

Tensor decode_npy(const std::string& bytes, const std::string& path) {
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
    if (header_len > bytes.size() - pos) throw InputError(what + "header length beyond the end of the file");
    const NpyHeader header = parse_npy_header(bytes.substr(pos, header_len), what);
    pos += header_len;

    if (!header.has_descr) throw InputError(what + "header has no 'descr'");
    if (header.fortran_order)
        throw InputError(what + "Fortran-ordered arrays are not supported; save with np.ascontiguousarray");
    if (!header.has_shape) throw InputError(what + "header has no 'shape'");
    const std::string& descr = header.descr;
    std::size_t elem = 0;
    if (descr == "<f4" || descr == "|f4") elem = 4;
    else if (descr == "<f8") elem = 8;
    else if (descr == "<f2") elem = 2;
    else throw InputError(what + "dtype '" + descr + "' is not supported (use float32 little-endian, '<f4')");
    Tensor t;
    t.shape = header.shape;
    const std::size_t available = bytes.size() - pos;
    const auto need = checked_byte_count(t.shape, elem, available);
    if (!need)
        throw InputError(what + "truncated: shape " + shape_string(t.shape) + " of " + std::to_string(elem) +
                         "-byte values needs more data bytes than the file's " + std::to_string(available));
    const std::size_t n = std::size_t(*need / elem);
    // The file's bytes and the float32 values are held at once (a float64 file decodes to half its size, a
    // float16 file to twice).
    check_host_memory("read " + path, std::uint64_t(bytes.size()) + std::uint64_t(n) * sizeof(float));
    t.data.resize(n);
    const char* p = bytes.data() + pos;
    for (std::size_t i = 0; i < n; ++i) {
        if (elem == 4) std::memcpy(&t.data[i], p + 4 * i, 4);
        else if (elem == 8) { double d; std::memcpy(&d, p + 8 * i, 8); t.data[i] = float(d); }
        else { std::uint16_t h; std::memcpy(&h, p + 2 * i, 2); t.data[i] = detail::half_to_float(h); }
    }
    return t;
}

}  // namespace detail

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
