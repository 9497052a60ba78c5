// One op run between guards, for the ops' own tests (test_max_pool.cpp, test_pad2d.cpp, test_resize.cpp): the input
// at an offset inside a bigger buffer whose other words are NaN (a read outside the input poisons an output), the
// output at an offset between sentinels (a write outside it changes one, which fails a CHECK).
#pragma once
#include <algorithm>
#include <cmath>
#include <vector>

#include "ops/view.hpp"
#include "test_support.hpp"

namespace ngi::test {

// enqueue(ctx, x_view, y_view) runs the op; returns y (out.size() floats).
template <class Enqueue>
std::vector<float> run_guarded(const std::vector<float>& x, const Shape& in, const Shape& out, Enqueue&& enqueue) {
    constexpr std::size_t kXOff = 3, kYOff = 7, kTail = 5;
    constexpr float kSentinel = 1234.5f;
    auto& c = ctx();
    std::vector<float> xs(kXOff + x.size() + kTail, NAN);
    std::copy(x.begin(), x.end(), xs.begin() + kXOff);
    detail::Buffer xb = upload(xs);
    detail::Buffer yb = upload(std::vector<float>(kYOff + out.size() + kTail, kSentinel));
    enqueue(c, detail::View{xb.get(), kXOff, in}, detail::View{yb.get(), kYOff, out});
    const std::vector<float> all = download(yb, kYOff + out.size() + kTail);
    for (std::size_t i = 0; i < kYOff; ++i) CHECK(all[i] == kSentinel);
    for (std::size_t i = kYOff + out.size(); i < all.size(); ++i) CHECK(all[i] == kSentinel);
    return std::vector<float>(all.begin() + kYOff, all.begin() + kYOff + std::ptrdiff_t(out.size()));
}

}  // namespace ngi::test
