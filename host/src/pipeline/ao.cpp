// Seed 001's AO network: ring gather (kernels/ao.cl) -> per-pixel MLP (the "mlp" family) -> clamp and mask.
#include "ngi/ao.hpp"

#include <algorithm>
#include <climits>
#include <cmath>

#include "models/model_access.hpp"
#include "ngi/error.hpp"
#include "runtime/context.hpp"

namespace ngi {

static_assert(AoNetwork::kRingPoints == detail::kAoNeighbours, "the AO model file's ring is the network's input");

struct AoNetwork::Impl {
    Device device;
    Model model;
    std::string path;
    std::string normals = "smooth";
    float radius = 0;
    int at_size = 0;
    detail::Kernel gather, finish;
    detail::Buffer offsets;
    DeviceBuffer inputs, raw;  // one band's [48][rows][w] and [rows][w], grown on demand
    std::size_t band_pixels = AoNetwork::kDefaultBandPixels;
    Impl(Device d, Model m) : device(std::move(d)), model(std::move(m)) {}
};

AoNetwork::AoNetwork(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
AoNetwork::AoNetwork(AoNetwork&&) noexcept = default;
AoNetwork& AoNetwork::operator=(AoNetwork&&) noexcept = default;
AoNetwork::~AoNetwork() = default;

AoNetwork AoNetwork::load(const Device& device, const std::string& path, const ModelOptions& options) {
    Model model = Model::load(device, path, options);
    const ModelConfig& c = model.config();
    auto fail = [&](const std::string& why) { return InputError("AO model " + path + ": " + why); };
    // A requirement of AoNetwork, not a dispatch: the "ao" metadata and the layers it checks are the mlp family's.
    if (c.family != "mlp") throw fail("family is '" + c.family + "', an AO model is an \"mlp\"");
    if (c.input_nc != 3 * kRingPoints) throw fail("input_nc is " + std::to_string(c.input_nc) + ", expected 48 (16 normals)");
    if (c.mlp.layers.back().out != 1)
        throw fail("the last layer has " + std::to_string(c.mlp.layers.back().out) + " outputs, expected 1");
    // The "ao" object (ring, radius, training size, normals), as the models library read it at load.
    const detail::AoMetadata a = detail::ModelAccess::ao(model, "AO model " + path + ": ");
    auto impl = std::make_unique<Impl>(device, std::move(model));
    impl->normals = a.normals;
    impl->path = path;
    impl->radius = a.radius_px;
    impl->at_size = a.at_size;
    detail::Context& ctx = detail::context_of(device);
    impl->gather = ctx.kernel("ao", "ao_ring_gather");
    impl->finish = ctx.kernel("ao", "ao_finish");
    impl->offsets = ctx.alloc(2 * kRingPoints * sizeof(int), "AO: ring offsets");
    return AoNetwork(std::move(impl));
}

const ModelConfig& AoNetwork::config() const { return impl_->model.config(); }
const std::string& AoNetwork::normals() const { return impl_->normals; }
float AoNetwork::trained_radius_px() const { return impl_->radius; }
int AoNetwork::trained_size() const { return impl_->at_size; }
float AoNetwork::radius_for(int height) const { return impl_->radius * float(height) / float(impl_->at_size); }

std::vector<int> AoNetwork::ring_offsets(float radius_px) {
    std::vector<int> o;
    for (int k = 0; k < kRingPoints; ++k) {
        const double a = 2.0 * M_PI * k / kRingPoints;
        o.push_back(int(std::lround(-double(radius_px) * std::sin(a))));
        o.push_back(int(std::lround(double(radius_px) * std::cos(a))));
    }
    return o;
}

void AoNetwork::enqueue(const DeviceBuffer& normals, const DeviceBuffer& ao, int height, int width, float radius_px) {
    Impl& m = *impl_;
    if (height < 1 || width < 1 || height > 65536 || width > 65536)
        throw InputError("AO " + m.path + ": image size " + std::to_string(width) + "x" + std::to_string(height) +
                         " not in 1..65536");
    if (radius_px < 0) radius_px = radius_for(height);
    if (!std::isfinite(radius_px) || radius_px > 65536.0f)
        throw InputError("AO " + m.path + ": ring radius " + std::to_string(radius_px) + " pixels is not a finite number <= 65536");
    const std::size_t hw = std::size_t(height) * width;
    if (3 * hw > std::size_t(INT_MAX))  // the kernels index the normals with int
        throw InputError("AO " + m.path + ": image size " + std::to_string(width) + "x" + std::to_string(height) +
                         " has more than " + std::to_string(INT_MAX / 3) + " pixels");
    if (normals.bytes() < 3 * hw * sizeof(float))
        throw InputError("AO " + m.path + ": the normals buffer holds " + std::to_string(normals.bytes()) +
                         " bytes, 3 x " + std::to_string(height) + " x " + std::to_string(width) + " floats need " +
                         std::to_string(3 * hw * sizeof(float)));
    if (ao.bytes() < hw * sizeof(float))
        throw InputError("AO " + m.path + ": the output buffer holds " + std::to_string(ao.bytes()) + " bytes, " +
                         std::to_string(hw * sizeof(float)) + " needed");
    detail::Context& ctx = detail::context_of(m.device);
    // Bands of whole rows, at most band_pixels each: the gathered inputs (48 floats a pixel) and the MLP's own
    // buffers scale with the band, not the image (a 4096 x 4096 image once asked for one 3.2 GB buffer).
    const int band_rows = int(std::clamp<std::size_t>(m.band_pixels / std::size_t(width), 1, std::size_t(height)));
    const std::size_t band_px = std::size_t(band_rows) * std::size_t(width);
    if (m.inputs.bytes() < 3 * kRingPoints * band_px * sizeof(float)) {
        m.inputs = DeviceBuffer::allocate(m.device, 3 * kRingPoints * band_px * sizeof(float));
        m.raw = DeviceBuffer::allocate(m.device, band_px * sizeof(float));
    }
    const std::vector<int> off = ring_offsets(radius_px);
    ctx.write(m.offsets, 0, off.size() * sizeof(int), off.data(), "AO: upload ring offsets");
    const int h = height, w = width, points = kRingPoints, total = int(hw);
    for (int row0 = 0; row0 < h; row0 += band_rows) {
        const int rows = std::min(band_rows, h - row0), n = rows * w;
        const std::size_t global = std::size_t(n);
        m.gather.args(normals.opencl_mem(), h, w, row0, rows, m.offsets, points, m.inputs.opencl_mem());
        ctx.launch(m.gather, 1, &global, nullptr);
        m.model.enqueue(m.inputs, m.raw, rows, w);
        m.finish.args(normals.opencl_mem(), m.raw.opencl_mem(), total, row0 * w, n, ao.opencl_mem());
        ctx.launch(m.finish, 1, &global, nullptr);
    }
}

void AoNetwork::set_band_pixels(std::size_t pixels) {
    if (pixels < 1) throw InputError("AO " + impl_->path + ": band size must be at least one pixel");
    impl_->band_pixels = pixels;
}
std::size_t AoNetwork::band_pixels() const { return impl_->band_pixels; }

Image AoNetwork::run(const Image& normals, float radius_px, RunInfo* info) {
    if (normals.channels != 3)
        throw InputError("AO " + impl_->path + ": the normals image has " + std::to_string(normals.channels) +
                         " channels, expected 3 (object-space x, y, z)");
    const std::size_t hw = normals.plane();
    DeviceBuffer in = DeviceBuffer::allocate(impl_->device, std::max<std::size_t>(3 * hw, 1) * sizeof(float));
    DeviceBuffer out = DeviceBuffer::allocate(impl_->device, std::max<std::size_t>(hw, 1) * sizeof(float));
    in.upload(normals.data.data(), 3 * hw * sizeof(float));
    enqueue(in, out, normals.height, normals.width, radius_px);
    Image ao(normals.width, normals.height, 1);
    out.download(ao.data.data(), hw * sizeof(float));
    if (info) info->sanitized_inputs = impl_->model.sanitized_inputs();
    return ao;
}

}  // namespace ngi
