// A device buffer with guard words before and after its payload, for the op harness (tests/op_harness/op_cases.hpp):
// an op that writes out of bounds on a real device damages a guard, and one that writes its inputs changes their
// payload; check() finds both after the op ran. Every element the ops take is 4 bytes (float, int32, uint32), and
// a byte image is padded to whole words, so the buffer is counted in 4-byte words.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "runtime/context.hpp"

namespace ngi::harness {

// What the op does with a buffer: reads it only (its payload must be unchanged afterwards), writes it, both (in
// place), or uses it as scratch.
enum class Role { Input, Output, InOut, Scratch };

// The guards' bit pattern: a signalling NaN with a distinctive payload. No kernel produces one: arithmetic on a
// NaN yields a quiet NaN, so the pattern survives only where nothing was written.
constexpr std::uint32_t kGuardBits = 0x7FA5A5A5u;
// The initial payload of outputs and scratch: a quiet NaN with a payload, so an output element the op never writes
// reads as NaN and fails the comparison instead of passing with a stale zero.
constexpr std::uint32_t kUnwrittenBits = 0x7FC0DEADu;

class GuardedBuffer {
public:
    // words >= 1 payload words; `initial` (words of them, or null) is the payload of an input or in-out buffer,
    // outputs and scratch start as kUnwrittenBits.
    GuardedBuffer(detail::Context& ctx, std::string name, Role role, std::size_t words, const void* initial);
    GuardedBuffer(const GuardedBuffer&) = delete;
    GuardedBuffer& operator=(const GuardedBuffer&) = delete;
    ~GuardedBuffer();

    const std::string& name() const { return name_; }
    Role role() const { return role_; }
    std::size_t words() const { return words_; }
    // The whole buffer, with the payload offset() words (= floats) in: what an op taking a buffer and an offset gets.
    cl_mem mem() const { return buffer_.get(); }
    std::size_t offset() const { return guard_words_; }
    std::size_t offset_bytes() const { return guard_words_ * 4; }
    // A sub-buffer that is exactly the payload: for op arguments without an offset. Its origin is aligned to the
    // device's CL_DEVICE_MEM_BASE_ADDR_ALIGN, which is why the guards are at least that long.
    cl_mem payload() const { return payload_; }

    std::vector<float> read_floats(detail::Context& ctx) const;
    std::vector<std::uint32_t> read_words(detail::Context& ctx) const;  // the payload

    // Empty when both guards are intact and an input's payload is unchanged; otherwise what was damaged, e.g.
    // "<case>: buffer 'y', guard after the payload, first damaged word 0 (of 32): 0x3f800000".
    std::string check(detail::Context& ctx, const std::string& case_name) const;

    // Guard length (words) on this device: max(16, CL_DEVICE_MEM_BASE_ADDR_ALIGN / 32).
    static std::size_t guard_words(detail::Context& ctx);

private:
    std::string name_;
    Role role_;
    std::size_t words_, guard_words_;
    detail::Buffer buffer_;
    cl_mem payload_ = nullptr;
    std::vector<std::uint32_t> initial_;  // the payload as written (inputs: must be unchanged)
};

}  // namespace ngi::harness
