// Image descriptors (ngi/image_desc.hpp): the gather kernel against a naive reference over random formats, strides,
// offsets and row orders at odd sizes; whole frames given as engine-shaped render targets (interleaved RGBA half,
// bottom-up rows, unorm8 normals, device buffers) against the same frame given as a Frame; and every refusal.
#include <cstring>
#include <functional>
#include <limits>

#include "ngi/device_buffer.hpp"
#include "ngi/error.hpp"
#include "ngi/image_desc.hpp"
#include "ngi/model.hpp"
#include "ngi/pipeline.hpp"
#include "base/half.hpp"
#include "ops/gather_image.hpp"
#include "reference_image_desc.hpp"
#include "test_support.hpp"

using namespace ngi;

namespace {

using test::byte_of;
using test::decode;
using test::Layout;
using test::store;
using test::to_half;

ImageDesc host_desc(const Layout& l, int n, const std::vector<unsigned char>& mem) {
    ImageDesc d;
    d.host = mem.data();
    d.host_bytes = mem.size();
    d.format = l.format;
    d.channels = l.channels;
    d.width = d.height = n;
    d.offset = l.offset;
    d.pixel_stride = l.pixel_stride;
    d.row_stride = l.row_stride;
    d.channel_stride = l.channel_stride;
    d.bottom_up = l.bottom_up;
    d.scale = l.scale;
    d.bias = l.bias;
    return d;
}

// A random layout: interleaved (tightly packed or padded pixels and rows) or planar, any format, offset aligned.
Layout random_layout(int n, int need, std::mt19937& rng) {
    Layout l;
    l.format = PixelFormat(std::uniform_int_distribution<int>(0, 3)(rng));
    const std::size_t elem = pixel_format_bytes(l.format);
    l.channels = std::uniform_int_distribution<int>(need, 4)(rng);
    l.offset = elem * std::uniform_int_distribution<std::size_t>(0, 37)(rng);
    if (rng() % 4 == 0) {  // planar: each channel a whole (padded) image after the previous one
        l.pixel_stride = elem * (1 + rng() % 2);
        l.row_stride = l.pixel_stride * std::size_t(n) + elem * (rng() % 5);
        l.channel_stride = l.row_stride * std::size_t(n) + elem * (rng() % 3);
    } else {
        l.channel_stride = elem;
        l.pixel_stride = elem * (std::size_t(l.channels) + rng() % 3);
        l.row_stride = l.pixel_stride * std::size_t(n) + elem * (rng() % 9);
    }
    l.bottom_up = rng() % 2;
    l.scale = rng() % 2 ? 1.0f : 2.0f;
    l.bias = l.scale == 2.0f ? -1.0f : 0.0f;
    return l;
}

const std::string kSurround = std::string(NGI_SOURCE_DIR) + "/models/ladder/gi_surround_n64_ngf16.safetensors";
const std::string kSingle = std::string(NGI_SOURCE_DIR) + "/models/ladder/gi_single_view_n64_ngf16.safetensors";

Frame random_frame(int n, std::mt19937& rng, bool optional_terms) {
    Frame fr;
    fr.n = n;
    fr.look = glm::normalize(glm::vec3(0.2f, -0.1f, -1.0f));
    for (int f = 0; f < kFaceCount; ++f) {
        auto img = [&](int c, float lo, float hi) {
            Image im(n, n, c);
            im.data = test::random_vector(im.data.size(), rng, lo, hi);
            return im;
        };
        fr.get(Feature::Albedo, Face(f)) = img(3, 0.0f, 1.0f);
        fr.get(Feature::Normal, Face(f)) = img(3, -1.0f, 1.0f);
        fr.get(Feature::Depth, Face(f)) = img(1, 0.5f, 60.0f);
        fr.get(Feature::Direct, Face(f)) = img(3, 0.0f, 4.0f);
        if (optional_terms) {
            fr.get(Feature::Emission, Face(f)) = img(3, 0.0f, 0.5f);
            fr.get(Feature::Env, Face(f)) = img(3, 0.0f, 0.3f);
        }
    }
    return fr;
}

// The frame as an engine holds it: per face and feature an interleaved RGBA16F image with padded rows, stored
// bottom-up (OpenGL), depth in an R32F image; `frame` is replaced by the values the half images hold.
struct EngineFrame {
    std::vector<std::vector<unsigned char>> memory;
    FrameInputs inputs;
};

EngineFrame engine_frame(Frame& frame, std::mt19937& rng) {
    const int n = frame.n;
    EngineFrame e;
    e.memory.reserve(std::size_t(kFaceCount) * kFeatureCount);
    e.inputs.look = frame.look;
    e.inputs.up = frame.up;
    for (int f = 0; f < kFaceCount; ++f)
        for (int k = 0; k < kFeatureCount; ++k) {
            Image& im = frame.get(Feature(k), Face(f));
            if (im.data.empty()) continue;
            Layout l;
            l.format = Feature(k) == Feature::Depth ? PixelFormat::F32 : PixelFormat::F16;
            l.channels = Feature(k) == Feature::Depth ? 1 : 4;
            const std::size_t elem = pixel_format_bytes(l.format);
            l.offset = 0;
            l.channel_stride = elem;
            l.pixel_stride = elem * std::size_t(l.channels);
            l.row_stride = l.pixel_stride * std::size_t(n) + 8;  // a pitch that is not the packed row
            l.bottom_up = true;
            l.scale = 1.0f;
            l.bias = 0.0f;
            e.memory.push_back(store(l, n, im, rng));
            e.inputs.at(Face(f), Feature(k)) = host_desc(l, n, e.memory.back());
            if (l.format == PixelFormat::F16)
                for (float& v : im.data) v = detail::half_to_float(to_half(v));
        }
    return e;
}

bool same_bits(const Image& a, const Image& b) {
    return a.data.size() == b.data.size() && std::memcmp(a.data.data(), b.data.data(), a.data.size() * 4) == 0;
}

}  // namespace

TEST_CASE("gather_image: every format, stride, offset and row order against a naive reference", "[image_desc][oclgrind]") {
    detail::Context& ctx = test::ctx();
    detail::GatherImage op(ctx);
    std::mt19937 rng(41);
    for (int trial = 0; trial < 24; ++trial) {
        const int n = std::vector<int>{1, 2, 3, 7, 13, 17, 33}[std::size_t(trial) % 7];
        const int need = trial % 3 == 0 ? 1 : 3;
        const Layout l = random_layout(n, need, rng);
        CAPTURE(trial, n, pixel_format_name(l.format), l.channels, l.offset, l.pixel_stride, l.row_stride,
                l.channel_stride, l.bottom_up, l.scale);
        Image src(n, n, l.channels);
        src.data = test::random_vector(src.data.size(), rng, 0.0f, 1.0f);
        if (l.format == PixelFormat::F32 || l.format == PixelFormat::F16)  // HDR and hostile values pass through
            for (std::size_t i = 0; i < src.data.size(); i += 7) src.data[i] = (i % 3 ? 65504.0f : -3.5f);
        const std::vector<unsigned char> mem = store(l, n, src, rng);
        detail::Buffer buf = ctx.alloc(mem.size(), "test image");
        ctx.write(buf, 0, mem.size(), mem.data(), "test image");
        // The destination has guard planes before and after: nothing outside the gathered planes may change.
        const int plane = n * n, dst_offset = plane + 5;
        const std::vector<float> sentinel(std::size_t(plane) * (need + 2) + 10, -7.0f);
        detail::Buffer dst = test::upload(sentinel);
        op.enqueue(ctx, test::gather_source(l, buf.get()), need, n, dst.get(), dst_offset, plane);
        const std::vector<float> got = test::download(dst, sentinel.size());
        std::vector<float> want = sentinel;
        for (int c = 0; c < need; ++c)
            for (int row = 0; row < n; ++row)
                for (int col = 0; col < n; ++col)
                    want[std::size_t(dst_offset + c * plane + row * n + col)] =
                        decode(mem, byte_of(l, n, row, col, c), l.format) * l.scale + l.bias;
        // Exact but for a possibly fused multiply-add (scale, bias); sRGB codes decode through a table rounded once
        // from double, as the reference does.
        CHECK(test::worst_ratio(got, want, 1e-7, 2e-7) <= 1.0);
    }
}

TEST_CASE("image descriptors: an engine's render targets light a frame exactly as the same frame's planes",
          "[image_desc][frame]") {
    Device& dev = test::device();
    std::mt19937 rng(5);
    const int n = 64;  // the rungs' size
    SurroundPipeline pl(dev, n);
    for (const std::string& path : {kSurround, kSingle}) {
        Model model = Model::load(dev, path);
        for (int variant = 0; variant < 2; ++variant) {
            CAPTURE(path, variant);
            Frame fr = random_frame(n, rng, variant == 1);
            if (variant == 1) {  // hostile values in the half images: NaN, infinities, the largest half
                Image& direct = fr.get(Feature::Direct, Face::Front);
                direct.data[3] = std::numeric_limits<float>::quiet_NaN();
                direct.data[70] = std::numeric_limits<float>::infinity();
                direct.data[400] = 65504.0f;
                fr.get(Feature::Albedo, Face::Left).data[9] = -std::numeric_limits<float>::infinity();
            }
            EngineFrame e = engine_frame(fr, rng);  // fr now holds the half-rounded values
            ToneMapOptions tm;
            tm.exposure_ev = -0.5f;
            PreprocessStats want_stats, got_stats;
            const FrameImages want = pl.run(model, fr, true, true, true, tm, &want_stats);
            FrameTimings timings;
            const FrameImages got = pl.run(model, e.inputs, true, true, true, tm, &got_stats, &timings);
            CHECK(same_bits(got.lightmap, want.lightmap));
            CHECK(same_bits(got.final_image, want.final_image));
            CHECK(same_bits(got.display, want.display));
            CHECK(got_stats.nonfinite == want_stats.nonfinite);
            // NaN and +Inf in the front direct light, -Inf in the left albedo (read by the surround model only).
            CHECK(got_stats.total_nonfinite() == (variant == 0 ? 0 : path == kSurround ? 3 : 2));
            CHECK(timings.gather_ms > 0.0);
            CHECK(timings.network_ms > 0.0);
            CHECK(timings.total_ms() >= timings.network_ms);
        }
    }
}

TEST_CASE("image descriptors: device buffers are gathered with no host transfer, unorm8 normals and sRGB albedo decode",
          "[image_desc][frame]") {
    Device& dev = test::device();
    std::mt19937 rng(9);
    const int n = 64;
    SurroundPipeline pl(dev, n);
    Model model = Model::load(dev, kSingle);
    Frame fr = random_frame(n, rng, false);
    // Front face only (a single-view model). Albedo as RGBA8 sRGB, normals as RGBA8 n/2 + 1/2 (scale 2, bias -1),
    // depth and direct as float: all four in one application buffer at aligned offsets.
    std::vector<unsigned char> all;
    FrameInputs in;
    in.look = fr.look;
    std::vector<std::size_t> at;
    std::vector<Layout> layouts;
    for (Feature k : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct}) {
        Layout l;
        l.format = k == Feature::Albedo ? PixelFormat::U8Srgb : k == Feature::Normal ? PixelFormat::U8Unorm : PixelFormat::F32;
        l.channels = k == Feature::Depth ? 1 : 4;
        const std::size_t elem = pixel_format_bytes(l.format);
        l.offset = 0;
        l.channel_stride = elem;
        l.pixel_stride = elem * std::size_t(l.channels);
        l.row_stride = l.pixel_stride * std::size_t(n);
        l.bottom_up = false;
        l.scale = k == Feature::Normal ? 2.0f : 1.0f;
        l.bias = k == Feature::Normal ? -1.0f : 0.0f;
        Image stored = fr.get(k, Face::Front);
        if (k == Feature::Normal)
            for (float& v : stored.data) v = v * 0.5f + 0.5f;
        if (k == Feature::Albedo)  // the sRGB encoding of the albedo
            for (float& v : stored.data) v = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
        std::vector<unsigned char> mem = store(l, n, stored, rng);
        mem.resize((mem.size() + 255) / 256 * 256);
        // What the frame holds is what the device decodes from those bytes.
        Image& im = fr.get(k, Face::Front);
        for (int c = 0; c < im.channels; ++c)
            for (int p = 0; p < n * n; ++p)
                im.data[std::size_t(c) * n * n + p] = decode(mem, byte_of(l, n, p / n, p % n, c), l.format) * l.scale + l.bias;
        at.push_back(all.size());
        layouts.push_back(l);
        all.insert(all.end(), mem.begin(), mem.end());
    }
    DeviceBuffer buf = DeviceBuffer::allocate(dev, all.size());
    buf.upload(all.data(), all.size());
    int i = 0;
    for (Feature k : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct}) {
        std::vector<unsigned char> none;
        ImageDesc d = host_desc(layouts[std::size_t(i)], n, none);
        d.host = nullptr;
        d.host_bytes = 0;
        d.buffer = buf;
        d.offset = at[std::size_t(i)];
        in.at(Face::Front, k) = d;
        ++i;
    }
    const FrameImages want = pl.run(model, fr, true, false, false);
    DeviceBuffer light = DeviceBuffer::allocate(dev, 3 * std::size_t(n) * n * sizeof(float));
    FrameOutputs outs;
    outs.lightmap = light;
    pl.enqueue(model, in, outs);  // compile and warm up
    const HostTransfers t0 = dev.host_transfers();
    pl.enqueue(model, in, outs);
    dev.finish();
    const HostTransfers t1 = dev.host_transfers();
    CHECK(t1.uploads == t0.uploads);
    CHECK(t1.downloads == t0.downloads);
    std::vector<float> got(3 * std::size_t(n) * n);
    light.download(got.data(), got.size() * sizeof(float));
    // The same bytes decoded on the host and on the device: equal up to the device's pow (the sRGB albedo is a network
    // input: a few ulp there move the lightmap by about as much).
    CHECK(test::worst_ratio(got, want.lightmap.data, 1e-5, 1e-4) <= 1.0);
}

TEST_CASE("image descriptors: bad descriptors are refused naming the face and feature, and nothing runs",
          "[image_desc]") {
    Device& dev = test::device();
    std::mt19937 rng(3);
    const int n = 64;
    SurroundPipeline pl(dev, n);
    Model model = Model::load(dev, kSurround);
    Frame fr = random_frame(n, rng, true);
    EngineFrame good = engine_frame(fr, rng);
    DeviceBuffer light = DeviceBuffer::allocate(dev, 3 * std::size_t(n) * n * sizeof(float));
    const std::vector<float> sentinel(3 * std::size_t(n) * n, -9.0f);
    light.upload(sentinel.data(), light.bytes());
    FrameOutputs outs;
    outs.lightmap = light;

    auto refused = [&](const std::function<void(FrameInputs&)>& spoil, const std::string& words) {
        FrameInputs in = good.inputs;
        spoil(in);
        CAPTURE(words);
        try {
            pl.enqueue(model, in, outs);
            FAIL("accepted");
        } catch (const InputError& e) {
            CAPTURE(e.what());
            CHECK(std::string(e.what()).find(words) != std::string::npos);
        }
    };
    refused([](FrameInputs& in) { in.at(Face::Left, Feature::Normal).pixel_stride = 4; },
            "image 'normal' of face 'left': pixel stride 4 bytes is smaller than the pixel");
    refused([](FrameInputs& in) { in.at(Face::Up, Feature::Albedo).offset = 1u << 30; },
            "image 'albedo' of face 'up': byte offset 1073741824 is past the end");
    refused([](FrameInputs& in) { in.at(Face::Back, Feature::Direct).channels = 2; },
            "image 'direct' of face 'back' has 2 channels; direct needs 3 to 4");
    refused([](FrameInputs& in) { in.at(Face::Back, Feature::Depth).channels = 5; }, "has 5 channels");
    refused([](FrameInputs& in) { in.at(Face::Right, Feature::Depth).width = 32; },
            "image 'depth' of face 'right' is 32x64, but this pipeline's faces are 64x64");
    refused([](FrameInputs& in) { in.at(Face::Down, Feature::Albedo).offset = 1; },
            "image 'albedo' of face 'down': byte offset 1 is not a multiple of 2 bytes");
    refused([](FrameInputs& in) { in.at(Face::Front, Feature::Albedo).row_stride = 100; },
            "row stride 100 bytes is smaller than a row of 64 pixels");
    refused([](FrameInputs& in) {
        ImageDesc& d = in.at(Face::Front, Feature::Albedo);
        d.host_bytes = d.offset + d.span_bytes() - 1;
    }, "image 'albedo' of face 'front' spans bytes [0, ");
    refused([](FrameInputs& in) { in.at(Face::Front, Feature::Depth) = ImageDesc{}; },
            "image 'depth' of face 'front' is missing");
    refused([](FrameInputs& in) { in.at(Face::Up, Feature::Env) = ImageDesc{}; },
            "image 'env' of face 'up' is missing while other faces have one");
    refused([](FrameInputs& in) { in.at(Face::Left, Feature::Albedo).format = PixelFormat(7); },
            "pixel format code 7 is unknown");
    refused([](FrameInputs& in) { in.at(Face::Left, Feature::Albedo).scale = std::numeric_limits<float>::infinity(); },
            "scale and bias must be finite");
    refused([&](FrameInputs& in) { in.at(Face::Left, Feature::Albedo).buffer = light; }, "both a buffer and a host pointer");
    std::vector<float> after(sentinel.size());
    light.download(after.data(), light.bytes());
    CHECK(after == sentinel);
    CHECK_THROWS_WITH(pixel_format_from_name("rgba"), Catch::Contains("unknown pixel format 'rgba'"));
    for (PixelFormat f : {PixelFormat::F32, PixelFormat::F16, PixelFormat::U8Unorm, PixelFormat::U8Srgb})
        CHECK(pixel_format_from_name(pixel_format_name(f)) == f);
}
