// The global view: where each of its pixels looks (global_view_direction), the lookup tables that merge six
// faces into it and extract the front view from it, and the coordinate map. Layout: docs/CONVENTIONS.md.
#include <algorithm>
#include <cmath>
#include <string>

#include "ngi/error.hpp"
#include "pipeline/pipeline_impl.hpp"

namespace ngi {

namespace {

constexpr float kPi = 3.14159265358979323846f;

// Thesis layout: the side face under global-view column x, and the column inside that face.
// [0, N/2) back (right half) | [N/2, 3N/2) left | [3N/2, 5N/2) front | [5N/2, 7N/2) right | [7N/2, 4N) back
// (left half). Going right in the image turns right in the cluster: back -> left -> front -> right -> back.
struct SideColumn {
    Face face;
    int col;
};

SideColumn thesis_side_column(int x, int n) {
    const int h = n / 2;
    if (x < h) return {Face::Back, x + h};
    if (x < h + n) return {Face::Left, x - h};
    if (x < h + 2 * n) return {Face::Front, x - h - n};
    if (x < h + 3 * n) return {Face::Right, x - h - 2 * n};
    return {Face::Back, x - h - 3 * n};
}

// Middle band of the thesis layout: global-view rows [N/2, 3N/2) are the side faces' rows, unchanged.
bool thesis_middle_band(int y, int n) { return y >= n / 2 && y < n / 2 + n; }

// Bilinear taps of a continuous face position (pixel centres at +0.5), clamped to the face's edge texels.
void face_taps(const FaceSample& s, int n, std::array<int, 4>& idx, std::array<float, 4>& w) {
    const float fx = std::clamp(s.col - 0.5f, 0.0f, float(n - 1)), fy = std::clamp(s.row - 0.5f, 0.0f, float(n - 1));
    const int x0 = int(fx), y0 = int(fy);
    const int x1 = std::min(x0 + 1, n - 1), y1 = std::min(y0 + 1, n - 1);
    const float ax = fx - float(x0), ay = fy - float(y0);
    const int base = int(s.face) * n * n;
    idx = {base + y0 * n + x0, base + y0 * n + x1, base + y1 * n + x0, base + y1 * n + x1};
    w = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
}

void copy_tap(int index, std::array<int, 4>& idx, std::array<float, 4>& w) {
    idx = {index, index, index, index};
    w = {1.0f, 0.0f, 0.0f, 0.0f};
}

void check_n(int n) {
    if (n < 2 || n > 2048 || n % 2 != 0)
        throw InputError("surround pipeline: face size N = " + std::to_string(n) +
                         " is not supported; the global view needs an even N in [2, 2048] (its bands are N/2 high)");
}

}  // namespace

glm::vec3 global_view_direction(int x, int y, int n, GlobalViewMode mode) {
    if (x < 0 || x >= 4 * n || y < 0 || y >= 2 * n)
        throw InputError("global_view_direction: pixel (" + std::to_string(x) + ", " + std::to_string(y) +
                         ") outside the " + std::to_string(4 * n) + "x" + std::to_string(2 * n) + " global view");
    if (mode == GlobalViewMode::Equirect)
        return phi_theta_to_direction((float(x) + 0.5f) / float(4 * n), (float(y) + 0.5f) / float(2 * n));

    const SideColumn sc = thesis_side_column(x, n);
    const FaceBasis b = cluster_face_basis(sc.face);
    if (thesis_middle_band(y, n)) return glm::normalize(face_pixel_direction(b, sc.col, y - n / 2, n));
    // Bands: w is where the side face's column meets its top (bottom) edge, seen from the up (down) face: a
    // point on that face's square perimeter. Band row t in (0, 1) walks from the pole (t -> 0) straight to w
    // (t -> 1), so the band's outer rows are the whole up/down face and its inner edge is the side faces' edge.
    const float u = 2.0f * (float(sc.col) + 0.5f) / float(n) - 1.0f;
    const glm::vec3 w = b.look + u * b.right;  // horizontal, max(|x|, |z|) = 1
    const float h = float(n / 2);
    if (y < n / 2) return glm::normalize((float(y) + 0.5f) / h * w + glm::vec3(0, 1, 0));
    return glm::normalize((float(2 * n - y) - 0.5f) / h * w - glm::vec3(0, 1, 0));
}

glm::vec2 direction_to_phi_theta(glm::vec3 d) {
    // atan2 for theta as well: acos(y / |d|) loses accuracy near the poles.
    const float phi = std::atan2(d.x, -d.z) / (2.0f * kPi) + 0.5f;
    const float theta = std::atan2(std::sqrt(d.x * d.x + d.z * d.z), d.y) / kPi;
    return {phi, theta};
}

glm::vec3 phi_theta_to_direction(float phi, float theta) {
    const float p = (phi - 0.5f) * 2.0f * kPi, t = theta * kPi;
    return {std::sin(t) * std::sin(p), std::cos(t), -std::sin(t) * std::cos(p)};
}

namespace detail {

GatherLut build_merge_lut(int n, GlobalViewMode mode) {
    check_n(n);
    const int w = 4 * n, h = 2 * n;
    GatherLut lut;
    lut.idx.resize(std::size_t(w) * h);
    lut.w.resize(std::size_t(w) * h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const std::size_t p = std::size_t(y) * w + x;
            if (mode == GlobalViewMode::Thesis && thesis_middle_band(y, n)) {
                // An index copy, not a resampling: the side faces appear bit for bit.
                const SideColumn sc = thesis_side_column(x, n);
                copy_tap(int(sc.face) * n * n + (y - n / 2) * n + sc.col, lut.idx[p], lut.w[p]);
            } else {
                face_taps(direction_to_face(global_view_direction(x, y, n, mode), n), n, lut.idx[p], lut.w[p]);
            }
        }
    return lut;
}

GatherLut build_extract_lut(int n, GlobalViewMode mode) {
    check_n(n);
    const int gw = 4 * n, gh = 2 * n;
    GatherLut lut;
    lut.idx.resize(std::size_t(n) * n);
    lut.w.resize(std::size_t(n) * n);
    const FaceBasis front = cluster_face_basis(Face::Front);
    for (int row = 0; row < n; ++row)
        for (int col = 0; col < n; ++col) {
            const std::size_t p = std::size_t(row) * n + col;
            if (mode == GlobalViewMode::Thesis) {
                copy_tap((row + n / 2) * gw + col + n / 2 + n, lut.idx[p], lut.w[p]);  // the exact crop
                continue;
            }
            // Equirect: resample at the front pixel's (phi, theta). The front view spans phi in [3/8, 5/8], so
            // clamping (rather than wrapping) at the left/right image edges never matters.
            const glm::vec2 pt = direction_to_phi_theta(face_pixel_direction(front, col, row, n));
            const float fx = std::clamp(pt.x * float(gw) - 0.5f, 0.0f, float(gw - 1));
            const float fy = std::clamp(pt.y * float(gh) - 0.5f, 0.0f, float(gh - 1));
            const int x0 = int(fx), y0 = int(fy);
            const int x1 = std::min(x0 + 1, gw - 1), y1 = std::min(y0 + 1, gh - 1);
            const float ax = fx - float(x0), ay = fy - float(y0);
            lut.idx[p] = {y0 * gw + x0, y0 * gw + x1, y1 * gw + x0, y1 * gw + x1};
            lut.w[p] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
        }
    return lut;
}

}  // namespace detail

namespace {

void upload_lut(detail::Context& ctx, const detail::GatherLut& lut, detail::Buffer& idx, detail::Buffer& w,
                const char* what) {
    const std::size_t bytes = lut.idx.size() * sizeof(lut.idx[0]);
    static_assert(sizeof(lut.idx[0]) == 16 && sizeof(lut.w[0]) == 16, "int4 / float4 records");
    idx = ctx.alloc(bytes, what);
    w = ctx.alloc(bytes, what);
    ctx.write(idx, 0, bytes, lut.idx.data(), what);
    ctx.write(w, 0, bytes, lut.w.data(), what);
}

}  // namespace

SurroundPipeline::SurroundPipeline(const Device& device, int n, GlobalViewMode mode, LuminationTransfer transfer) {
    check_n(n);
    impl_ = std::make_unique<Impl>(device, n, mode, transfer);
    {
        // The tables are built on the host (an int4 and a float4 per pixel of the 4N x 2N view: 256 N^2 bytes, 1 GiB
        // at N = 2048), then copied to the device: held in the ledger while they exist.
        const std::uint64_t table = 32ull * 8 * std::uint64_t(n) * std::uint64_t(n);
        const HostMemoryHold building("build the global view merge table for N = " + std::to_string(n), table);
        upload_lut(impl_->ctx, detail::build_merge_lut(n, mode), impl_->merge_idx, impl_->merge_w,
                   "global view merge table");
    }
    upload_lut(impl_->ctx, detail::build_extract_lut(n, mode), impl_->extract_idx, impl_->extract_w,
               "front view extraction table");
    Image& c = impl_->coords;
    impl_->coords_hold = HostMemoryHold("the global view's coordinates for N = " + std::to_string(n),
                                        4ull * 2 * 2 * sizeof(float) * std::uint64_t(n) * std::uint64_t(n));
    c = Image(4 * n, 2 * n, 2);
    for (int y = 0; y < c.height; ++y)
        for (int x = 0; x < c.width; ++x) {
            const glm::vec2 pt = direction_to_phi_theta(global_view_direction(x, y, n, mode));
            c.at(0, y, x) = pt.x;
            c.at(1, y, x) = pt.y;
        }
}

Image SurroundPipeline::global_view(const Frame& frame, Feature feature) {
    Impl& im = *impl_;
    const int n = im.n, channels = feature_channels(feature);
    const std::size_t face_plane = std::size_t(n) * n, stack_plane = face_plane * kFaceCount;
    // Faces stacked as [channel][face][row][col] on the device: one table index (face, row, col) serves every
    // channel. Each face plane is uploaded straight from the frame.
    for (int f = 0; f < kFaceCount; ++f)
        detail::check_face_image(frame.get(feature, Face(f)), feature, Face(f), n, "global view");
    detail::ensure_buffer(im.ctx, im.raw, stack_plane * channels * sizeof(float), "global view input");
    for (int f = 0; f < kFaceCount; ++f) {
        const Image& src = frame.get(feature, Face(f));
        for (int c = 0; c < channels; ++c)
            im.ctx.write(im.raw, (c * stack_plane + f * face_plane) * sizeof(float), face_plane * sizeof(float),
                         &src.data[c * face_plane], "global view input");
    }
    Image out(4 * n, 2 * n, channels);
    detail::ensure_buffer(im.ctx, im.out, out.data.size() * sizeof(float), "global view");
    im.gather_planes(im.raw.get(), int(stack_plane), im.merge_idx, im.merge_w, int(out.plane()), channels, im.out.get(),
                     int(out.plane()));
    im.ctx.read(im.out, 0, out.data.size() * sizeof(float), out.data.data(), "global view");
    return out;
}

}  // namespace ngi
