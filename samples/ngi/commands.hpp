// The ngi sample's commands; one file each (cmd_<name>.cpp). Each adds its subcommand and options to the app and
// returns what runs it once the command line is parsed; that returns the process exit code.
#pragma once
#include "options.hpp"

namespace ngi_cli {

Run add_devices(CLI::App& app);
Run add_generate(CLI::App& app);
Run add_metrics(CLI::App& app);
Run add_merge(CLI::App& app);
Run add_lightmap(CLI::App& app);
Run add_render(CLI::App& app);
Run add_dataset(CLI::App& app);
Run add_ao_data(CLI::App& app);
Run add_ao(CLI::App& app);
Run add_voxel_data(CLI::App& app);
Run add_probe_gi(CLI::App& app);
Run add_neural_gi(CLI::App& app);
Run add_warmup(CLI::App& app);

}  // namespace ngi_cli
