// Seed 001: ambient occlusion per pixel from object-space normals with a small MLP (docs/RESULTS_AO.md).
// An AO model is an "mlp" model file with 48 inputs and one output whose metadata has an "ao" object
// (docs/MODEL_FORMAT.md): 16 normals on a circle of radius_px pixels (at an image of at_size rows) around the
// pixel, in the order of docs/CONVENTIONS.md section 15. AoNetwork gathers that ring on the device, runs the MLP
// and clamps the result: accessibility in [0, 1], 1 = unoccluded, 1 on the background (zero normals).
#pragma once
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "ngi/device.hpp"
#include "ngi/device_buffer.hpp"
#include "ngi/image.hpp"
#include "ngi/model.hpp"

namespace ngi {

class AoNetwork {
public:
    static constexpr int kRingPoints = 16;
    // Pixels per band (whole rows) the ring gather and the MLP run over at once: 2^20 pixels hold 192 MiB of
    // gathered inputs (and as much again in the MLP's guarded copy), so any image size fits a device's allocation.
    static constexpr std::size_t kDefaultBandPixels = std::size_t(1) << 20;

    // Throws InputError naming the file if it is not an mlp with 48 inputs, 1 output and valid "ao" metadata.
    static AoNetwork load(const Device& device, const std::string& path, const ModelOptions& options = {});
    AoNetwork(AoNetwork&&) noexcept;
    AoNetwork& operator=(AoNetwork&&) noexcept;
    ~AoNetwork();

    const ModelConfig& config() const;
    float trained_radius_px() const;  // the ring radius of the training data, in its pixels
    // Which normals the network was trained on (metadata ao.normals): "smooth" (Renderer::render_geometry's
    // blurred-occupancy normals, an AO frame folder's normal.npy; the default) or "face" (voxel face normals,
    // face_normal.npy). Feed it the same kind.
    const std::string& normals() const;
    int trained_size() const;         // the training images' height in pixels
    // The training radius scaled to an image of `height` rows (the ring covers the same part of the view).
    float radius_for(int height) const;
    // The 16 ring offsets (row, column) for a radius: round(r cos a) columns, round(-r sin a) rows, a = 2 pi k / 16
    // (half away from zero); radius 0 = the seed's inference (all 16 = the pixel itself).
    static std::vector<int> ring_offsets(float radius_px);

    // normals: 3 x H x W. Returns 1 x H x W. radius_px < 0: radius_for(H). `info` receives the MLP's run
    // information (sanitized inputs: NaN / Inf normal components replaced).
    Image run(const Image& normals, float radius_px = -1.0f, RunInfo* info = nullptr);
    // Device in, device out, asynchronous: `normals` holds [3][height][width] float32, `ao` receives
    // [height][width]; both on this network's device. Nothing is waited for.
    void enqueue(const DeviceBuffer& normals, const DeviceBuffer& ao, int height, int width, float radius_px = -1.0f);
    // Memory for speed: the band size (at least one row is run at once whatever the setting). Results do not
    // depend on it (each pixel's MLP is independent). Throws InputError for 0.
    void set_band_pixels(std::size_t pixels);
    std::size_t band_pixels() const;

private:
    struct Impl;
    explicit AoNetwork(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
};

}  // namespace ngi
