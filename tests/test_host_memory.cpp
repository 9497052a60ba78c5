// The process-wide host-memory ledger (ngi/host_memory.hpp): its limit (NGI_HOST_MEMORY_LIMIT or
// set_host_memory_limit), what counts against it (HostMemoryHold, ngi's buffers on a CPU device, what a file
// reader will hold at once), and the refusals that name it.
#include <catch2/catch.hpp>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>

#include "base/file_util.hpp"
#include "io_test_support.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/host_memory.hpp"
#include "ngi/image_io.hpp"
#include "ngi/tensor.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using ngi::test::TempDir;

namespace {

// Sets the process's host-memory limit for one scope (ngi/host_memory.hpp) and restores the default after.
struct HostMemoryLimit {
    explicit HostMemoryLimit(std::uint64_t bytes) { ngi::set_host_memory_limit(bytes); }
    ~HostMemoryLimit() { ngi::set_host_memory_limit(0); }
    HostMemoryLimit(const HostMemoryLimit&) = delete;
    HostMemoryLimit& operator=(const HostMemoryLimit&) = delete;
};

}  // namespace

// Issue 51: the viewer at --n 2048 reached 15 GB past NGI_HOST_MEMORY_LIMIT -- its network's tensor arena,
// allocated on PoCL, whose device memory is host memory. ngi's buffers on a CPU device now count against the budget
// while they live.
TEST_CASE("ngi's buffers on a CPU device count against the host-memory budget while they live", "[io][limits]") {
    ngi::Device& dev = ngi::test::device();
    if (!dev.info().is_cpu) {
        WARN("not a CPU device: its memory is not host memory, nothing to check");
        return;
    }
    const HostMemoryLimit limit(256u << 20);  // other buffers of this process (a test device's) hold far less
    const std::uint64_t before = ngi::host_memory_held();
    CHECK_THROWS_WITH(ngi::DeviceBuffer::allocate(dev, 257u << 20),
                      Contains("allocate device buffer on a CPU device") && Contains("needs 269484032 bytes") &&
                          Contains("host-memory limit"));
    CHECK(ngi::host_memory_held() == before);  // a refusal holds nothing
    {
        const ngi::DeviceBuffer a = ngi::DeviceBuffer::allocate(dev, 160u << 20);
        CHECK(ngi::host_memory_held() == before + (160u << 20));
        // 160 MiB held: 160 more would pass the 256 MiB budget.
        CHECK_THROWS_WITH(ngi::DeviceBuffer::allocate(dev, 160u << 20), Contains("already held"));
        CHECK_NOTHROW(ngi::DeviceBuffer::allocate(dev, 64u << 20));
    }
    // Released: the budget is free again.
    CHECK(ngi::host_memory_held() == before);
    CHECK_NOTHROW(ngi::DeviceBuffer::allocate(dev, 200u << 20));
}

// The same ledger holds what an application or the pipeline keeps on the host (the GL viewer's G-buffer on a
// software renderer, the global view's tables): a HostMemoryHold and a CPU device's buffers are judged together.
TEST_CASE("host-memory holds and CPU device buffers share one ledger", "[io][limits]") {
    ngi::Device& dev = ngi::test::device();  // opened first: what it holds is part of `before`
    const std::uint64_t before = ngi::host_memory_held();  // whatever this process already holds, plus 256 MiB
    const HostMemoryLimit limit(before + (256u << 20));
    CHECK_THROWS_WITH(ngi::HostMemoryHold("the test's frames", 300u << 20),
                      Contains("the test's frames: needs 314572800 bytes") && Contains("host-memory limit"));
    CHECK(ngi::host_memory_held() == before);
    {
        ngi::HostMemoryHold frames("the test's frames", 160u << 20);
        CHECK(ngi::host_memory_held() == before + (160u << 20));
        CHECK_THROWS_WITH(ngi::HostMemoryHold("more frames", 160u << 20), Contains("already held"));
        if (dev.info().is_cpu)
            CHECK_THROWS_WITH(ngi::DeviceBuffer::allocate(dev, 160u << 20), Contains("already held"));
        ngi::HostMemoryHold moved = std::move(frames);  // the hold moves; it is released once
        CHECK(frames.bytes() == 0);
        CHECK(moved.bytes() == (160u << 20));
        CHECK(ngi::host_memory_held() == before + (160u << 20));
        moved = ngi::HostMemoryHold("smaller frames", 32u << 20);  // assignment releases the old hold
        CHECK(ngi::host_memory_held() == before + (32u << 20));
    }
    CHECK(ngi::host_memory_held() == before);
}

// Issue 31, item 6: an 805 MB npy into an AO model reached 2.5 GB of host memory unchecked. Every reader now
// checks what it will hold at once -- the file's bytes plus what they decode to -- against a limit the user can
// raise (NGI_HOST_MEMORY_LIMIT), before allocating. A compressed image is judged by its decoded size, not its file.
TEST_CASE("readers check the host memory they will hold before allocating", "[io][limits]") {
    TempDir dir("host-memory-readers");
    // 512 x 512 x 3 constant: small files (ZIP / deflate), 3 MiB of floats once decoded.
    ngi::Image flat(512, 512, 3, 0.25f);
    const std::string exr = dir / "flat.exr", png = dir / "flat.png", npy = dir / "flat.npy";
    ngi::write_exr(exr, flat, ngi::ExrPixelType::Half);
    ngi::write_png(png, flat);
    ngi::Tensor t({3, 512, 512});
    ngi::write_npy(npy, t);
    REQUIRE(fs::file_size(exr) < 64 * 1024);
    REQUIRE(fs::file_size(png) < 64 * 1024);
    {
        HostMemoryLimit limit(1 << 20);  // 1 MiB: every decoded image above is 3 MiB
        for (const std::string& path : {exr, png, npy}) {
            INFO(path);
            CHECK_THROWS_WITH(path.ends_with(".npy") ? void(ngi::read_npy(path)) : void(ngi::read_image(path)),
                              Contains(path) && Contains("of host memory at once") &&
                                  Contains("host-memory limit of 1048576 bytes (1 MiB)") &&
                                  Contains("NGI_HOST_MEMORY_LIMIT"));
        }
        // The file itself over the limit: refused from its size, before a byte is read.
        HostMemoryLimit tiny(1000);
        CHECK_THROWS_WITH(ngi::detail::read_file(npy, "read"), Contains("flat.npy") && Contains("1000 bytes"));
    }
    // The default limit (half the physical memory, at least 1 GiB) reads them all.
    CHECK(ngi::host_memory_limit() >= (std::uint64_t(1) << 30));
    CHECK(ngi::read_image(exr).data.size() == flat.data.size());
    CHECK(ngi::read_image(png).data.size() == flat.data.size());
    CHECK(ngi::read_npy(npy).data.size() == flat.data.size());
    // Exactly at the limit is allowed: the npy holds its 3 MiB of values plus its file's bytes.
    {
        HostMemoryLimit exact(fs::file_size(npy) + 512 * 512 * 3 * sizeof(float));
        CHECK(ngi::read_npy(npy).data.size() == flat.data.size());
        HostMemoryLimit one_less(fs::file_size(npy) + 512 * 512 * 3 * sizeof(float) - 1);
        CHECK_THROWS_AS(ngi::read_npy(npy), ngi::InputError);
    }
}

TEST_CASE("NGI_HOST_MEMORY_LIMIT takes bytes with a binary suffix, and names itself when malformed", "[io][limits]") {
    const char* old = std::getenv("NGI_HOST_MEMORY_LIMIT");
    const std::string saved = old ? old : "";
    auto with_env = [](const char* value) {
        ::setenv("NGI_HOST_MEMORY_LIMIT", value, 1);
        return ngi::host_memory_limit();
    };
    CHECK(with_env("123456") == 123456u);
    CHECK(with_env("64K") == 64u << 10);
    CHECK(with_env("512m") == 512u << 20);
    CHECK(with_env("16G") == std::uint64_t(16) << 30);
    CHECK(with_env("2T") == std::uint64_t(2) << 40);
    for (const char* bad : {"lots", "0", "-5", "12GB", "1.5G", "99999999999999999999", "20000000T"}) {
        INFO(bad);
        CHECK_THROWS_WITH(with_env(bad), Contains(std::string("NGI_HOST_MEMORY_LIMIT='") + bad + "'"));
    }
    {
        HostMemoryLimit set(4096);  // the application's setting wins over the environment
        CHECK(with_env("lots") == 4096u);
    }
    if (old) ::setenv("NGI_HOST_MEMORY_LIMIT", saved.c_str(), 1);
    else ::unsetenv("NGI_HOST_MEMORY_LIMIT");
    CHECK(ngi::host_memory_limit() >= (std::uint64_t(1) << 30));
    CHECK(ngi::describe_bytes(805306368) == "805306368 bytes (768 MiB)");
    CHECK(ngi::describe_bytes(3u << 30) == "3221225472 bytes (3.0 GiB)");
    CHECK(ngi::describe_bytes(1000) == "1000 bytes");
}
