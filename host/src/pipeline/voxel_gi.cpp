// ngi/voxel_gi.hpp: the public face of the LTF (ops/voxel_ltf) and probe shading (ops/probe_shade) ops over one
// scene's surface voxels.
#include "ngi/voxel_gi.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "ngi/error.hpp"
#include "ops/probe_shade.hpp"
#include "ops/voxel_ltf.hpp"
#include "runtime/context.hpp"

namespace ngi {
namespace {

std::vector<float> float4s(const std::vector<glm::vec3>& v) {
    std::vector<float> out(v.size() * 4, 0.0f);
    for (std::size_t i = 0; i < v.size(); ++i) {
        out[4 * i] = v[i].x;
        out[4 * i + 1] = v[i].y;
        out[4 * i + 2] = v[i].z;
    }
    return out;
}

// rgb triples [V][3] -> float4 [V], refusing a wrong length or a value that is not finite (naming `what`).
std::vector<float> rgb_to_float4(const std::vector<float>& rgb, std::size_t voxels, const std::string& what) {
    if (rgb.size() != voxels * 3)
        throw InputError(what + ": " + std::to_string(rgb.size()) + " values, " + std::to_string(voxels) +
                         " voxels need " + std::to_string(voxels * 3));
    std::vector<float> out(voxels * 4, 0.0f);
    for (std::size_t i = 0; i < voxels; ++i)
        for (int c = 0; c < 3; ++c) {
            const float v = rgb[3 * i + std::size_t(c)];
            if (!std::isfinite(v))
                throw InputError(what + ": voxel " + std::to_string(i) + " channel " + std::to_string(c) +
                                 " is not finite");
            out[4 * i + std::size_t(c)] = v;
        }
    return out;
}

}  // namespace

struct VoxelGi::Impl {
    std::shared_ptr<detail::Context> ctx;
    glm::ivec3 grid{0};
    std::size_t voxels = 0;
    detail::Buffer position, normal, albedo, exposed, index_of, direct, out, visibility, field, shaded, depth, normals;
    std::size_t visibility_words = 0;
    std::unique_ptr<detail::VoxelLtf> ltf;
    std::unique_ptr<detail::ProbeShade> shade;

    detail::Buffer upload(const void* data, std::size_t bytes, const char* what) {
        detail::Buffer b = ctx->alloc(std::max<std::size_t>(bytes, 4), what);
        if (bytes) ctx->write(b, 0, bytes, data, what);
        return b;
    }
    // Grows `b` to at least `bytes` (never shrinks: frames and fields of one scene keep their sizes).
    void ensure(detail::Buffer& b, std::size_t bytes, const char* what) {
        if (b.bytes() < bytes) b = ctx->alloc(bytes, what);
    }
};

VoxelGi::VoxelGi(const Device& device, const SurfaceVoxels& v) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.ctx = detail::shared_context_of(device);
    m.grid = v.grid;
    m.voxels = v.size();
    const std::size_t V = m.voxels;
    const std::size_t blocks = std::size_t(v.grid.x) * std::size_t(v.grid.y) * std::size_t(v.grid.z);
    if (V == 0) throw InputError("voxel GI: the scene has no surface voxels");
    if (v.attributes.size() != V * kVoxelAttributes || v.normal.size() != V || v.probe.size() != V ||
        v.exposed.size() != V || v.index_of.size() != blocks)
        throw InputError("voxel GI: inconsistent surface voxels (" + std::to_string(V) + " cells, " +
                         std::to_string(v.attributes.size()) + " attributes, " + std::to_string(v.index_of.size()) +
                         " index entries for " + std::to_string(blocks) + " blocks)");
    std::vector<float> albedo(V * 4, 0.0f);
    for (std::size_t i = 0; i < V; ++i)
        for (int c = 0; c < 3; ++c) albedo[4 * i + std::size_t(c)] = v.attributes[i * kVoxelAttributes + 3 + std::size_t(c)];
    const std::vector<std::uint32_t> exposed(v.exposed.begin(), v.exposed.end());
    // The LTF's voxel positions are the probe points: where each voxel's light is measured (docs/VOXEL_FIELD.md).
    const std::vector<float> pos = float4s(v.probe), nrm = float4s(v.normal);
    m.position = m.upload(pos.data(), pos.size() * 4, "voxel GI: positions");
    m.normal = m.upload(nrm.data(), nrm.size() * 4, "voxel GI: normals");
    m.albedo = m.upload(albedo.data(), albedo.size() * 4, "voxel GI: albedo");
    m.exposed = m.upload(exposed.data(), exposed.size() * 4, "voxel GI: exposed faces");
    m.index_of = m.upload(v.index_of.data(), v.index_of.size() * 4, "voxel GI: voxel index grid");
}

VoxelGi::~VoxelGi() = default;
VoxelGi::VoxelGi(VoxelGi&&) noexcept = default;
VoxelGi& VoxelGi::operator=(VoxelGi&&) noexcept = default;

std::size_t VoxelGi::voxels() const { return impl_->voxels; }
glm::ivec3 VoxelGi::grid() const { return impl_->grid; }

std::vector<float> VoxelGi::ltf(const std::vector<float>& direct, int bounces, LtfVariant variant,
                                const std::vector<std::uint32_t>* visibility, std::vector<double>* energy) {
    Impl& m = *impl_;
    const std::size_t V = m.voxels;
    const std::vector<float> d = rgb_to_float4(direct, V, "voxel LTF: direct lighting");
    m.ensure(m.direct, d.size() * 4, "voxel LTF: direct lighting");
    m.ctx->write(m.direct, 0, d.size() * 4, d.data(), "voxel LTF: upload direct lighting");
    cl_mem vis = nullptr;
    if (visibility) {
        if (variant != LtfVariant::Physical)
            throw InputError("voxel LTF: the paper's LTF has no shadow term; a visibility mask needs the physical "
                             "variant");
        const std::size_t words = V * ((V + 31) / 32);
        if (visibility->size() != words)
            throw InputError("voxel LTF: visibility mask of " + std::to_string(visibility->size()) + " words, " +
                             std::to_string(V) + " voxels need " + std::to_string(words));
        m.ensure(m.visibility, words * 4, "voxel LTF: visibility mask");
        m.ctx->write(m.visibility, 0, words * 4, visibility->data(), "voxel LTF: upload visibility mask");
        vis = m.visibility.get();
    }
    m.ensure(m.out, V * 16, "voxel LTF: lighting");
    if (!m.ltf) m.ltf = std::make_unique<detail::VoxelLtf>(*m.ctx);
    detail::LtfInputs in;
    in.voxels = int(V);
    in.position = m.position.get();
    in.normal = m.normal.get();
    in.albedo = m.albedo.get();
    in.direct = m.direct.get();
    in.exposed = m.exposed.get();
    m.ltf->run(*m.ctx, in, bounces,
               variant == LtfVariant::Physical ? detail::LtfVariant::Physical : detail::LtfVariant::AsWritten, vis,
               m.out.get(), energy);
    std::vector<float> o4(V * 4);
    m.ctx->read(m.out, 0, o4.size() * 4, o4.data(), "voxel LTF: read lighting");
    std::vector<float> rgb(V * 3);
    for (std::size_t i = 0; i < V; ++i)
        for (int c = 0; c < 3; ++c) rgb[3 * i + std::size_t(c)] = o4[4 * i + std::size_t(c)];
    return rgb;
}

Image VoxelGi::shade(const Frame& frame, glm::vec3 camera_position, Face face, const std::vector<float>& field,
                     VoxelFieldKind kind, ShadeStats* stats) {
    Impl& m = *impl_;
    const std::size_t V = m.voxels;
    const int n = frame.n;
    const Image& depth = frame.get(Feature::Depth, face);
    const Image& normal = frame.get(Feature::Normal, face);
    const std::size_t npix = std::size_t(n) * std::size_t(n);
    if (n < 1 || depth.data.size() != npix || normal.data.size() != 3 * npix)
        throw InputError(std::string("voxel GI shading: the frame's depth and normal of the ") + face_name(face) +
                         " face are missing or not " + std::to_string(n) + "x" + std::to_string(n));
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(camera_position[k])) throw InputError("voxel GI shading: the camera position is not finite");
    std::vector<float> f;
    if (kind == VoxelFieldKind::Sh) {
        if (field.size() != V * 27)
            throw InputError("voxel GI shading: SH field of " + std::to_string(field.size()) + " values, " +
                             std::to_string(V) + " voxels need " + std::to_string(V * 27));
        f = field;  // a model output or a file: a non-finite coefficient is refused by name, not shaded
        for (std::size_t i = 0; i < f.size(); ++i)
            if (!std::isfinite(f[i]))
                throw InputError("voxel GI shading: SH coefficient " + std::to_string(i % 27) + " of voxel " +
                                 std::to_string(i / 27) + " is not finite");
    } else {
        f = rgb_to_float4(field, V, "voxel GI shading: per-voxel lighting");
    }
    m.ensure(m.field, f.size() * 4, "voxel GI: field");
    m.ctx->write(m.field, 0, f.size() * 4, f.data(), "voxel GI: upload field");
    m.ensure(m.depth, npix * 4, "voxel GI: depth");
    m.ensure(m.normals, 3 * npix * 4, "voxel GI: normals");
    m.ensure(m.shaded, 3 * npix * 4, "voxel GI: lighting");
    m.ctx->write(m.depth, 0, npix * 4, depth.data.data(), "voxel GI: upload depth");
    m.ctx->write(m.normals, 0, 3 * npix * 4, normal.data.data(), "voxel GI: upload normals");
    const FaceBasis b = CameraCluster::from_look_up(frame.look, frame.up).face(face);
    detail::ProbeShadeInputs in;
    in.n = n;
    in.depth = m.depth.get();
    in.normal = m.normals.get();
    for (int k = 0; k < 3; ++k) {
        in.camera.centre[k] = camera_position[k];
        in.camera.look[k] = b.look[k];
        in.camera.right[k] = b.right[k];
        in.camera.up[k] = b.up[k];
    }
    in.grid[0] = m.grid.x;
    in.grid[1] = m.grid.y;
    in.grid[2] = m.grid.z;
    in.index_of = m.index_of.get();
    in.voxels = int(V);
    in.mode = kind == VoxelFieldKind::Sh ? detail::ProbeField::Sh : detail::ProbeField::PerVoxel;
    in.field = m.field.get();
    if (!m.shade) m.shade = std::make_unique<detail::ProbeShade>(*m.ctx);
    m.shade->enqueue(*m.ctx, in, m.shaded.get(), stats != nullptr);
    if (stats) {
        const detail::ProbeShadeCounts c = m.shade->counts(*m.ctx);
        stats->no_voxel = c.no_voxel;
        stats->non_finite = c.non_finite;
    }
    Image out(n, n, 3);
    m.ctx->read(m.shaded, 0, 3 * npix * 4, out.data.data(), "voxel GI: read lighting");
    return out;
}

}  // namespace ngi
