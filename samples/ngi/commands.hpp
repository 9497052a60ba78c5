// The ngi sample's commands; one file each (cmd_<name>.cpp). Each adds its subcommand and options to the app and
// returns what runs it once the command line is parsed; that returns the process exit code.
#pragma once
#include <string>
#include <vector>

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
Run add_adapt(CLI::App& app);
// `ngi adapt ARGS...`: runs python3 -m ngi_train.adapt ARGS... in place of this process (returns only when the
// interpreter cannot be started). main() calls it with the arguments as given, before CLI11 parses anything.
int run_adapt(const std::vector<std::string>& args);

}  // namespace ngi_cli
