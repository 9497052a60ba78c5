// One frame = one enqueue: SurroundPipeline::enqueue (device in, device out) and run (host in, host out) against
// the step-by-step path, their host-transfer counts, a device made from the application's own OpenCL objects,
// and the checks on device buffers.
#include <CL/cl.h>

#include <atomic>
#include <cfloat>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <thread>

#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"
#include "ngi/render.hpp"
#include "ngi/scene.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

const std::string kModels[2] = {std::string(NGI_SOURCE_DIR) + "/models/surround.safetensors",
                                std::string(NGI_SOURCE_DIR) + "/models/single_view.safetensors"};

// A frame with plausible values everywhere and the optional terms present or not.
Frame random_frame(int n, std::mt19937& rng, bool emission, bool env) {
    Frame fr;
    fr.n = n;
    fr.look = glm::normalize(glm::vec3(0.3f, -0.2f, -1.0f));
    fr.up = glm::vec3(0, 1, 0);
    for (int f = 0; f < kFaceCount; ++f) {
        auto img = [&](int c, float lo, float hi) {
            Image im(n, n, c);
            im.data = test::random_vector(im.data.size(), rng, lo, hi);
            return im;
        };
        fr.get(Feature::Albedo, Face(f)) = img(3, 0.0f, 1.0f);
        fr.get(Feature::Normal, Face(f)) = img(3, -1.0f, 1.0f);
        fr.get(Feature::Depth, Face(f)) = img(1, 0.5f, 40.0f);
        fr.get(Feature::Direct, Face(f)) = img(3, 0.0f, 4.0f);
        if (emission) fr.get(Feature::Emission, Face(f)) = img(3, 0.0f, 0.5f);
        if (env) fr.get(Feature::Env, Face(f)) = img(3, 0.0f, 0.2f);
    }
    return fr;
}

// The frame's packed planes on the device: all six faces for a surround model, the front face for a single-view one.
DeviceBuffer upload_planes(Device& dev, const Frame& fr, const Model& model) {
    const std::vector<float> planes = pack_frame_planes(fr, model.config().input_nc == 12 ? 6 : 1);
    DeviceBuffer in = DeviceBuffer::allocate(dev, planes.size() * sizeof(float));
    in.upload(planes.data(), in.bytes());
    return in;
}

HostTransfers since(const Device& d, const HostTransfers& t0) {
    HostTransfers t = d.host_transfers();
    return {t.uploads - t0.uploads, t.downloads - t0.downloads, t.upload_bytes - t0.upload_bytes,
            t.download_bytes - t0.download_bytes};
}

std::vector<float> read_back(const DeviceBuffer& b) {
    std::vector<float> v(b.bytes() / sizeof(float));
    b.download(v.data(), b.bytes());
    return v;
}

// A copy of the model file `src` (in the temp folder) whose config says output_mode `mode`, the weights untouched:
// the safetensors header is rewritten (data offsets are relative to the data section, which follows unchanged).
std::string with_output_mode(const std::string& src, const std::string& mode) {
    std::ifstream in(src, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    REQUIRE(bytes.size() >= 8);
    std::uint64_t len = 0;
    for (int i = 0; i < 8; ++i) len |= std::uint64_t(std::uint8_t(bytes[i])) << (8 * i);
    nlohmann::json header = nlohmann::json::parse(bytes.substr(8, len));
    nlohmann::json config = nlohmann::json::parse(header["__metadata__"]["ngi"].get<std::string>());
    config["output_mode"] = mode;
    config["required"] = {"output_mode"};
    header["__metadata__"]["ngi"] = config.dump();
    std::string h = header.dump();
    while (h.size() % 8) h += ' ';
    std::string out(8, '\0');
    for (int i = 0; i < 8; ++i) out[i] = char((std::uint64_t(h.size()) >> (8 * i)) & 0xff);
    out += h + bytes.substr(8 + len);
    const std::filesystem::path p = std::filesystem::temp_directory_path() /
                                    ("ngi_test_" + mode + "_" + std::filesystem::path(src).filename().string());
    std::ofstream(p, std::ios::binary).write(out.data(), std::streamsize(out.size()));
    return p.string();
}

float clean_light(float v) { return std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, FLT_MAX); }

}  // namespace

TEST_CASE("frame path: run() and enqueue() equal the step-by-step path bit for bit", "[frame]") {
    Device& dev = test::device();
    std::mt19937 rng(7);
    const int n = 64;  // the shipped models' size (7 and 6 downsamplings)
    for (const std::string& path : kModels) {
        Model model = Model::load(dev, path);
        SurroundPipeline pl(dev, n);
        for (int variant = 0; variant < 2; ++variant) {
            CAPTURE(path, variant);
            const Frame fr = random_frame(n, rng, variant == 1, variant == 1);
            ToneMapOptions tm;
            tm.exposure_ev = 0.5f;
            // The step-by-step path: host tensors between every stage.
            PreprocessStats want_stats;
            const Tensor x = pl.network_input(fr, model.config(), &want_stats);
            const Image light = pl.front_lightmap(model.run(x), model.config());
            const Image final_image = pl.compose(light, fr);
            const Image display = pl.tonemap(final_image, tm);

            PreprocessStats got_stats;
            const FrameImages r = pl.run(model, fr, true, true, true, tm, &got_stats);
            REQUIRE(r.lightmap.data == light.data);
            REQUIRE(r.final_image.data == final_image.data);
            REQUIRE(r.display.data == display.data);
            REQUIRE(got_stats.nonfinite == want_stats.nonfinite);
            REQUIRE(got_stats.far_depths == want_stats.far_depths);

            // Only what was asked for comes back.
            const FrameImages only = pl.run(model, fr, false, true, false);
            REQUIRE(only.lightmap.data.empty());
            REQUIRE(only.display.data.empty());
            REQUIRE(only.final_image.data == final_image.data);

            // Device in, device out.
            DeviceBuffer in = upload_planes(dev, fr, model);
            FrameOutputs outs;
            outs.tonemap = tm;
            outs.lightmap = DeviceBuffer::allocate(dev, light.data.size() * sizeof(float));
            outs.display = DeviceBuffer::allocate(dev, light.data.size() * sizeof(float));
            pl.enqueue(model, in, FrameDesc::of(fr, model.config().input_nc == 12 ? 6 : 1), outs);
            REQUIRE(read_back(outs.lightmap) == light.data);
            REQUIRE(read_back(outs.display) == display.data);
        }
    }
}

TEST_CASE("frame path: host in/out costs one upload and one download, device in/out none", "[frame]") {
    Device& dev = test::device();
    std::mt19937 rng(8);
    const int n = 64;
    Model model = Model::load(dev, kModels[0]);
    SurroundPipeline pl(dev, n);
    const Frame fr = random_frame(n, rng, true, false);
    const std::size_t out_bytes = 3 * std::size_t(n) * n * sizeof(float);
    pl.run(model, fr, true, true, true);  // warm-up: first-use uploads (coordinate planes, tables' sizes)

    HostTransfers t0 = dev.host_transfers();
    pl.run(model, fr, true, true, true);
    HostTransfers t = since(dev, t0);
    CHECK(t.uploads == 1);
    CHECK(t.upload_bytes == (long long)frame_planes_bytes(n, 6));
    CHECK(t.downloads == 1);
    CHECK(t.download_bytes == (long long)(3 * out_bytes));

    const std::vector<float> planes = pack_frame_planes(fr, 6);
    DeviceBuffer in = DeviceBuffer::allocate(dev, planes.size() * sizeof(float));
    in.upload(planes.data(), in.bytes());
    FrameOutputs outs;
    outs.lightmap = DeviceBuffer::allocate(dev, out_bytes);
    outs.final_image = DeviceBuffer::allocate(dev, out_bytes);
    outs.display = DeviceBuffer::allocate(dev, out_bytes);
    const FrameDesc desc = FrameDesc::of(fr, 6);
    pl.enqueue(model, in, desc, outs);  // warm-up
    dev.finish();
    t0 = dev.host_transfers();
    for (int i = 0; i < 3; ++i) pl.enqueue(model, in, desc, outs);
    dev.finish();
    t = since(dev, t0);
    CHECK(t.uploads == 0);
    CHECK(t.downloads == 0);

    // The step-by-step path, for the record: what one frame cost before.
    t0 = dev.host_transfers();
    const Image light = pl.front_lightmap(model.run(pl.network_input(fr, model.config())), model.config());
    pl.tonemap(pl.compose(light, fr));
    t = since(dev, t0);
    WARN("step-by-step path: " << t.uploads << " uploads (" << t.upload_bytes << " B), " << t.downloads
                               << " downloads (" << t.download_bytes << " B) per frame");
    CHECK(t.uploads + t.downloads > 2);
}

TEST_CASE("frame path: a device on the application's own context, queue and buffers", "[frame][interop]") {
    // The application's side, in raw OpenCL: its context and in-order queue on the test device, its G-buffer
    // planes and its lightmap buffer (the lightmap at an aligned offset inside a larger buffer).
    cl_device_id cl_dev = test::ctx().device();
    cl_int err = CL_SUCCESS;
    cl_context app_ctx = clCreateContext(nullptr, 1, &cl_dev, nullptr, nullptr, &err);
    REQUIRE(err == CL_SUCCESS);
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
    cl_command_queue app_queue = clCreateCommandQueue(app_ctx, cl_dev, 0, &err);
#pragma GCC diagnostic pop
    REQUIRE(err == CL_SUCCESS);

    std::mt19937 rng(9);
    const int n = 64;
    const Frame fr = random_frame(n, rng, false, true);
    const std::vector<float> planes = pack_frame_planes(fr, 6);
    const std::size_t out_bytes = 3 * std::size_t(n) * n * sizeof(float);
    cl_uint align_bits = 0;
    REQUIRE(clGetDeviceInfo(cl_dev, CL_DEVICE_MEM_BASE_ADDR_ALIGN, sizeof align_bits, &align_bits, nullptr) == CL_SUCCESS);
    const std::size_t offset = align_bits / 8;  // one alignment unit in: a real offset, a legal sub-buffer
    cl_mem app_planes = clCreateBuffer(app_ctx, CL_MEM_READ_ONLY, planes.size() * sizeof(float), nullptr, &err);
    REQUIRE(err == CL_SUCCESS);
    cl_mem app_light = clCreateBuffer(app_ctx, CL_MEM_READ_WRITE, offset + out_bytes, nullptr, &err);
    REQUIRE(err == CL_SUCCESS);
    REQUIRE(clEnqueueWriteBuffer(app_queue, app_planes, CL_TRUE, 0, planes.size() * sizeof(float), planes.data(), 0,
                                 nullptr, nullptr) == CL_SUCCESS);

    // The reference: the same frame through run() on the test device.
    Model ref_model = Model::load(test::device(), kModels[0]);
    SurroundPipeline ref_pl(test::device(), n);
    const FrameImages want = ref_pl.run(ref_model, fr, true, false, false);

    {
        Device dev = Device::from_opencl(app_ctx, cl_dev, app_queue);
        REQUIRE(dev.opencl_queue() == app_queue);
        REQUIRE(dev.info().name == test::device().info().name);
        Model model = Model::load(dev, kModels[0]);
        SurroundPipeline pl(dev, n);
        FrameOutputs outs;
        outs.lightmap = DeviceBuffer::wrap(dev, app_light, offset, out_bytes);
        REQUIRE_FALSE(outs.lightmap.owned());
        const DeviceBuffer in = DeviceBuffer::wrap(dev, app_planes, 0, planes.size() * sizeof(float));
        REQUIRE_FALSE(in.writable());
        pl.enqueue(model, in, FrameDesc::of(fr, 6), outs);
        pl.enqueue(model, in, FrameDesc::of(fr, 6), outs);  // warm, then counted
        const HostTransfers t0 = dev.host_transfers();
        pl.enqueue(model, in, FrameDesc::of(fr, 6), outs);
        CHECK(since(dev, t0).uploads == 0);
        CHECK(since(dev, t0).downloads == 0);

        // A read-only buffer is refused as an output, naming it.
        FrameOutputs bad;
        bad.lightmap = in;
        REQUIRE_THROWS_WITH(pl.enqueue(model, in, FrameDesc::of(fr, 6), bad), Catch::Contains("lightmap") &&
                                                                               Catch::Contains("READ_ONLY"));
    }  // every ngi object released: the application's objects stay, with their own references only

    // The application waits on its own queue and reads its own buffer.
    std::vector<float> got(out_bytes / sizeof(float));
    REQUIRE(clEnqueueReadBuffer(app_queue, app_light, CL_TRUE, offset, out_bytes, got.data(), 0, nullptr, nullptr) ==
            CL_SUCCESS);
    REQUIRE(got == want.lightmap.data);
    // ngi holds no reference any more: once the application releases its objects, the driver frees its buffers.
    // (CL_MEM_REFERENCE_COUNT is no proof either way: drivers keep references in finished commands for a while.)
    static std::atomic<int> freed{0};
    freed = 0;
    auto on_free = [](cl_mem, void*) { ++freed; };
    REQUIRE(clSetMemObjectDestructorCallback(app_planes, on_free, nullptr) == CL_SUCCESS);
    REQUIRE(clSetMemObjectDestructorCallback(app_light, on_free, nullptr) == CL_SUCCESS);
    REQUIRE(clFinish(app_queue) == CL_SUCCESS);
    clReleaseMemObject(app_planes);
    clReleaseMemObject(app_light);
    clReleaseCommandQueue(app_queue);
    clReleaseContext(app_ctx);
    for (int i = 0; i < 500 && freed < 2; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    CHECK(freed == 2);
}

TEST_CASE("frame path: device buffers and interop objects that do not fit are refused", "[frame][interop]") {
    Device& dev = test::device();
    cl_device_id cl_dev = test::ctx().device();
    cl_int err = CL_SUCCESS;
    cl_context other = clCreateContext(nullptr, 1, &cl_dev, nullptr, nullptr, &err);
    REQUIRE(err == CL_SUCCESS);
    cl_mem foreign = clCreateBuffer(other, CL_MEM_READ_WRITE, 4096, nullptr, &err);
    REQUIRE(err == CL_SUCCESS);
    cl_mem own = clCreateBuffer(test::ctx().context(), CL_MEM_READ_WRITE, 4096, nullptr, &err);
    REQUIRE(err == CL_SUCCESS);

    REQUIRE_THROWS_WITH(DeviceBuffer::wrap(dev, nullptr, 0, 16), Catch::Contains("NULL"));
    REQUIRE_THROWS_WITH(DeviceBuffer::wrap(dev, own, 0, 0), Catch::Contains("0 bytes"));
    REQUIRE_THROWS_WITH(DeviceBuffer::wrap(dev, own, 0, 4097), Catch::Contains("outside"));
    REQUIRE_THROWS_WITH(DeviceBuffer::wrap(dev, own, 4000, 100), Catch::Contains("outside"));
    REQUIRE_THROWS_WITH(DeviceBuffer::wrap(dev, own, 4, 16), Catch::Contains("CL_DEVICE_MEM_BASE_ADDR_ALIGN"));
    REQUIRE_THROWS_WITH(DeviceBuffer::wrap(dev, foreign, 0, 16), Catch::Contains("another OpenCL context"));
    REQUIRE_THROWS_WITH(DeviceBuffer::allocate(dev, 0), Catch::Contains("0 bytes"));
    DeviceBuffer b = DeviceBuffer::wrap(dev, own, 0, 64);
    std::vector<float> v(32);
    REQUIRE_THROWS_WITH(b.upload(v.data(), 128), Catch::Contains("outside"));
    REQUIRE_THROWS_WITH(b.download(v.data(), 4, 64), Catch::Contains("outside"));

    // Interop objects that do not belong together.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
    cl_command_queue other_queue = clCreateCommandQueue(other, cl_dev, 0, &err);
    REQUIRE(err == CL_SUCCESS);
    cl_command_queue ooo = clCreateCommandQueue(other, cl_dev, CL_QUEUE_OUT_OF_ORDER_EXEC_MODE_ENABLE, &err);
#pragma GCC diagnostic pop
    REQUIRE_THROWS_WITH(Device::from_opencl(nullptr, cl_dev, other_queue), Catch::Contains("NULL"));
    REQUIRE_THROWS_WITH(Device::from_opencl(test::ctx().context(), cl_dev, other_queue),
                        Catch::Contains("another context"));
    if (err == CL_SUCCESS) {  // a device may not support out-of-order queues at all
        REQUIRE_THROWS_WITH(Device::from_opencl(other, cl_dev, ooo), Catch::Contains("out of order"));
        clReleaseCommandQueue(ooo);
    }

    // Frames that do not fit the pipeline or the model.
    const int n = 64;
    Model model = Model::load(dev, kModels[0]);
    SurroundPipeline pl(dev, n);
    DeviceBuffer small = DeviceBuffer::allocate(dev, frame_planes_bytes(n, 6) - 4);
    FrameOutputs outs;
    outs.lightmap = DeviceBuffer::allocate(dev, 3 * n * n * sizeof(float));
    REQUIRE_THROWS_WITH(pl.enqueue(model, small, FrameDesc{}, outs), Catch::Contains("planes buffer holds"));
    DeviceBuffer planes = DeviceBuffer::allocate(dev, frame_planes_bytes(n, 6));
    FrameDesc one;
    one.faces = 1;
    REQUIRE_THROWS_WITH(pl.enqueue(model, planes, one, outs), Catch::Contains("needs all 6 faces"));
    FrameOutputs tiny;
    tiny.display = DeviceBuffer::allocate(dev, 16);
    REQUIRE_THROWS_WITH(pl.enqueue(model, planes, FrameDesc{}, tiny), Catch::Contains("display buffer holds"));
    SurroundPipeline wrong(dev, 32);  // 2N = 64 is not a multiple of 2^7
    REQUIRE_THROWS_WITH(wrong.enqueue(model, planes, FrameDesc{}, outs), Catch::Contains("2^num_downs"));
    REQUIRE_THROWS_WITH(model.enqueue(planes, outs.lightmap, 100, 256), Catch::Contains("multiples of 2^num_downs"));
    REQUIRE_THROWS_WITH(model.enqueue(planes, outs.lightmap, 128, 256), Catch::Contains("output buffer holds"));

    clReleaseMemObject(own);
    clReleaseMemObject(foreign);
    clReleaseCommandQueue(other_queue);
    clReleaseContext(other);
}

// A room traced at face size n from its middle, the frame rendered on the host: what the two tracer cases share.
struct TracedRoom {
    VoxelScene scene = generate_scene("room", 5);
    Renderer renderer;
    CameraPose pose;
    Lighting lighting = lighting_at(15.0f, 0.7f);
    RenderSettings rs;
    Frame fr;
    TracedRoom(Device& dev, int n) : renderer(dev, scene) {
        pose.position = glm::vec3(scene.size) * 0.5f;
        pose.look = glm::normalize(glm::vec3(0.4f, -0.1f, -1.0f));
        rs.n = n;
        rs.feature_spp = 2;
        rs.reference = false;
        fr = renderer.render(pose, lighting, rs);
    }
};

// The tracer half of the device path (runs on every stack: no network) ...
TEST_CASE("frame path: the path tracer renders frame planes on the device, bit for bit its faces", "[frame][render]") {
    Device& dev = test::device();
    const int n = 32;
    TracedRoom room(dev, n);
    Renderer& renderer = room.renderer;
    const CameraPose& pose = room.pose;
    const Lighting& lighting = room.lighting;
    const RenderSettings& rs = room.rs;
    const Frame& fr = room.fr;
    DeviceBuffer planes = DeviceBuffer::allocate(dev, frame_planes_bytes(n, 6));
    renderer.render_planes(pose, lighting, rs, planes);  // warm-up
    dev.finish();
    const HostTransfers t0 = dev.host_transfers();
    renderer.render_planes(pose, lighting, rs, planes);
    dev.finish();
    const HostTransfers t = since(dev, t0);
    CHECK(t.downloads == 0);
    CHECK(t.upload_bytes < (long long)(n * n * sizeof(float)));
    REQUIRE(read_back(planes) == pack_frame_planes(fr, 6));
    DeviceBuffer small = DeviceBuffer::allocate(dev, 64);
    REQUIRE_THROWS_WITH(renderer.render_planes(pose, lighting, rs, small), Catch::Contains("planes buffer holds"));
}

// ... and the whole device path with the generator (host plumbing: PoCL, the sanitizers; the rusticl stage leaves it
// out, as every network-running frame-path case: each generator run takes ~40 s on llvmpipe).
TEST_CASE("frame path: the path tracer feeds the pipeline without the frame leaving the device", "[frame][render]") {
    Device& dev = test::device();
    const int n = 64;
    TracedRoom room(dev, n);
    Renderer& renderer = room.renderer;
    const CameraPose& pose = room.pose;
    const Lighting& lighting = room.lighting;
    const RenderSettings& rs = room.rs;
    const Frame& fr = room.fr;

    Model model = Model::load(dev, kModels[0]);
    SurroundPipeline pl(dev, n);
    const FrameImages want = pl.run(model, fr, true, true, false);

    DeviceBuffer planes = DeviceBuffer::allocate(dev, frame_planes_bytes(n, 6));
    FrameOutputs outs;
    outs.lightmap = DeviceBuffer::allocate(dev, 3 * n * n * sizeof(float));
    outs.final_image = DeviceBuffer::allocate(dev, 3 * n * n * sizeof(float));
    const FrameDesc desc{6, true, true, pose.look, pose.up};
    renderer.render_planes(pose, lighting, rs, planes);  // warm-up
    pl.enqueue(model, planes, desc, outs);
    dev.finish();
    const HostTransfers t0 = dev.host_transfers();
    renderer.render_planes(pose, lighting, rs, planes);
    pl.enqueue(model, planes, desc, outs);
    dev.finish();
    const HostTransfers t = since(dev, t0);
    CHECK(t.downloads == 0);
    // Only the renderer's per-frame parameters go up (materials, emitters, camera): far less than one plane.
    CHECK(t.upload_bytes < (long long)(n * n * sizeof(float)));
    WARN("render + frame on the device: " << t.uploads << " parameter uploads, " << t.upload_bytes << " bytes");

    // The same values as render()'s faces, bit for bit, so the same lightmap and final image.
    REQUIRE(read_back(planes) == pack_frame_planes(fr, 6));
    REQUIRE(read_back(outs.lightmap) == want.lightmap.data);
    REQUIRE(read_back(outs.final_image) == want.final_image.data);

    DeviceBuffer small = DeviceBuffer::allocate(dev, 64);
    REQUIRE_THROWS_WITH(renderer.render_planes(pose, lighting, rs, small), Catch::Contains("planes buffer holds"));
}

TEST_CASE("frame path: an indirect-mode model's lightmap is the lightmap mode's + the sanitized front direct light",
          "[frame]") {
    // The same weights read as output_mode "indirect": the network's output is identical, so run(), enqueue() and
    // the step-by-step path must give exactly the lightmap mode's lightmap + the cleaned front direct light, and
    // the final and display images of that lightmap.
    Device& dev = test::device();
    std::mt19937 rng(9);
    const int n = 64;
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    for (const std::string& path : kModels) {
        Model lightmap_model = Model::load(dev, path);
        Model model = Model::load(dev, with_output_mode(path, "indirect"));
        REQUIRE(lightmap_model.config().output_mode == "lightmap");
        REQUIRE(model.config().output_mode == "indirect");
        SurroundPipeline pl(dev, n);
        Frame fr = random_frame(n, rng, true, path == kModels[0]);
        std::vector<float>& d = fr.get(Feature::Direct, Face::Front).data;
        const float hostile[] = {nan, inf, -inf, -2.0f, 65504.0f, 70000.0f, 1e30f, FLT_MAX};
        for (std::size_t k = 0; k < std::size(hostile); ++k) d[k * 997 % d.size()] = hostile[k];
        ToneMapOptions tm;
        tm.exposure_ev = -1.0f;
        CAPTURE(path);

        PreprocessStats want_stats, got_stats;
        const FrameImages base = pl.run(lightmap_model, fr, true, true, true, tm, &want_stats);
        const FrameImages r = pl.run(model, fr, true, true, true, tm, &got_stats);
        REQUIRE(r.lightmap.data.size() == d.size());
        for (std::size_t i = 0; i < d.size(); ++i) {
            REQUIRE(std::isfinite(r.lightmap.data[i]));
            REQUIRE(r.lightmap.data[i] == std::min(base.lightmap.data[i] + clean_light(d[i]), FLT_MAX));
        }
        REQUIRE(r.final_image.data == pl.compose(r.lightmap, fr).data);
        REQUIRE(r.display.data == pl.tonemap(r.final_image, tm).data);
        // The non-finite direct values are counted by preprocessing, as in either mode.
        REQUIRE(got_stats.nonfinite == want_stats.nonfinite);
        REQUIRE(got_stats.nonfinite[int(Feature::Direct)] >= 3);

        // The step-by-step path: the frame overload of front_lightmap; the old one refuses an indirect model.
        const Tensor y = model.run(pl.network_input(fr, model.config()));
        REQUIRE(pl.front_lightmap(y, model.config(), fr).data == r.lightmap.data);
        REQUIRE_THROWS_WITH(pl.front_lightmap(y, model.config()),
                            Catch::Matchers::Contains("needs the frame's front direct light"));

        // Device in, device out: the direct light is read from the planes on the device.
        DeviceBuffer in = upload_planes(dev, fr, model);
        FrameOutputs outs;
        outs.tonemap = tm;
        outs.lightmap = DeviceBuffer::allocate(dev, d.size() * sizeof(float));
        outs.final_image = DeviceBuffer::allocate(dev, d.size() * sizeof(float));
        pl.enqueue(model, in, FrameDesc::of(fr, model.config().input_nc == 12 ? 6 : 1), outs);
        REQUIRE(read_back(outs.lightmap) == r.lightmap.data);
        REQUIRE(read_back(outs.final_image) == r.final_image.data);
    }
}
