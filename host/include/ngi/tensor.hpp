// A host tensor: float32, row-major (C order), e.g. NCHW for images. What the public API takes and returns.
#pragma once
#include <cstddef>
#include <string>
#include <vector>

namespace ngi {

struct Tensor {
    std::vector<int> shape;
    std::vector<float> data;

    Tensor() = default;
    explicit Tensor(std::vector<int> s) : shape(std::move(s)), data(element_count(shape), 0.0f) {}
    std::size_t size() const { return data.size(); }
    static std::size_t element_count(const std::vector<int>& s) {
        std::size_t n = 1;
        for (int d : s) n *= std::size_t(d < 0 ? 0 : d);
        return n;
    }
};

std::string shape_string(const std::vector<int>& shape);  // "[1, 12, 512, 1024]"

// NumPy .npy (format 1.0/2.0/3.0): float32 (and float64 / float16, converted) little-endian, C order.
// Writes float32 to a uniquely named temporary file renamed into place, so a failed write leaves nothing behind.
Tensor read_npy(const std::string& path);
void write_npy(const std::string& path, const Tensor& t);

}  // namespace ngi
