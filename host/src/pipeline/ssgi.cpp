#include "pipeline/ssgi.hpp"

#include <algorithm>
#include <array>
#include <cfloat>

#include "ngi/error.hpp"
#include "pipeline/frame_planes.hpp"
#include "pipeline/pipeline_impl.hpp"
#include "runtime/kernel_defines.hpp"

namespace ngi::detail {

namespace {

constexpr int kRecordPlanes = 11;  // kernels/ssgi.cl R_PLANES: area, A n (3), A L (3), A p (3), A |p|^2
const Face kFaces[kFaceCount] = {Face::Front, Face::Back, Face::Left, Face::Right, Face::Up, Face::Down};


}  // namespace

std::string ssgi_defines() {
    // The faces' bases in cluster space, defined once (cluster_face_basis): axis vectors, so exact as integers.
    std::array<int, 9 * kFaceCount> faces{};
    for (int f = 0; f < kFaceCount; ++f) {
        const FaceBasis fb = cluster_face_basis(kFaces[f]);
        const glm::vec3 v[3] = {fb.look, fb.right, fb.up};
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c) faces[9 * f + 3 * k + c] = int(v[k][c]);
    }
    return join_defines({frame_plane_defines(), define_list("SSGI_FACE_BASIS", faces),
                         define("SSGI_MAX_DEPTH", kMaxSurfaceDepth),
                         define("SSGI_MIN_COS", kSsgiMinCos), define("SSGI_MAX_RADIANCE", kSsgiMaxRadiance),
                         define("SSGI_LOCAL", kSsgiLocal), define("SSGI_VEC", kSsgiVec),
                         define("SSGI_VIS_SLOPE", kSsgiVisSlope)});
}

Ssgi::Ssgi(Context& ctx)
    : senders_(ctx.kernel("ssgi", "ssgi_senders", ssgi_defines())),
      cluster_(ctx.kernel("ssgi", "ssgi_cluster", ssgi_defines())),
      gather_(ctx.kernel("ssgi", "ssgi_gather", ssgi_defines())) {}

void Ssgi::enqueue(Context& ctx, cl_mem planes, int faces, int n, bool has_emission, const CameraCluster& cluster,
                   const ModelConfig::Ssgi& p, cl_mem lightmap) {
    const int senders = p.view == "front" ? 1 : kFaceCount;
    if (faces < senders)
        throw InputError("ssgi: view \"" + p.view + "\" gathers from " + std::to_string(senders) +
                         " faces, the frame holds " + std::to_string(faces));
    const int b = 1 << p.cluster_level;
    if (n % b != 0)
        throw InputError("ssgi: cluster_level " + std::to_string(p.cluster_level) + " groups " + std::to_string(b) +
                         "x" + std::to_string(b) + " texels, which does not divide the face size N = " +
                         std::to_string(n) + "; use a smaller cluster_level");
    // Records: the texels (fine), their clusters of b x b (coarse, padded to the gather's vector width with zero
    // records that send nothing) and the clusters' quarters of bm x bm (mid; the texels themselves when b = 2).
    const int bm = b > 1 ? b / 2 : 1;
    const std::size_t npix = std::size_t(n) * n, texels = senders * npix;
    const std::size_t fine_count = round_up(texels, std::size_t(kSsgiVec));
    const std::size_t mid_count = texels / (std::size_t(bm) * bm);
    const std::size_t coarse_count = round_up(texels / (std::size_t(b) * b), std::size_t(kSsgiVec));
    const long limit = ctx.loop_limit();
    if (limit > 0 && long(coarse_count / kSsgiVec) > limit)
        throw InputError("ssgi: " + std::to_string(coarse_count) + " sender clusters per receiver exceed this "
                         "device's loop limit of " + std::to_string(limit) + " iterations of " +
                         std::to_string(kSsgiVec) + " per work-item; use a larger cluster_level");
    if (double(kRecordPlanes) * double(fine_count) > 2147483647.0)
        throw InputError("ssgi: face size N = " + std::to_string(n) + " gives more than 2^31 - 1 record values");

    ensure_buffer(ctx, fine_, kRecordPlanes * fine_count * sizeof(float), "ssgi sender records");
    if (b > 2) ensure_buffer(ctx, mid_, kRecordPlanes * mid_count * sizeof(float), "ssgi quarter-cluster records");
    if (b > 1) ensure_buffer(ctx, coarse_, kRecordPlanes * coarse_count * sizeof(float), "ssgi cluster records");
    const Buffer& mid = b > 2 ? mid_ : fine_;
    const Buffer& coarse = b > 1 ? coarse_ : fine_;
    const int mid_stride = int(b > 2 ? mid_count : fine_count), cstride = int(b > 1 ? coarse_count : fine_count);
    const glm::vec3 al = cluster.alpha, be = cluster.beta, ga = cluster.gamma;  // the kernels' SSGI_CLUSTER_ARGS
    const float near2 = p.near_factor * p.near_factor;
    const float min_d2 = std::max(p.min_distance * p.min_distance, FLT_MIN);  // coincident points send nothing
    const float thickness = p.thickness > 0.0f ? p.thickness : FLT_MAX;  // x depth; 0: everything behind is solid
    static const std::size_t local[1] = {kSsgiLocal};
    // Parent record i = the sum of child records [i k, (i + 1) k); zero records past `count` up to `stride`.
    auto sum_children = [&](const Buffer& child, int child_stride, int k, std::size_t count, std::size_t stride,
                            const Buffer& parent) {
        cluster_.args(child, child_stride, k, int(count), int(stride), parent);
        const std::size_t g[1] = {round_up(stride, std::size_t(kSsgiLocal))};
        ctx.launch(cluster_, 1, g, local);
    };

    // Each bounce after the first gathers at every sender face the light of the previous one (a radiosity step over
    // what the cluster sees); the last gathers at the front face into the lightmap.
    if (p.bounces > 1) ensure_buffer(ctx, bounce_, 3 * texels * sizeof(float), "ssgi bounce light");
    for (int bounce = 1; bounce <= p.bounces; ++bounce) {
        const bool last = bounce == p.bounces;
        senders_.args(planes, senders, n, b, al.x, al.y, al.z, be.x, be.y, be.z, ga.x, ga.y, ga.z, int(has_emission), bounce > 1 ? bounce_.get() : fine_.get(),
                      int(bounce > 1), int(fine_count), fine_);
        const std::size_t gs[1] = {round_up(fine_count, std::size_t(kSsgiLocal))};
        ctx.launch(senders_, 1, gs, local);
        if (b > 2) sum_children(fine_, int(fine_count), bm * bm, mid_count, mid_count, mid_);
        if (b > 1) sum_children(mid, mid_stride, 4, texels / (std::size_t(b) * b), coarse_count, coarse_);
        const int faces_out = last ? 1 : senders;
        gather_.args(planes, n, al.x, al.y, al.z, be.x, be.y, be.z, ga.x, ga.y, ga.z, coarse, cstride, mid, mid_stride, fine_, int(fine_count), bm * bm, int(b > 1),
                     near2, min_d2, 0, faces_out, int(last), senders, p.visibility_steps, thickness, b,
                     last ? lightmap : bounce_.get());
        const std::size_t gg[1] = {round_up(std::size_t(faces_out) * npix, std::size_t(kSsgiLocal))};
        ctx.launch(gather_, 1, gg, local);
    }
}

}  // namespace ngi::detail
