// DeviceBvh: a Bvh on a device and batches of rays through kernels/bvh.cl (tests and perf/bench_bvh).
#include <chrono>
#include <cstring>

#include "ngi/error.hpp"
#include "render/bvh.hpp"
#include "runtime/context.hpp"

namespace ngi::detail {

struct DeviceBvh::Impl {
    std::shared_ptr<Context> ctx;
    Buffer nodes, tris, info, normals;
    std::vector<std::uint32_t> order;
    Kernel kernel;
    Buffer rays, hits, steps;
    std::size_t capacity = 0;
};

DeviceBvh::DeviceBvh(const Device& device, const Bvh& bvh) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.ctx = shared_context_of(device);
    m.order = bvh.order;
    auto upload = [&](const void* data, std::size_t bytes, const char* what) {
        const std::vector<float> zero(8, 0.0f);  // OpenCL refuses zero-sized buffers
        if (bytes == 0) {
            data = zero.data();
            bytes = zero.size() * 4;
        }
        Buffer b = m.ctx->alloc(bytes, what);
        m.ctx->write(b, 0, bytes, data, what);
        return b;
    };
    m.nodes = upload(bvh.nodes.data(), bvh.nodes.size() * 4, "bvh: nodes");
    m.tris = upload(bvh.tri_vertices.data(), bvh.tri_vertices.size() * 4, "bvh: triangles");
    m.info = upload(bvh.tri_info.data(), bvh.tri_info.size() * 4, "bvh: triangle materials");
    m.normals = upload(bvh.vertex_normals.data(), bvh.vertex_normals.size() * 4, "bvh: vertex normals");
}

DeviceBvh::~DeviceBvh() = default;
const Buffer& DeviceBvh::nodes() const { return impl_->nodes; }
const Buffer& DeviceBvh::triangles() const { return impl_->tris; }
const Buffer& DeviceBvh::triangle_info() const { return impl_->info; }
const Buffer& DeviceBvh::vertex_normals() const { return impl_->normals; }
DeviceBvh::DeviceBvh(DeviceBvh&&) noexcept = default;
DeviceBvh& DeviceBvh::operator=(DeviceBvh&&) noexcept = default;

std::vector<RayHit> DeviceBvh::trace(const std::vector<float>& rays, bool any, std::vector<std::uint32_t>* steps,
                                     double* device_ms) {
    Impl& m = *impl_;
    if (rays.size() % 8 != 0) throw InputError("bvh trace: rays must be 8 floats each, got " + std::to_string(rays.size()));
    const std::size_t count = rays.size() / 8;
    if (count == 0) return {};
    if (count > std::size_t(INT32_MAX)) throw InputError("bvh trace: too many rays");
    if (count > m.capacity) {
        m.rays = m.ctx->alloc(count * 32, "bvh trace: rays");
        m.hits = m.ctx->alloc(count * 16, "bvh trace: hits");
        m.steps = m.ctx->alloc(count * 4, "bvh trace: steps");
        m.capacity = count;
    }
    // Built at the first query: a renderer holds a DeviceBvh only for its buffers and never pays for this program.
    if (!m.kernel.get()) m.kernel = m.ctx->kernel("bvh", "bvh_trace_rays", bvh_defines());
    m.ctx->write(m.rays, 0, count * 32, rays.data(), "bvh trace: upload rays");
    m.kernel.args(m.nodes, m.tris, int(m.order.size()), m.rays, int(count), int(any), m.hits, m.steps);
    const std::size_t global = count, local = 64;
    const auto t0 = std::chrono::steady_clock::now();
    m.ctx->launch(m.kernel, 1, &global, &local);
    m.ctx->finish();
    if (device_ms) *device_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    std::vector<float> h(count * 4);
    m.ctx->read(m.hits, 0, h.size() * 4, h.data(), "bvh trace: read hits");
    if (steps) {
        steps->resize(count);
        m.ctx->read(m.steps, 0, count * 4, steps->data(), "bvh trace: read steps");
    }
    std::vector<RayHit> out(count);
    for (std::size_t i = 0; i < count; ++i) {
        std::int32_t slot;
        std::memcpy(&slot, &h[4 * i + 1], 4);
        if (slot >= 0 && std::size_t(slot) < m.order.size())
            out[i] = {h[4 * i], std::int32_t(m.order[std::size_t(slot)]), h[4 * i + 2], h[4 * i + 3]};
    }
    return out;
}

}  // namespace ngi::detail
