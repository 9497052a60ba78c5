// ngi-dataset-mpi: `ngi dataset` over MPI ranks (mpirun, srun). Rank 0 prepares the dataset folder (validates the
// config and every scene, writes dataset.json); then every rank renders its shard of the frames (frame k of the
// whole dataset belongs to rank k % size: docs/RENDERER.md "Distributed rendering"), each frame written atomically
// by exactly one rank. The result is the single-process dataset bit for bit, and a killed run resumes with any
// number of ranks. Rank 0 reports the whole job's progress with an ETA (it counts the finished frames on disk).
//
//   mpirun -np K ngi-dataset-mpi --config FILE.json --out DIR [--device D] [--device-per-rank]
//
// Every rank must be given the same config: the ranks compare a hash of it first and refuse to start otherwise.
// Exit codes as the ngi CLI: 0 ok, 1 bad input (on any rank), 2 usage, 3 device failure.
#include <mpi.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <thread>

#include "ngi/dataset.hpp"
#include "ngi/device.hpp"
#include "ngi/error.hpp"

namespace {

enum Status : int { kOk = 0, kInput = 1, kUsage = 2, kDevice = 3 };

std::uint64_t fnv1a(const std::string& s) {
    std::uint64_t h = 1469598103934665603ull;
    for (unsigned char c : s) h = (h ^ c) * 1099511628211ull;
    return h;
}

std::string hms(double s) {
    const long t = long(s + 0.5);
    char b[32];
    std::snprintf(b, sizeof b, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    return b;
}

// Runs f, turning ngi's exceptions into a status and a message (printed with the rank).
template <class F>
int guarded(int rank, F&& f) {
    try {
        f();
        return kOk;
    } catch (const ngi::ClError& e) {
        std::fprintf(stderr, "ngi-dataset-mpi rank %d: device error: %s\n", rank, e.what());
        return kDevice;
    } catch (const ngi::OutOfMemoryError& e) {
        std::fprintf(stderr, "ngi-dataset-mpi rank %d: device error: %s\n", rank, e.what());
        return kDevice;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "ngi-dataset-mpi rank %d: error: %s\n", rank, e.what());
        return kInput;
    }
}

int worst(int mine) {  // the highest status over all ranks (collective)
    int all = 0;
    MPI_Allreduce(&mine, &all, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return all;
}

}  // namespace

int main(int argc, char** argv) {
    int provided = 0;  // rank 0 renders in a worker thread while its main thread talks MPI
    MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);

    CLI::App app{"ngi-dataset-mpi: render an ngi dataset over MPI ranks (each frame by exactly one rank)"};
    std::string config_path, out, device_spec;
    bool per_rank = false;
    app.add_option("--config", config_path, "the dataset config (JSON, see configs/)")->required();
    app.add_option("--out", out, "the dataset folder (new, empty, or an earlier run of this config)")->required();
    app.add_option("--device", device_spec, "OpenCL device of every rank (ngi devices); default $NGI_DEVICE, else "
                                            "the first GPU, else the first CPU");
    app.add_flag("--device-per-rank", per_rank, "GPU number = the rank on its node (OMPI_COMM_WORLD_LOCAL_RANK / "
                                                "SLURM_LOCALID) modulo the GPUs: one GPU per rank on multi-GPU nodes");
    int status = kOk;
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        if (rank == 0) app.exit(e);
        MPI_Finalize();
        return 0;
    } catch (const CLI::ParseError& e) {
        if (rank == 0) std::fprintf(stderr, "ngi-dataset-mpi: %s; run with --help for the options\n", e.what());
        status = kUsage;
    }
    if (worst(status) != kOk) {
        MPI_Finalize();
        return kUsage;
    }

    // Same config on every rank (a hash of the file's bytes), else nobody starts.
    ngi::DatasetConfig config;
    std::string text;
    status = guarded(rank, [&] {
        config = ngi::DatasetConfig::load(config_path);
        FILE* f = std::fopen(config_path.c_str(), "rb");
        char buf[4096];
        for (std::size_t n; f && (n = std::fread(buf, 1, sizeof buf, f)) > 0;) text.append(buf, n);
        if (f) std::fclose(f);
    });
    unsigned long long hash = fnv1a(text), lo = 0, hi = 0;
    MPI_Allreduce(&hash, &lo, 1, MPI_UNSIGNED_LONG_LONG, MPI_MIN, MPI_COMM_WORLD);
    MPI_Allreduce(&hash, &hi, 1, MPI_UNSIGNED_LONG_LONG, MPI_MAX, MPI_COMM_WORLD);
    if (status == kOk && lo != hi) {
        std::fprintf(stderr, "ngi-dataset-mpi rank %d: the ranks were given different configs (%s here); every rank "
                             "must render the same dataset\n", rank, config_path.c_str());
        status = kInput;
    }
    if ((status = worst(status)) != kOk) {
        MPI_Finalize();
        return status;
    }

    if (rank == 0) status = guarded(rank, [&] { ngi::prepare_dataset(config, out); });
    if ((status = worst(status)) != kOk) {
        MPI_Finalize();
        return status;
    }

    std::optional<ngi::Device> device;  // opened below, on every rank
    status = guarded(rank, [&] {
        std::string spec = device_spec;
        if (per_rank) {
            const char* local = std::getenv("OMPI_COMM_WORLD_LOCAL_RANK");
            if (!local) local = std::getenv("SLURM_LOCALID");
            int gpus = 0;
            const auto devices = ngi::list_devices();
            for (const auto& d : devices) gpus += d.is_gpu;
            if (gpus > 0) {
                const int pick = (local ? std::atoi(local) : rank) % gpus;
                int seen = 0;
                for (const auto& d : devices)
                    if (d.is_gpu && seen++ == pick)
                        spec = std::to_string(d.platform_index) + ":" + std::to_string(d.device_index);
            }
        }
        device = ngi::Device::open(spec);
    });
    if ((status = worst(status)) != kOk) {
        MPI_Finalize();
        return status;
    }
    if (rank == 0)
        std::fprintf(stderr, "ngi-dataset-mpi: %d ranks, %zu train + %zu test scenes, N = %d, %d spp, rank 0 on %s\n",
                     size, config.train.size(), config.test.size(), config.render.n, config.render.reference_spp,
                     device->info().name.c_str());

    // Rank 0 renders its own shard in a thread and reports the whole job from the files on disk meanwhile; the
    // other ranks only render. A failure on one rank does not stop the others: their frames are kept, and the
    // rerun finishes the job.
    const auto t0 = std::chrono::steady_clock::now();
    int rendered = 0;
    std::atomic<bool> shard_done{false};
    std::thread worker([&] {  // makes no MPI call (MPI_THREAD_FUNNELED)
        status = guarded(rank, [&] {
            ngi::render_dataset(*device, config, out, [&](const ngi::DatasetProgress& p) { rendered = p.frames_rendered; },
                                ngi::DatasetShard{rank, size});
        });
        shard_done = true;
    });
    // Every rank enters a barrier when its shard is done; rank 0 polls it, and the frame count, until all are.
    MPI_Request all_done;
    if (rank == 0) {
        const int before = ngi::count_dataset_frames(config, out).first;
        const bool tty = isatty(STDERR_FILENO);
        bool in_barrier = false;
        auto last = std::chrono::steady_clock::now() - std::chrono::hours(1);
        for (int finished = 0; !finished;) {
            if (!in_barrier && shard_done) {
                worker.join();
                MPI_Ibarrier(MPI_COMM_WORLD, &all_done);
                in_barrier = true;
            }
            if (in_barrier) MPI_Test(&all_done, &finished, MPI_STATUS_IGNORE);
            const auto now = std::chrono::steady_clock::now();
            if (finished || now - last >= std::chrono::seconds(tty ? 1 : 10)) {  // a line per 10 s in a log
                last = now;
                const auto [done, total] = ngi::count_dataset_frames(config, out);
                const double s = std::chrono::duration<double>(now - t0).count();
                const double rate = done > before ? (done - before) / s : 0.0;
                std::fprintf(stderr, "%s%d/%d frames (%d were done before)  %.2f frames/s over %d ranks  ETA %s%s",
                             tty ? "\r" : "", done, total, before, rate, size,
                             rate > 0 ? hms((total - done) / rate).c_str() : "?", tty ? "\x1b[K" : "\n");
            }
            if (!finished) std::this_thread::sleep_for(std::chrono::milliseconds(100));
        }
        if (tty) std::fputc('\n', stderr);
    } else {
        worker.join();
        MPI_Ibarrier(MPI_COMM_WORLD, &all_done);
        MPI_Wait(&all_done, MPI_STATUS_IGNORE);
    }
    const int mine = status;
    int rendered_all = 0;
    MPI_Reduce(&rendered, &rendered_all, 1, MPI_INT, MPI_SUM, 0, MPI_COMM_WORLD);
    status = worst(mine);
    if (rank == 0) {
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        if (status == kOk) std::printf("dataset written to %s: %d frames rendered by %d ranks in %.1f s\n", out.c_str(),
                                       rendered_all, size, s);
        else std::fprintf(stderr, "ngi-dataset-mpi: a rank failed (see above); finished frames are kept, run again "
                                  "to complete the dataset\n");
    }
    MPI_Finalize();
    return status;
}
