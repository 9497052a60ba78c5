// ngi: the command-line sample. It uses only the public API (host/include/ngi, bindings/c), so every command
// doubles as a usage example. The command line is parsed by CLI11 (options.hpp); `ngi help COMMAND` and
// `ngi COMMAND --help` list a command's options, a usage error is one line naming the option (exit code 2).
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "ngi.h"
#include "ngi/error.hpp"

namespace {

const char kFooter[] =
    "devices: --device cpu | gpu | P:D (platform:device, see `ngi devices`) | a platform name (pocl, rusticl);\n"
    "         default $NGI_DEVICE, else the first GPU, else the first CPU\n"
    "output: commands that write several files write all of them or none (a folder is staged as DIR.tmp-* and\n"
    "        renamed into place; an existing DIR is replaced only if it holds nothing but files the command\n"
    "        writes, and only once the new one is complete)\n"
    "exit codes: 0 success; 1 bad input or failed write (the message names the file); 2 usage error (unknown\n"
    "            command or option, missing or bad option value); 3 device failure (OpenCL error, device memory\n"
    "            exhausted, no OpenCL device)\n"
    "memory: a file or image that needs more host memory than $NGI_HOST_MEMORY_LIMIT (bytes, or 512M, 16G; default\n"
    "        half of the physical memory) is refused before it is allocated (exit code 1)";

// The version of the ngi headers this sample is built with (= the CMake project version, checked by CMake).
std::string version() {
    return std::to_string(NGI_VERSION_MAJOR) + "." + std::to_string(NGI_VERSION_MINOR) + "." +
           std::to_string(NGI_VERSION_PATCH);
}

// One short line on stderr: what is wrong, and where the options are listed. Exit code 2.
int usage_error(const CLI::App* cmd, const std::string& what) {
    if (cmd)
        std::fprintf(stderr, "ngi %s: %s; run 'ngi %s --help' for the options\n", cmd->get_name().c_str(), what.c_str(),
                     cmd->get_name().c_str());
    else
        std::fprintf(stderr, "ngi: %s; run 'ngi --help' for the commands\n", what.c_str());
    return ngi_cli::kExitUsage;
}

// What is wrong with a command line, in the order a reader looks for it: a word nobody knows (an unknown option,
// a stray argument, an unknown command), an option given twice; "" if neither.
std::string stray_or_repeated(const CLI::App& app, const CLI::App* cmd) {
    for (const CLI::App* a : {cmd, &app}) {
        if (!a || a->remaining().empty()) continue;
        std::string word = a->remaining().front();
        if (word.size() > 1 && word[0] == '-') return "unknown option " + word.substr(0, word.find('='));
        return (a == cmd ? "unexpected argument '" : "unknown command '") + word + "'";
    }
    if (cmd)
        for (const CLI::Option* o : cmd->get_options())
            if (o->count() > 1 && o->get_multi_option_policy() != CLI::MultiOptionPolicy::TakeAll)
                return "option " + o->get_name() + " given twice";  // TakeAll: a repeatable option (probe-gi --model)
    return "";
}

// CLI11's message, in the sample's words where CLI11's are unclear.
std::string describe(const CLI::ParseError& e) {
    const std::string what = e.what();
    if (dynamic_cast<const CLI::ArgumentMismatch*>(&e)) {
        std::string name = what.substr(0, what.find_first_of(": "));
        if (name.rfind('-', 0) != 0) name = "--" + name;  // a flag override names the flag without its dashes
        if (what.find(" required ") != std::string::npos && what.size() > 8 &&
            what.compare(what.size() - 8, 8, " missing") == 0)
            return "option " + name + " needs a value";
        if (what.find("disallowed flag override") != std::string::npos) return "option " + name + " takes no value";
    }
    return what;
}

int run_command(const CLI::App& cmd, const ngi_cli::Run& run) {
    const char* name = cmd.get_name().c_str();
    try {
        const int rc = run();
        // The report on stdout is output too (metrics prints its result there): a failed write is an error.
        if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
            std::fprintf(stderr, "ngi %s: error: cannot write to standard output: %s\n", name, std::strerror(errno));
            return ngi_cli::kExitInput;
        }
        return rc;
    } catch (const ngi_cli::UsageError& e) {
        return usage_error(&cmd, e.what());
    } catch (const ngi::ClError& e) {
        std::fprintf(stderr, "ngi %s: device error: %s\n", name, e.what());
        return ngi_cli::kExitDevice;
    } catch (const ngi::OutOfMemoryError& e) {
        std::fprintf(stderr, "ngi %s: device error: %s\n", name, e.what());
        return ngi_cli::kExitDevice;
    } catch (const ngi::DeviceNotFoundError& e) {  // before Error: "no device" is a device failure (exit 3)
        std::fprintf(stderr, "ngi %s: device error: %s\n", name, e.what());
        return ngi_cli::kExitDevice;
    } catch (const ngi::Error& e) {
        std::fprintf(stderr, "ngi %s: error: %s\n", name, e.what());
        return ngi_cli::kExitInput;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "ngi %s: error: out of memory\n", name);
        return ngi_cli::kExitInput;
    } catch (const std::exception& e) {
        // Last resort: every known failure is converted into an ngi::Error naming the file at its source.
        std::fprintf(stderr, "ngi %s: unexpected error: %s\n", name, e.what());
        return ngi_cli::kExitInput;
    }
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app("ngi " + version() + ": neural global illumination with OpenCL, from the command line", "ngi");
    ngi_cli::configure_app(app, "ngi " + version());
    std::vector<std::pair<CLI::App*, ngi_cli::Run>> commands;
    for (auto add : {ngi_cli::add_devices, ngi_cli::add_generate, ngi_cli::add_metrics, ngi_cli::add_merge,
                     ngi_cli::add_lightmap, ngi_cli::add_render, ngi_cli::add_dataset, ngi_cli::add_ao_data,
                     ngi_cli::add_ao, ngi_cli::add_voxel_data, ngi_cli::add_probe_gi, ngi_cli::add_neural_gi,
                     ngi_cli::add_warmup, ngi_cli::add_adapt}) {
        ngi_cli::Run run = add(app);
        commands.emplace_back(app.get_subcommands({}).back(), std::move(run));
    }
    // `ngi adapt ARGS...`: the arguments are the Python adaptation's, exactly as given (a leading "--" too).
    if (argc >= 2 && std::strcmp(argv[1], "adapt") == 0)
        return ngi_cli::run_adapt(std::vector<std::string>(argv + 2, argv + argc));
    std::string topic;
    CLI::App* help = ngi_cli::add_command(app, "help", "list the commands, or with COMMAND: that command's options");
    std::string names;
    for (const auto& c : commands) names += (names.empty() ? "" : ", ") + c.first->get_name();
    help->add_option("COMMAND", topic, "one of " + names);
    app.footer(kFooter);  // after the commands: CLI11 copies a footer into commands added after it

    std::string problem;
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp&) {
        std::fputs(app.help().c_str(), stdout);  // the help of the command named, else the command list
        return ngi_cli::kExitOk;
    } catch (const CLI::CallForVersion& e) {
        std::printf("%s\n", e.what());
        return ngi_cli::kExitOk;
    } catch (const CLI::ParseError& e) {
        problem = describe(e);
    }
    const std::vector<CLI::App*> chosen = app.get_subcommands();
    const CLI::App* cmd = chosen.empty() ? nullptr : chosen.front();
    if (const std::string found = stray_or_repeated(app, cmd); !found.empty()) problem = found;
    if (!problem.empty()) return usage_error(cmd, problem);
    if (!cmd) return usage_error(nullptr, "no command given");

    if (cmd == help) {
        if (topic.empty()) {
            std::fputs(app.get_formatter()->make_help(&app, "ngi", CLI::AppFormatMode::Normal).c_str(), stdout);
            return ngi_cli::kExitOk;
        }
        for (const CLI::App* c : app.get_subcommands({}))
            if (c->get_name() == topic) {
                std::fputs(c->help("ngi").c_str(), stdout);
                return ngi_cli::kExitOk;
            }
        return usage_error(nullptr, "unknown command '" + topic + "'");
    }
    for (const auto& c : commands)
        if (c.first == cmd) return run_command(*cmd, c.second);
    return usage_error(nullptr, "no command given");  // not reached: every command is in the list
}
