// An out-of-tree C++ consumer of an installed ngi (find_package(ngi), ngi::pipeline) that owns its OpenCL context:
// it creates its context, in-order queue, G-buffer planes and lightmap buffer in raw OpenCL, runs the surround
// pipeline on them through Device::from_opencl with zero host transfers, reads its own buffer back, and checks the
// result against ngi's host path.
#include <CL/cl.h>

#include <cstdio>
#include <stdexcept>
#include <ngi/device_buffer.hpp>
#include <ngi/model.hpp>
#include <ngi/pipeline.hpp>
#include <vector>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s surround.safetensors\n", argv[0]);
        return 2;
    }
    try {
        const int n = 64;
        std::vector<float> planes(ngi::frame_planes_bytes(n, 6) / sizeof(float));
        for (std::size_t i = 0; i < planes.size(); ++i) planes[i] = float(i % 97) / 97.0f;
        const std::size_t light_bytes = 3 * std::size_t(n) * n * sizeof(float);

        // ngi's host path on a device it opens itself: the reference.
        ngi::Device own = ngi::Device::open();
        ngi::Model own_model = ngi::Model::load(own, argv[1]);
        ngi::SurroundPipeline own_pipeline(own, n);
        const ngi::FrameDesc desc;
        const ngi::FrameImages want = own_pipeline.run(own_model, planes.data(), planes.size() * sizeof(float), desc,
                                                       true, false, false);

        // The application's OpenCL objects, on the same OpenCL device.
        cl_device_id dev = own.opencl_device();
        cl_int err = CL_SUCCESS;
        cl_context ctx = clCreateContext(nullptr, 1, &dev, nullptr, nullptr, &err);
        if (err != CL_SUCCESS) throw std::runtime_error("clCreateContext failed");
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
        cl_command_queue queue = clCreateCommandQueue(ctx, dev, 0, &err);
#pragma GCC diagnostic pop
        cl_mem gbuf = clCreateBuffer(ctx, CL_MEM_READ_ONLY, planes.size() * sizeof(float), nullptr, &err);
        cl_mem lightmap = clCreateBuffer(ctx, CL_MEM_READ_WRITE, light_bytes, nullptr, &err);
        clEnqueueWriteBuffer(queue, gbuf, CL_TRUE, 0, planes.size() * sizeof(float), planes.data(), 0, nullptr, nullptr);

        std::vector<float> got(light_bytes / sizeof(float));
        long long transfers = 0;
        {
            ngi::Device device = ngi::Device::from_opencl(ctx, dev, queue);
            ngi::Model model = ngi::Model::load(device, argv[1]);
            ngi::SurroundPipeline pipeline(device, n);
            ngi::FrameOutputs outs;
            outs.lightmap = ngi::DeviceBuffer::wrap(device, lightmap, 0, light_bytes);
            const ngi::DeviceBuffer in = ngi::DeviceBuffer::wrap(device, gbuf, 0, planes.size() * sizeof(float));
            pipeline.enqueue(model, in, desc, outs);  // first frame: builds, plans, uploads constant tables
            const ngi::HostTransfers t0 = device.host_transfers();
            pipeline.enqueue(model, in, desc, outs);
            const ngi::HostTransfers t1 = device.host_transfers();
            transfers = (t1.uploads - t0.uploads) + (t1.downloads - t0.downloads);
        }
        // The application reads its own buffer on its own queue, after ngi's work in queue order.
        clEnqueueReadBuffer(queue, lightmap, CL_TRUE, 0, light_bytes, got.data(), 0, nullptr, nullptr);
        clReleaseMemObject(gbuf);
        clReleaseMemObject(lightmap);
        clReleaseCommandQueue(queue);
        clReleaseContext(ctx);
        if (got != want.lightmap.data || transfers != 0) {
            std::fprintf(stderr, "c++ consumer: app-owned path differs from the host path or moved data (%lld)\n",
                         transfers);
            return 1;
        }
        std::printf("c++ consumer: %s: the application's cl_mem G-buffers -> its cl_mem lightmap (%dx%d) on its own "
                    "context and queue, 0 host transfers, equal to the host path\n",
                    own.info().name.c_str(), n, n);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "c++ consumer: %s\n", e.what());
        return 1;
    }
    return 0;
}
