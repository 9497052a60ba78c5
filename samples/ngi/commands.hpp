// The ngi sample's commands; one file each (cmd_<name>.cpp). Each returns the process exit code.
#pragma once
#include "args.hpp"

namespace ngi_cli {

struct Command {
    const char* name;
    const char* synopsis;
    int (*run)(int argc, char** argv);  // argv[0] = "ngi", argv[1] = command name
};

int cmd_devices(int argc, char** argv);
int cmd_generate(int argc, char** argv);
int cmd_metrics(int argc, char** argv);
int cmd_merge(int argc, char** argv);
int cmd_lightmap(int argc, char** argv);
int cmd_render(int argc, char** argv);
int cmd_dataset(int argc, char** argv);
int cmd_ao_data(int argc, char** argv);
int cmd_ao(int argc, char** argv);

}  // namespace ngi_cli
