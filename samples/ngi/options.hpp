// The ngi sample's command-line conventions on top of CLI11: strict option values, help text with each option's
// allowed values and default, and one-line usage errors (main.cpp). Every mistake is a usage error naming the
// option (exit code 2): an unknown or repeated option, a missing value, a number that is not entirely a decimal
// number, not finite, or out of range, a value that is not one of the allowed ones.
#pragma once
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace ngi_cli {

// A usage error found after parsing (e.g. options that depend on each other): exit code 2, like CLI11's errors.
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Exit codes (`ngi --help`, README): 0 success; 1 bad input or failed write (ngi::InputError and other ngi::Errors,
// the message names the file); 2 usage error; 3 device failure (ngi::ClError, ngi::OutOfMemoryError, no device).
enum ExitCode : int { kExitOk = 0, kExitInput = 1, kExitUsage = 2, kExitDevice = 3 };

// What runs a command once its command line is parsed into the variables its options are bound to.
using Run = std::function<int()>;

// A command: its name, a one-line summary (the `ngi --help` list) and more text for `ngi help COMMAND`.
CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& summary, const std::string& details = "");

// A string option; `required` options must be given, and with a non-empty value. `metavar` names the value in the
// help ("DIR", "SPEC").
CLI::Option* add_path(CLI::App& cmd, const std::string& name, std::string& value, const std::string& metavar,
                      const std::string& help, bool required);
// A string option that, when given, must not be empty.
CLI::Option* add_nonempty(CLI::App& cmd, const std::string& name, std::string& value, const std::string& metavar,
                          const std::string& help);
// --device D (empty: $NGI_DEVICE, else the first GPU, else the first CPU).
CLI::Option* add_device(CLI::App& cmd, std::string& device);
// A whole decimal integer in [lo, hi]: no sign games, no trailing characters, no overflow. The help shows the
// range and the default (`value` as it is now, unless `default_text` says otherwise).
CLI::Option* add_integer(CLI::App& cmd, const std::string& name, int& value, int lo, int hi, const std::string& metavar,
                         const std::string& help, const std::string& default_text = "");
// A whole finite decimal number in [lo, hi] ("nan", "inf", "1e999", "3x", "0x10" are refused); hi = the largest
// double: no upper bound.
CLI::Option* add_real(CLI::App& cmd, const std::string& name, double& value, double lo, double hi,
                      const std::string& metavar, const std::string& help, const std::string& default_text = "");
// One of `choices` (CLI::IsMember); empty `default_text`: `value` as it is now.
CLI::Option* add_choice(CLI::App& cmd, const std::string& name, std::string& value,
                        const std::vector<std::string>& choices, const std::string& help,
                        const std::string& default_text = "");
// A switch without a value ("--flag=x" is refused).
CLI::Option* add_switch(CLI::App& cmd, const std::string& name, bool& value, const std::string& help);

// The whole string as a decimal integer in [lo, hi], or false (std::from_chars: no sign games, no leading space).
bool parse_integer(const std::string& s, int lo, int hi, int& out);

// The application's look: help and version flags, the help formatter; call before adding the commands.
void configure_app(CLI::App& app, const std::string& version);

}  // namespace ngi_cli
