// The threading model (docs/ARCHITECTURE.md "Threading"): one Device shared by several threads, each with its own
// Models and SurroundPipelines, compiling programs for the first time concurrently. Every result must equal,
// bit for bit, the same work done on one thread. tools/test.sh's tsan stage runs these under ThreadSanitizer.
#include <atomic>
#include <functional>
#include <thread>

#include "ngi/device_buffer.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

const std::string kSingleView = std::string(NGI_SOURCE_DIR) + "/models/single_view.safetensors";
const std::string kSurround = std::string(NGI_SOURCE_DIR) + "/models/surround.safetensors";

Frame flat_frame(int n, float direct) {
    Frame fr;
    fr.n = n;
    for (int f = 0; f < kFaceCount; ++f) {
        fr.get(Feature::Albedo, Face(f)) = Image(n, n, 3, 0.6f);
        Image normal(n, n, 3, 0.0f);
        for (int i = 0; i < n * n; ++i) normal.data[std::size_t(n) * n + i] = 1.0f;  // +y
        fr.get(Feature::Normal, Face(f)) = normal;
        fr.get(Feature::Depth, Face(f)) = Image(n, n, 1, 3.0f + float(f));
        fr.get(Feature::Direct, Face(f)) = Image(n, n, 3, direct * float(f + 1));
    }
    return fr;
}

// Runs `work(thread index)` on `threads` threads at once (released together) and rethrows the first failure.
void concurrently(int threads, const std::function<void(int)>& work) {
    std::atomic<int> ready{0};
    std::vector<std::thread> pool;
    std::vector<std::exception_ptr> errors(threads);
    for (int t = 0; t < threads; ++t)
        pool.emplace_back([&, t] {
            ++ready;
            while (ready.load() < threads) std::this_thread::yield();
            try {
                work(t);
            } catch (...) {
                errors[t] = std::current_exception();
            }
        });
    for (auto& th : pool) th.join();
    for (auto& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace

TEST_CASE("threads: one device, a model per thread, first-use builds at once: results equal one thread's",
          "[threads]") {
    const int n = 64, threads = 4, runs = 3;
    std::mt19937 rng(31);
    std::vector<Tensor> inputs;
    for (int i = 0; i < threads * runs; ++i) {
        Tensor x({1, 10, n, n});
        x.data = test::random_vector(x.size(), rng);
        inputs.push_back(std::move(x));
    }
    // The single-threaded answers, on the test device.
    std::vector<Tensor> want;
    {
        Model m = Model::load(test::device(), kSingleView);
        for (const Tensor& x : inputs) want.push_back(m.run(x));
    }
    // A fresh Device (empty in-process program cache) shared by every thread: each loads its own model, so the
    // programs are built by whichever thread gets there first while the others wait for them.
    const char* spec = std::getenv("NGI_TEST_DEVICE");
    Device shared = Device::open(spec && *spec ? spec : "cpu");
    std::vector<std::vector<Tensor>> got(threads);
    concurrently(threads, [&](int t) {
        Model m = Model::load(shared, kSingleView);
        for (int r = 0; r < runs; ++r) got[t].push_back(m.run(inputs[std::size_t(t) * runs + r]));
    });
    for (int t = 0; t < threads; ++t)
        for (int r = 0; r < runs; ++r) {
            CAPTURE(t, r);
            REQUIRE(got[t][r].data == want[std::size_t(t) * runs + r].data);
        }
}

TEST_CASE("threads: pipelines and device buffers on one device from several threads", "[threads]") {
    const int n = 64, threads = 3;
    Device& dev = test::device();
    std::vector<Frame> frames;
    for (int t = 0; t < threads; ++t) frames.push_back(flat_frame(n, 0.5f + 0.25f * float(t)));
    std::vector<Image> want;
    {
        Model m = Model::load(dev, kSurround);
        SurroundPipeline pl(dev, n);
        for (const Frame& f : frames) want.push_back(pl.run(m, f, true, false, false).lightmap);
    }
    std::vector<Image> host(threads), device_side(threads);
    concurrently(threads, [&](int t) {
        Model m = Model::load(dev, kSurround);
        SurroundPipeline pl(dev, n);
        host[t] = pl.run(m, frames[t], true, false, false).lightmap;
        // The device path with this thread's own buffers; enqueue then a blocking download of its own buffer.
        const std::vector<float> planes = pack_frame_planes(frames[t], 6);
        DeviceBuffer in = DeviceBuffer::allocate(dev, planes.size() * sizeof(float));
        in.upload(planes.data(), in.bytes());
        FrameOutputs outs;
        outs.lightmap = DeviceBuffer::allocate(dev, 3 * std::size_t(n) * n * sizeof(float));
        pl.enqueue(m, in, FrameDesc::of(frames[t], 6), outs);
        device_side[t] = Image(n, n, 3);
        outs.lightmap.download(device_side[t].data.data(), outs.lightmap.bytes());
    });
    for (int t = 0; t < threads; ++t) {
        CAPTURE(t);
        REQUIRE(host[t].data == want[t].data);
        REQUIRE(device_side[t].data == want[t].data);
    }
}
