// An out-of-tree C++ consumer of an installed ngi (find_package(ngi), ngi::pipeline): one frame through the
// surround pipeline from host planes, and the same from device buffers with zero host transfers.
#include <cmath>
#include <cstdio>
#include <ngi/device_buffer.hpp>
#include <ngi/model.hpp>
#include <ngi/pipeline.hpp>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s surround.safetensors\n", argv[0]);
        return 2;
    }
    try {
        ngi::Device device = ngi::Device::open();
        ngi::Model model = ngi::Model::load(device, argv[1]);
        const int n = 64;
        ngi::SurroundPipeline pipeline(device, n);
        std::vector<float> planes(ngi::frame_planes_bytes(n, 6) / sizeof(float), 0.5f);
        ngi::FrameDesc desc;
        const ngi::FrameImages host = pipeline.run(model, planes.data(), planes.size() * sizeof(float), desc, true,
                                                   false, false);
        ngi::DeviceBuffer in = ngi::DeviceBuffer::allocate(device, planes.size() * sizeof(float));
        in.upload(planes.data(), in.bytes());
        ngi::FrameOutputs outs;
        outs.lightmap = ngi::DeviceBuffer::allocate(device, host.lightmap.data.size() * sizeof(float));
        const ngi::HostTransfers t0 = device.host_transfers();
        pipeline.enqueue(model, in, desc, outs);
        device.finish();
        const ngi::HostTransfers t1 = device.host_transfers();
        std::vector<float> light(host.lightmap.data.size());
        outs.lightmap.download(light.data(), outs.lightmap.bytes());
        if (light != host.lightmap.data || t1.uploads != t0.uploads || t1.downloads != t0.downloads) {
            std::fprintf(stderr, "c++ consumer: device path differs from the host path or moved data\n");
            return 1;
        }
        std::printf("c++ consumer: %s, %dx%d lightmap, device path equal, 0 host transfers\n",
                    device.info().name.c_str(), n, n);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "c++ consumer: %s\n", e.what());
        return 1;
    }
    return 0;
}
