#include "op_harness/guarded_buffer.hpp"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <utility>

namespace ngi::harness {

namespace {

std::string hex(std::uint32_t w) {
    char s[16];
    std::snprintf(s, sizeof s, "0x%08x", w);
    return s;
}

}  // namespace

std::size_t GuardedBuffer::guard_words(detail::Context& ctx) {
    cl_uint align_bits = 0;
    detail::check(clGetDeviceInfo(ctx.device(), CL_DEVICE_MEM_BASE_ADDR_ALIGN, sizeof align_bits, &align_bits, nullptr),
                  "op harness: base address alignment", "clGetDeviceInfo");
    return std::max<std::size_t>(16, align_bits / 32);
}

GuardedBuffer::GuardedBuffer(detail::Context& ctx, std::string name, Role role, std::size_t words,
                             const void* initial)
    : name_(std::move(name)), role_(role), words_(std::max<std::size_t>(1, words)), guard_words_(guard_words(ctx)) {
    std::vector<std::uint32_t> all(words_ + 2 * guard_words_, kGuardBits);
    initial_.assign(words_, kUnwrittenBits);
    if (initial && words > 0) std::memcpy(initial_.data(), initial, words * 4);
    std::copy(initial_.begin(), initial_.end(), all.begin() + std::ptrdiff_t(guard_words_));
    buffer_ = ctx.alloc(all.size() * 4, "op harness buffer");
    ctx.write(buffer_, 0, all.size() * 4, all.data(), "op harness buffer");
    const cl_buffer_region region{offset_bytes(), words_ * 4};
    cl_int err = CL_SUCCESS;
    payload_ = clCreateSubBuffer(buffer_.get(), CL_MEM_READ_WRITE, CL_BUFFER_CREATE_TYPE_REGION, &region, &err);
    detail::check(err, "op harness: payload sub-buffer", "clCreateSubBuffer", name_);
}

GuardedBuffer::~GuardedBuffer() {
    if (payload_) clReleaseMemObject(payload_);
}

std::vector<std::uint32_t> GuardedBuffer::read_words(detail::Context& ctx) const {
    std::vector<std::uint32_t> w(words_);
    ctx.read(buffer_, offset_bytes(), words_ * 4, w.data(), "op harness payload");
    return w;
}

std::vector<float> GuardedBuffer::read_floats(detail::Context& ctx) const {
    std::vector<float> f(words_);
    ctx.read(buffer_, offset_bytes(), words_ * 4, f.data(), "op harness payload");
    return f;
}

std::string GuardedBuffer::check(detail::Context& ctx, const std::string& case_name) const {
    std::vector<std::uint32_t> all(words_ + 2 * guard_words_);
    ctx.read(buffer_, 0, all.size() * 4, all.data(), "op harness guards");
    const std::string where = case_name + ": buffer '" + name_ + "', ";
    // The guard before the payload is scanned from its end (the word next to the payload: where an off-by-one
    // lands), the one after from its start.
    for (std::size_t k = 0; k < guard_words_; ++k) {
        const std::size_t i = guard_words_ - 1 - k;
        if (all[i] != kGuardBits)
            return where + "guard before the payload, first damaged word " + std::to_string(k) + " before it (of " +
                   std::to_string(guard_words_) + "): " + hex(all[i]);
    }
    for (std::size_t k = 0; k < guard_words_; ++k) {
        const std::uint32_t w = all[guard_words_ + words_ + k];
        if (w != kGuardBits)
            return where + "guard after the payload, first damaged word " + std::to_string(k) + " after it (of " +
                   std::to_string(guard_words_) + "): " + hex(w);
    }
    if (role_ == Role::Input)
        for (std::size_t i = 0; i < words_; ++i)
            if (all[guard_words_ + i] != initial_[i])
                return where + "an input the op wrote: payload word " + std::to_string(i) + " was " + hex(initial_[i]) +
                       ", is " + hex(all[guard_words_ + i]);
    return {};
}

}  // namespace ngi::harness
