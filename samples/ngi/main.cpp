// ngi: the command-line sample. It uses only the public API (host/include/ngi, bindings/c), so every command
// doubles as a usage example.
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>

#include "commands.hpp"
#include "ngi/error.hpp"

namespace {

const ngi_cli::Command kCommands[] = {
    {"devices", "ngi devices [--no-check]         list OpenCL devices, their capabilities and ngi's self-check on\n"
                "                                 each (GEMM variant in use, variants refused and why, loop limit)",
     ngi_cli::cmd_devices},
    {"generate", "ngi generate --model M.safetensors --input x.npy --output y.npy [--device D] [--profile]\n"
                 "             [--bn-mode running|per_image] [--dropout off|seeded]\n"
                 "             [--mlp-path fused|dense]\n"
                 "                                 run a generator on a NumPy NCHW float32 tensor (N=1), or an\n"
                 "                                 mlp per pixel ([1, C, H, W]) or per point ([N, C])",
     ngi_cli::cmd_generate},
    {"metrics", "ngi metrics A B [--range R] [--device D]\n"
                "                                 MSE, PSNR and SSIM of two images (.exr/.png/.npy) as JSON; R = data\n"
                "                                 range (default 1); psnr is null for identical images",
     ngi_cli::cmd_metrics},
    {"merge", "ngi merge --frame DIR --out DIR [--mode thesis|equirect] [--model M | --single-view] [--npy-only]\n"
              "          [--device D]\n"
              "                                 global view of every feature, coord.exr, the network input.npy and,\n"
              "                                 with a reference, the training target.npy (--npy-only: only the .npy)",
     ngi_cli::cmd_merge},
    {"lightmap", "ngi lightmap --frame DIR --model M.safetensors --out DIR [--size WxH] [--device D]\n"
                 "                                 lightmap.exr, final.png, and with a reference: compare.png, metrics.json",
     ngi_cli::cmd_lightmap},
    {"render", "ngi render --scene SPEC --out DIR [--frame K] [--face N] [--spp S] [--time HOURS] [--device D]\n"
               "           [--feature-spp F] [--bounces B] [--path-frames P] [--no-reference] [--preview PNG]\n"
               "                                 path-trace one frame folder; SPEC = room|street|cave|backlit|bleed|sculpture"
               "[:seed=S] or a .vox file",
     ngi_cli::cmd_render},
    {"dataset", "ngi dataset --config FILE.json --out DIR [--device D]\n"
                "                                 render a train/test dataset (resumable; see configs/)",
     ngi_cli::cmd_dataset},
    {"ao-data", "ngi ao-data --scene SPEC --out DIR [--views 128] [--heldout-views 32] [--n 256] [--rays 256]\n"
                "            [--max-distance 4] [--sigma 1.5] [--device D]\n"
                "                                 seed 001's AO data: orbit views of one object (smooth normals,\n"
                "                                 face normals, depth, ray-traced AO per view; resumable)",
     ngi_cli::cmd_ao_data},
    {"ao", "ngi ao --frame DIR --model M.safetensors --out DIR [--radius PX] [--device D]\n"
           "                                 AO of an AO frame folder with a trained AO MLP: ao.npy, ao.png and, with a\n"
           "                                 reference, compare.png + metrics.json (--radius 0: the seed's inference)",
     ngi_cli::cmd_ao},
};

void usage(FILE* out) {
    std::fprintf(out, "usage:\n");
    for (const auto& c : kCommands) std::fprintf(out, "  %s\n", c.synopsis);
    std::fprintf(out, "devices: --device cpu | gpu | P:D (platform:device, see `ngi devices`) | a platform name (pocl, rusticl); "
                      "default $NGI_DEVICE, "
                      "else the first GPU, else the first CPU\n");
    std::fprintf(out, "output: commands that write several files write all of them or none (a folder is staged as\n"
                      "        DIR.tmp-* and renamed into place; an existing DIR is replaced only if it holds nothing but\n"
                      "        files the command writes, and only once the new one is complete)\n");
    std::fprintf(out, "exit codes: 0 success; 1 error (bad input file, failed write, device error; the message names\n"
                      "            the file); 2 usage error (unknown command or option, bad option value)\n");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
        usage(argc < 2 ? stderr : stdout);
        return argc < 2 ? 2 : 0;
    }
    for (const auto& c : kCommands) {
        if (std::strcmp(argv[1], c.name) != 0) continue;
        try {
            const int rc = c.run(argc, argv);
            // The report on stdout is output too (metrics prints its result there): a failed write is an error.
            if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
                std::fprintf(stderr, "ngi %s: error: cannot write to standard output: %s\n", c.name,
                             std::strerror(errno));
                return 1;
            }
            return rc;
        } catch (const ngi_cli::UsageError& e) {
            std::fprintf(stderr, "ngi %s: %s\n", c.name, e.what());
            usage(stderr);
            return 2;
        } catch (const ngi::Error& e) {
            std::fprintf(stderr, "ngi %s: error: %s\n", c.name, e.what());
            return 1;
        } catch (const std::bad_alloc&) {
            std::fprintf(stderr, "ngi %s: error: out of memory\n", c.name);
            return 1;
        } catch (const std::exception& e) {
            // Last resort: every known failure is converted into an ngi::Error naming the file at its source.
            std::fprintf(stderr, "ngi %s: unexpected error: %s\n", c.name, e.what());
            return 1;
        }
    }
    std::fprintf(stderr, "ngi: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return 2;
}
