#include "ops/probe_shade.hpp"

#include "ops/buffer_checks.hpp"

#include <cmath>
#include <cstdint>
#include <string>

namespace ngi::detail {

namespace {

void require_probe_buffer(cl_mem m, std::size_t need, const std::string& name, const std::string& for_what) {
    detail::require_buffer(m, need, "probe shading", name, for_what);
}

void require_finite(const float* v, const char* name) {
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(v[k])) throw InputError(std::string("probe shading: the camera's ") + name + " is not finite");
}

}  // namespace

ProbeShade::ProbeShade(Context& ctx)
    : kernel_(ctx.kernel("probe_shade", "probe_shade", probe_shade_defines())),
      counts_(ctx.alloc(kProbeCounters * sizeof(std::uint32_t), "probe shading: miss counters")) {}

int ProbeShade::enqueue(Context& ctx, const ProbeShadeInputs& in, cl_mem out, bool read_counts) {
    if (in.n < 1 || in.n > kProbeMaxFace)
        throw InputError("probe shading: face size " + std::to_string(in.n) + " (1 to " + std::to_string(kProbeMaxFace) +
                         " supported)");
    const int X = in.grid[0], Y = in.grid[1], Z = in.grid[2];
    if (X < 1 || Y < 1 || Z < 1 || double(X) * Y * Z > 2147483647.0)
        throw InputError("probe shading: grid " + std::to_string(X) + "x" + std::to_string(Y) + "x" + std::to_string(Z) +
                         " (each side >= 1, at most 2^31 - 1 blocks)");
    if (in.voxels < 0) throw InputError("probe shading: " + std::to_string(in.voxels) + " voxels");
    if (in.mode != ProbeField::Sh && in.mode != ProbeField::PerVoxel)
        throw InputError("probe shading: unknown field mode " + std::to_string(int(in.mode)));
    const ProbeCamera& c = in.camera;
    require_finite(c.centre, "centre");
    require_finite(c.look, "look vector");
    require_finite(c.right, "right vector");
    require_finite(c.up, "up vector");
    if (c.look[0] == 0.0f && c.look[1] == 0.0f && c.look[2] == 0.0f)
        throw InputError("probe shading: the camera's look vector is zero");
    const std::size_t npix = std::size_t(in.n) * in.n;
    const std::string face = std::to_string(in.n) + "x" + std::to_string(in.n) + " face";
    require_probe_buffer(in.depth, npix * sizeof(float), "depth", "a " + face);
    require_probe_buffer(in.normal, 3 * npix * sizeof(float), "normal", "a " + face);
    require_probe_buffer(out, 3 * npix * sizeof(float), "output", "a " + face);
    require_probe_buffer(in.index_of, std::size_t(X) * Y * Z * sizeof(std::int32_t), "index_of", "the grid");
    const std::size_t per_voxel = in.mode == ProbeField::Sh ? 27 : 4;
    if (in.voxels > 0)
        require_probe_buffer(in.field, std::size_t(in.voxels) * per_voxel * sizeof(float),
                       in.mode == ProbeField::Sh ? "SH field" : "per-voxel lighting",
                       std::to_string(in.voxels) + " voxels");
    for (cl_mem m : {in.depth, in.normal, in.index_of, in.field})
        if (m == out) throw InputError("probe shading: the output buffer is also an input");

    ctx.fill_zero(counts_, 0, counts_.bytes(), "probe shading: miss counters");
    kernel_.args(in.depth, in.normal, in.n, c.centre[0], c.centre[1], c.centre[2], c.look[0], c.look[1], c.look[2],
                 c.right[0], c.right[1], c.right[2], c.up[0], c.up[1], c.up[2], X, Y, Z, in.index_of, in.voxels,
                 int(in.mode), in.field ? in.field : in.index_of, out, counts_);
    static const std::size_t local = 64;
    ctx.launch(kernel_, 1, &npix, &local);
    if (!read_counts) return -1;
    return int(counts(ctx).total());
}

ProbeShadeCounts ProbeShade::counts(Context& ctx) const {
    std::uint32_t v[kProbeCounters] = {};
    ctx.read(counts_, 0, sizeof v, v, "probe shading: miss counters");
    ProbeShadeCounts r;
    r.no_voxel = v[kProbeCountNoVoxel];
    r.non_finite = v[kProbeCountNonFinite];
    return r;
}

}  // namespace ngi::detail
