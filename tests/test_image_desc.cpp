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
using test::octahedral_decode;
using test::octahedral_encode;
using test::perspective_depth;
using test::to_half;
using test::window_depth;

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
    d.normal_encoding = l.normal_encoding;
    d.normal_to_world = l.normal_to_world;
    d.depth_encoding = l.depth_encoding;
    d.near_m = l.near_m;
    d.far_m = l.far_m;
    d.reversed_z = l.reversed_z;
    return d;
}

// A random layout: interleaved (tightly packed or padded pixels and rows) or planar, any format (packed formats: one
// word per pixel, padded or not), offset aligned.
Layout random_layout(int n, int need, std::mt19937& rng) {
    Layout l;
    l.format = PixelFormat(std::uniform_int_distribution<int>(0, 7)(rng));
    const std::size_t elem = pixel_format_bytes(l.format);
    const int packed = pixel_format_packed_channels(l.format);
    l.channels = packed ? packed : std::uniform_int_distribution<int>(need, 4)(rng);
    l.offset = elem * std::uniform_int_distribution<std::size_t>(0, 37)(rng);
    if (packed) {  // the channels share the pixel's word
        l.channel_stride = 0;
        l.pixel_stride = elem * (1 + rng() % 2);
        l.row_stride = l.pixel_stride * std::size_t(n) + elem * (rng() % 5);
    } else if (rng() % 4 == 0) {  // planar: each channel a whole (padded) image after the previous one
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
    for (int trial = 0; trial < 40; ++trial) {
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
                        decode(mem, byte_of(l, n, row, col, c), l.format, c) * l.scale + l.bias;
        // Exact but for a possibly fused multiply-add (scale, bias); sRGB codes decode through a table rounded once
        // from double, as the reference does.
        CHECK(test::worst_ratio(got, want, 1e-7, 2e-7) <= 1.0);
    }
}

TEST_CASE("gather_image: octahedral and view-space normals, perspective depth against a naive reference",
          "[image_desc][oclgrind]") {
    detail::Context& ctx = test::ctx();
    detail::GatherImage op(ctx);
    std::mt19937 rng(43);
    const double eps = std::numeric_limits<float>::epsilon();
    // Normals: the octahedral map stored as float, half, snorm16 or unorm16 (scale 2, bias -1), two channels or four
    // (padding), with a random rotation (view -> world) or none.
    const PixelFormat normal_formats[] = {PixelFormat::F32, PixelFormat::F16, PixelFormat::S16Snorm,
                                          PixelFormat::U16Unorm, PixelFormat::U8Unorm};
    for (int trial = 0; trial < 10; ++trial) {
        const int n = std::vector<int>{1, 3, 7, 13, 17}[std::size_t(trial) % 5];
        Layout l;
        l.format = normal_formats[trial % 5];
        const std::size_t elem = pixel_format_bytes(l.format);
        l.channels = trial % 2 ? 4 : 2;
        l.offset = elem * std::size_t(trial);
        l.channel_stride = elem;
        l.pixel_stride = elem * std::size_t(l.channels);
        l.row_stride = l.pixel_stride * std::size_t(n) + elem * std::size_t(trial % 3);
        l.bottom_up = trial % 3 == 0;
        const bool unorm = l.format == PixelFormat::U16Unorm || l.format == PixelFormat::U8Unorm;
        l.scale = unorm ? 2.0f : 1.0f;
        l.bias = unorm ? -1.0f : 0.0f;
        l.normal_encoding = NormalEncoding::Octahedral;
        glm::dmat3 rot(1.0);
        if (trial >= 4) {  // a random rotation: an orthonormal basis from Gram-Schmidt
            glm::dvec3 a(test::random_vector(3, rng, -1, 1)[0], 0.3, 0.8), b(0.1, test::random_vector(1, rng, -1, 1)[0], -0.4);
            a = glm::normalize(a);
            b = glm::normalize(b - glm::dot(a, b) * a);
            rot = glm::dmat3(a, b, glm::cross(a, b));
            l.normal_to_world = glm::mat3(rot);
        }
        CAPTURE(trial, n, pixel_format_name(l.format), l.channels);
        Image src(n, n, l.channels);
        for (int p = 0; p < n * n; ++p) {
            const std::vector<float> r = test::random_vector(3, rng, -1, 1);
            glm::dvec3 v(r[0], r[1], r[2]);
            if (p % 5 == 0) v = glm::dvec3(0, 0, p % 2 ? 1 : -1);  // the poles and the fold
            if (glm::length(v) < 1e-3) v = {1, 0, 0};
            const glm::dvec2 e = octahedral_encode(glm::normalize(v));
            src.data[std::size_t(p)] = float(unorm ? e.x * 0.5 + 0.5 : e.x);
            src.data[std::size_t(n * n + p)] = float(unorm ? e.y * 0.5 + 0.5 : e.y);
        }
        const std::vector<unsigned char> mem = store(l, n, src, rng);
        detail::Buffer buf = ctx.alloc(mem.size(), "test normals");
        ctx.write(buf, 0, mem.size(), mem.data(), "test normals");
        const int plane = n * n;
        const std::vector<float> sentinel(std::size_t(plane) * 3 + 4, -7.0f);
        detail::Buffer dst = test::upload(sentinel);
        op.enqueue(ctx, test::gather_source(l, buf.get()), 3, n, dst.get(), 2, plane);
        const std::vector<float> got = test::download(dst, sentinel.size());
        std::vector<float> want = sentinel;
        for (int row = 0; row < n; ++row)
            for (int col = 0; col < n; ++col) {
                const double x = double(decode(mem, byte_of(l, n, row, col, 0), l.format)) * l.scale + l.bias;
                const double y = double(decode(mem, byte_of(l, n, row, col, 1), l.format)) * l.scale + l.bias;
                const glm::dvec3 w = rot * octahedral_decode({x, y});  // world = R v (glm's product)
                for (int c = 0; c < 3; ++c) want[std::size_t(2 + c * plane + row * n + col)] = float(w[c]);
            }
        // float32 decode, normalize and rotation: a few ulp of a unit vector's components.
        CHECK(test::worst_ratio(got, want, 8 * eps, 0.0) <= 1.0);
    }
    // Depth: window depth of a perspective projection, standard or reversed, finite or infinite far plane, stored as
    // float32 (a D32F attachment) or unorm16 (D16), with cleared pixels (no surface).
    for (int trial = 0; trial < 12; ++trial) {
        const int n = std::vector<int>{2, 5, 9, 16}[std::size_t(trial) % 4];
        const bool reversed = trial % 2, infinite = trial % 3 == 2;
        const double near_m = trial % 4 < 2 ? 0.1 : 0.5, far_m = infinite ? INFINITY : (trial % 4 == 1 ? 100.0 : 1000.0);
        Layout l;
        l.format = trial >= 8 ? PixelFormat::U16Unorm : PixelFormat::F32;
        const std::size_t elem = pixel_format_bytes(l.format);
        l.channels = 1;
        l.offset = elem * 3;
        l.channel_stride = elem;
        l.pixel_stride = elem;
        l.row_stride = elem * std::size_t(n + trial % 3);
        l.bottom_up = trial % 2 == 0;
        l.scale = 1.0f;
        l.bias = 0.0f;
        l.depth_encoding = DepthEncoding::Perspective;
        l.near_m = float(near_m);
        l.far_m = float(far_m);
        l.reversed_z = reversed;
        CAPTURE(trial, n, pixel_format_name(l.format), reversed, near_m, far_m);
        Image src(n, n, 1);
        for (int p = 0; p < n * n; ++p) {
            const double z = near_m * std::exp(test::random_vector(1, rng, 0.0f, 7.0f)[0]);  // 1x .. 1100x near
            const bool cleared = p % 7 == 3 || (!infinite && z >= far_m);
            src.data[std::size_t(p)] = float(cleared ? (reversed ? 0.0 : 1.0) : window_depth(z, near_m, far_m, reversed));
        }
        const std::vector<unsigned char> mem = store(l, n, src, rng);
        detail::Buffer buf = ctx.alloc(mem.size(), "test depth");
        ctx.write(buf, 0, mem.size(), mem.data(), "test depth");
        detail::Buffer dst = test::upload(std::vector<float>(std::size_t(n) * n, -7.0f));
        op.enqueue(ctx, test::gather_source(l, buf.get()), 1, n, dst.get(), 0, n * n);
        const std::vector<float> got = test::download(dst, std::size_t(n) * n);
        int cleared = 0;
        for (int row = 0; row < n; ++row)
            for (int col = 0; col < n; ++col) {
                const double d = decode(mem, byte_of(l, n, row, col, 0), l.format);
                const double want = perspective_depth(d, near_m, far_m, reversed);
                const float g = got[std::size_t(row * n + col)];
                INFO("row " << row << " col " << col << " window depth " << d << ": got " << g << ", want " << want);
                if (want == detail::kNoSurfaceDepth) {
                    CHECK(g == detail::kNoSurfaceDepth);
                    ++cleared;
                    continue;
                }
                // The kernel's float32 z = near / (1 - d k), k = 1 - near / far: a few roundings, amplified by the
                // cancellation in 1 - d k (its condition number d k / (1 - d k), at most z / near). Reversed Z,
                // z = near / (d k + near / far), has no cancellation: a few roundings.
                const double k = std::isinf(far_m) ? 1.0 : 1 - near_m / far_m;
                const double bound = 4 * eps * (reversed ? 1.0 : 1 + d * k / (1 - d * k)) * want;
                CHECK(std::abs(double(g) - want) <= bound);
            }
        CHECK(cleared > 0);
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

TEST_CASE("image descriptors: a GL engine's attachments as rendered (perspective depth, octahedral view-space "
          "normals, RGB10A2, R11G11B10F) light a frame as their decoded planes", "[image_desc][frame]") {
    Device& dev = test::device();
    std::mt19937 rng(17);
    const int n = 64;
    SurroundPipeline pl(dev, n);
    Model model = Model::load(dev, kSingle);
    Frame fr = random_frame(n, rng, false);
    const double near_m = 0.05;
    const glm::dmat3 view_to_world(glm::dvec3(0.6, 0, -0.8), glm::dvec3(0, 1, 0), glm::dvec3(0.8, 0, 0.6));
    FrameInputs in;
    in.look = fr.look;
    std::vector<std::vector<unsigned char>> memory;
    memory.reserve(4);
    for (Feature k : {Feature::Albedo, Feature::Normal, Feature::Depth, Feature::Direct}) {
        Layout l;
        l.format = k == Feature::Albedo   ? PixelFormat::RGB10A2Unorm
                   : k == Feature::Normal ? PixelFormat::S16Snorm
                   : k == Feature::Depth  ? PixelFormat::F32
                                          : PixelFormat::R11G11B10F;
        const std::size_t elem = pixel_format_bytes(l.format);
        const int packed = pixel_format_packed_channels(l.format);
        l.channels = packed ? packed : k == Feature::Normal ? 2 : 1;
        l.offset = 0;
        l.channel_stride = packed ? 0 : elem;
        l.pixel_stride = packed ? elem : elem * std::size_t(l.channels);
        l.row_stride = l.pixel_stride * std::size_t(n) + 16;
        l.bottom_up = true;
        l.scale = 1.0f;
        l.bias = 0.0f;
        Image& im = fr.get(k, Face::Front);
        Image stored(n, n, l.channels);
        for (int p = 0; p < n * n; ++p) {
            if (k == Feature::Normal) {  // view space: v = R^-1 n, octahedral
                const glm::dvec3 nw(im.data[std::size_t(p)], im.data[std::size_t(n * n + p)], im.data[std::size_t(2 * n * n + p)]);
                const glm::dvec2 e = octahedral_encode(glm::transpose(view_to_world) * glm::normalize(nw));
                stored.data[std::size_t(p)] = float(e.x);
                stored.data[std::size_t(n * n + p)] = float(e.y);
            } else if (k == Feature::Depth) {  // reversed Z, infinite far plane; one pixel in 9 cleared (sky)
                stored.data[std::size_t(p)] = p % 9 == 4 ? 0.0f : float(window_depth(im.data[std::size_t(p)], near_m, INFINITY, true));
            } else {
                for (int c = 0; c < l.channels; ++c)
                    stored.data[std::size_t(c * n * n + p)] = c < 3 ? im.data[std::size_t(c * n * n + p)] : 1.0f;
            }
        }
        if (k == Feature::Normal) {
            l.normal_encoding = NormalEncoding::Octahedral;
            l.normal_to_world = glm::mat3(view_to_world);  // world = M v (glm's product, M[column][row])
        }
        if (k == Feature::Depth) {
            l.depth_encoding = DepthEncoding::Perspective;
            l.near_m = float(near_m);
            l.far_m = INFINITY;
            l.reversed_z = true;
        }
        memory.push_back(store(l, n, stored, rng));
        const std::vector<unsigned char>& mem = memory.back();
        // What the frame holds is what the reference decodes from those bytes.
        for (int p = 0; p < n * n; ++p) {
            const int row = p / n, col = p % n;
            if (k == Feature::Normal) {
                const glm::dvec3 w = view_to_world * octahedral_decode({decode(mem, byte_of(l, n, row, col, 0), l.format),
                                                                        decode(mem, byte_of(l, n, row, col, 1), l.format)});
                for (int c = 0; c < 3; ++c) im.data[std::size_t(c * n * n + p)] = float(w[c]);
            } else if (k == Feature::Depth) {
                im.data[std::size_t(p)] =
                    float(perspective_depth(decode(mem, byte_of(l, n, row, col, 0), l.format), near_m, INFINITY, true));
            } else {
                for (int c = 0; c < 3; ++c)
                    im.data[std::size_t(c * n * n + p)] = decode(mem, byte_of(l, n, row, col, c), l.format, c);
            }
        }
        in.at(Face::Front, k) = host_desc(l, n, mem);
    }
    CHECK(fr.get(Feature::Depth, Face::Front).data[4] == detail::kNoSurfaceDepth);
    // The octahedral map has no "no surface": where the depth attachment was cleared the normal is the zero vector.
    for (int p = 0; p < n * n; ++p)
        if (fr.get(Feature::Depth, Face::Front).data[std::size_t(p)] == detail::kNoSurfaceDepth)
            for (int c = 0; c < 3; ++c) fr.get(Feature::Normal, Face::Front).data[std::size_t(c * n * n + p)] = 0.0f;
    const FrameImages want = pl.run(model, fr, true, false, false);
    const FrameImages got = pl.run(model, in, true, false, false);
    // The same bytes decoded in double on the host and in float32 on the device (normalize, a rotation, a
    // division): a few ulp in the network's input, about as much in its lightmap.
    CHECK(test::worst_ratio(got.lightmap.data, want.lightmap.data, 1e-5, 1e-4) <= 1.0);
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
    refused([](FrameInputs& in) { in.at(Face::Left, Feature::Albedo).format = PixelFormat(8); },
            "pixel format code 8 is unknown");
    refused([](FrameInputs& in) { in.at(Face::Left, Feature::Albedo).scale = std::numeric_limits<float>::infinity(); },
            "scale and bias must be finite");
    refused([&](FrameInputs& in) { in.at(Face::Left, Feature::Albedo).buffer = light; }, "both a buffer and a host pointer");
    // Engine formats and encodings the feature cannot take (issue 48).
    refused([](FrameInputs& in) {
        ImageDesc& d = in.at(Face::Back, Feature::Depth);
        d.format = PixelFormat::U16Unorm;
        d.pixel_stride = d.row_stride = 0;
    }, "image 'depth' of face 'back': format u16 cannot hold linear depth in metres; a depth attachment in it needs "
       "the perspective encoding");
    refused([](FrameInputs& in) {
        ImageDesc& d = in.at(Face::Back, Feature::Depth);
        d.depth_encoding = DepthEncoding::Perspective;
        d.near_m = 0.0f;
        d.far_m = 100.0f;
    }, "image 'depth' of face 'back': the perspective depth encoding needs 0 < near_m < far_m");
    refused([](FrameInputs& in) { in.at(Face::Back, Feature::Normal).depth_encoding = DepthEncoding::Perspective; },
            "image 'normal' of face 'back': the perspective depth encoding applies to depth only");
    refused([](FrameInputs& in) { in.at(Face::Back, Feature::Albedo).normal_encoding = NormalEncoding::Octahedral; },
            "image 'albedo' of face 'back': the octahedral encoding applies to normals only");
    refused([](FrameInputs& in) { in.at(Face::Back, Feature::Direct).normal_to_world[0][0] = 2.0f; },
            "a normal rotation (normal_to_world) applies to normals only");
    refused([](FrameInputs& in) { in.at(Face::Back, Feature::Normal).normal_to_world[1][2] = NAN; },
            "image 'normal' of face 'back': normal_to_world has a non-finite entry");
    refused([](FrameInputs& in) {
        ImageDesc& d = in.at(Face::Back, Feature::Direct);
        d.format = PixelFormat::R11G11B10F;
        d.channel_stride = d.pixel_stride = 0;
    }, "format r11g11b10f packs 3 channels in each pixel's word, but the descriptor says 4");
    refused([](FrameInputs& in) {
        ImageDesc& d = in.at(Face::Back, Feature::Direct);
        d.format = PixelFormat::RGB10A2Unorm;
        d.channel_stride = 4;
    }, "format rgb10a2 packs its channels in one word per pixel: channel_stride must be 0");
    refused([](FrameInputs& in) { in.at(Face::Back, Feature::Normal).normal_encoding = NormalEncoding(5); },
            "normal encoding code 5 is unknown");
    std::vector<float> after(sentinel.size());
    light.download(after.data(), light.bytes());
    CHECK(after == sentinel);
    CHECK_THROWS_WITH(pixel_format_from_name("rgba"), Catch::Contains("unknown pixel format 'rgba'"));
    for (int f = 0; f < 8; ++f) CHECK(pixel_format_from_name(pixel_format_name(PixelFormat(f))) == PixelFormat(f));
}
