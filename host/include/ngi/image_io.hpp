// Image files and the frame folder: OpenEXR (half/float), PNG (8-bit, 16-bit read), NumPy .npy.
//
// Every reader throws InputError naming the file when it cannot be opened, is not a regular file (a directory, a
// device, a FIFO), is larger than 4 GiB, is not of the expected format, is truncated or corrupt, or its header
// promises more pixels than its compressed data can hold. Every writer encodes the whole file in memory, writes it to a temporary file next to
// the target and renames it into place, so a failed write leaves neither a partial file nor a temporary behind.
// Images are planar CHW float, row 0 = top (ngi/image.hpp).
#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "ngi/image.hpp"
#include "ngi/output_folder.hpp"

namespace ngi {

// ---- OpenEXR ------------------------------------------------------------------------------------------------

enum class ExrPixelType { Half, Float };

// The channel names ngi writes for an image with `channels` channels: 1 -> Y; 3 -> R, G, B; 4 -> R, G, B, A;
// any other count -> c0, c1, ..., c<N-1>.
std::vector<std::string> exr_channel_names(int channels);

// Reads every channel of the first part (scanline or tiled; half, float or uint samples, converted to float).
// The image has the size of the display window; pixels of the display window outside the data window are 0.
// Channel order: by layer ("diffuse.R" is channel R of layer "diffuse"; plain names are the unnamed layer, first),
// within a layer R, G, B, then the other names in natural order (c2 before c10, X before Y before Z), then A.
// So RGB(A) files read as R, G, B(, A), and files written by write_exr read back in their original order.
// `channel_names`, when given, receives the names in that order. Subsampled (chroma) channels are rejected.
// NaN and Inf values are returned as stored.
Image read_exr(const std::string& path, std::vector<std::string>* channel_names = nullptr);

// Writes 1..N channels, ZIP-compressed, scanline, named channel_names (one distinct name per channel) or, when
// that is empty, exr_channel_names(). With ExrPixelType::Half, finite values beyond the half range are clamped to
// +-65504 (half has no larger finite value); NaN/Inf are kept.
void write_exr(const std::string& path, const Image& image, ExrPixelType type = ExrPixelType::Half,
               const std::vector<std::string>& channel_names = {});

// ---- PNG ----------------------------------------------------------------------------------------------------

// Linear: sample / (2^bits - 1), no transfer function (the default; gAMA/sRGB/iCCP chunks are ignored).
// Srgb: additionally apply the sRGB EOTF (read) / its inverse (write) to the colour channels; alpha stays linear.
enum class PngEncoding { Linear, Srgb };

// Reads 8- and 16-bit PNGs (1/2/4-bit grey and palettes are expanded to 8 bits, tRNS to an alpha channel).
// Channels: 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA; values in [0, 1].
Image read_png(const std::string& path, PngEncoding encoding = PngEncoding::Linear);

// Writes 8-bit PNG with 1, 2, 3 or 4 channels (grey, grey + alpha, RGB, RGBA). Values are clamped to [0, 1]
// (NaN -> 0) and rounded to the nearest of the 256 levels.
void write_png(const std::string& path, const Image& image, PngEncoding encoding = PngEncoding::Linear);

// ---- any of the above, by extension ---------------------------------------------------------------------------

// .exr (read_exr), .png (read_png, linear), .npy (float32/64/16 with shape [H, W], [C, H, W] or [1, C, H, W]).
// The extension is matched case-insensitively; anything else is an InputError.
Image read_image(const std::string& path);
// .exr (float samples, lossless), .png (8-bit, linear), .npy (float32, shape [C, H, W]).
void write_image(const std::string& path, const Image& image);

// ---- frame folder ---------------------------------------------------------------------------------------------
//
// <dir>/<face>_<feature>.exr   face in {front, back, left, right, up, down},
//                              feature in {albedo, normal, depth, direct, emission, env};
//                              albedo, direct, emission and env may instead be 8/16-bit <face>_<feature>.png,
//                              read linearly (value / (2^bits - 1), no sRGB decode): such files are LDR and
//                              reported in FrameReadStats::ldr_files. Having both the .exr and the .png is an error.
//                              emission and env are optional (docs/CONVENTIONS.md: they then count as 0), but
//                              only as a whole: on all six faces or on none; absent ones stay empty (0x0) Images.
// <dir>/camera.json            {"look": [x, y, z], "up": [x, y, z]} of the front camera; optional "position"
//                              [x, y, z] (the cluster centre, world metres) and "area_light" {"centre", "half_u",
//                              "half_v", "radiance"} (Frame::area_light, checked by check_area_light); other
//                              keys ignored
// <dir>/reference.exr          optional: front-view reference lighting, 3 channels, N x N (the face size;
//                              any other size is an InputError naming both sizes)
//
// All face images must be square and of one size N; channel counts must match feature_channels() (a 3-channel
// feature may carry a 4th channel named A / a PNG alpha channel, which is dropped).
//
// Sanitizing (not fatal; every NaN/Inf value is counted per file in FrameReadStats) follows the preprocessing rules
// of docs/CONVENTIONS.md, so a frame read from disk and the same frame passed in memory give the same network input:
//   albedo                              NaN -> 0, +Inf -> 1, -Inf -> 0
//   normal                              a pixel with any non-finite component -> the zero vector (no surface)
//   depth                               NaN, +Inf -> FLT_MAX (no hit: farther than anything; preprocessing maps
//                                       it to its far plane); negative values (-Inf included) are an InputError
//                                       naming the file and the number of such pixels
//   direct, emission, env, reference    NaN -> 0, -Inf -> 0, +Inf -> FLT_MAX (saturated light)

struct SanitizedFile {
    std::string file;          // file name within the frame folder
    std::size_t nan = 0;       // NaN values replaced
    std::size_t inf = 0;       // +-Inf values replaced
};

struct FrameReadStats {
    std::vector<SanitizedFile> sanitized;  // one entry per file with NaN/Inf values, in read order
    std::vector<std::string> ldr_files;    // features read from PNG
    std::size_t total_sanitized() const;   // sum of nan + inf over all files
};

Frame read_frame(const std::string& dir, FrameReadStats* stats = nullptr);

// Writes every face image (emission / env only when given for all faces; all six empty = absent), camera.json and
// (if present) reference.exr. Pixel types: albedo, direct, emission and
// env as half (11-bit mantissa, more than enough for colours; a file with a finite value beyond the half range
// is written as float instead, so nothing is clamped); normal, depth and reference as float (depth >> 1000 m
// needs float's precision; the reference is what metrics are measured against). Depth is one channel named Y.
// The frame is validated first (sizes, channel counts). The files are written into a fresh <dir>.tmp-<id>
// folder that is renamed to <dir> at the end, so no partial frame folder is ever visible under <dir>. An
// existing <dir> is replaced only if it is empty or a frame folder (holds camera.json); anything else is an
// InputError, so a mistyped path never deletes unrelated files.
void write_frame(const std::string& dir, const Frame& frame);

// write_frame in two steps, for a command that writes a frame folder together with other outputs and commits them
// all or none (OutputFolder::commit_all; ngi probe-gi --write-frame): frame_output_folder makes the OutputFolder of a
// frame folder at <dir> (write_frame's target checks, InputError up front), write_frame_files validates the frame
// and writes its files into that folder's staging area. Nothing is visible under <dir> before the caller commits.
std::unique_ptr<OutputFolder> frame_output_folder(const std::string& dir);
void write_frame_files(const OutputFolder& out, const Frame& frame);

// The target checks of write_frame alone (InputError if <dir> is a file or a non-empty folder without camera.json),
// so that a caller can refuse a bad --out before spending minutes on the render. Writes nothing.
void check_frame_folder_target(const std::string& dir);

}  // namespace ngi
