// The ngi sample's option helpers and help layout (options.hpp).
#include "options.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <memory>
#include <sstream>
#include <system_error>

namespace ngi_cli {
namespace {

constexpr std::size_t kHelpWidth = 100, kColumn = 26;

// The shortest form that reads back as the same double ("0.001", "1e+06").
std::string num(double v) {
    char b[32];
    const auto r = std::to_chars(b, b + sizeof b, v);
    return std::string(b, r.ptr);
}

// A range bound for people: "1000000", not "1e+06".
std::string bound(double v) {
    char b[400];
    const auto r = std::to_chars(b, b + sizeof b, v, std::chars_format::fixed);
    return r.ec == std::errc() ? std::string(b, r.ptr) : num(v);
}

// ", default 64", or ", default: the scene's" when a text stands for the default.
std::string default_part(const std::string& value, const std::string& text) {
    return text.empty() ? ", default " + value : ", default: " + text;
}

// Each line of `text` word-wrapped to `width` columns (continuation lines keep the line's leading spaces).
std::string wrap(const std::string& text, std::size_t width) {
    std::string out;
    std::istringstream lines(text);
    std::string line;
    bool first_line = true;
    while (std::getline(lines, line)) {
        if (!first_line) out += '\n';
        first_line = false;
        const std::size_t indent = line.find_first_not_of(' ') == std::string::npos ? 0 : line.find_first_not_of(' ');
        std::istringstream words(line.substr(indent));
        std::string word, current(indent, ' ');
        bool empty = true;
        while (words >> word) {
            if (!empty && current.size() + 1 + word.size() > width) {
                out += current + '\n';
                current.assign(indent, ' ');
                empty = true;
            }
            current += (empty ? "" : " ") + word;
            empty = false;
        }
        out += current;
    }
    return out;
}

// The sample's help layout: "--name VALUE  description [allowed values, default]", usage lines naming the required
// options, and the command list with each command's one-line summary.
class HelpFormatter : public CLI::Formatter {
public:
    HelpFormatter() { column_width(kColumn); }

    std::string make_option_opts(const CLI::Option* opt) const override {
        // Flags take no value; the validators' own descriptions are empty, so the type name is the metavar.
        return opt->get_type_size() == 0 || opt->get_positional() ? std::string() : " " + opt->get_type_name();
    }
    std::string make_option_desc(const CLI::Option* opt) const override {
        return wrap(opt->get_description(), kHelpWidth - kColumn);
    }
    std::string make_description(const CLI::App* app) const override {
        const std::string& d = app->get_description();
        return d.empty() ? std::string() : wrap(d, kHelpWidth) + "\n\n";
    }
    std::string make_usage(const CLI::App* app, std::string name) const override {
        std::string out = get_label("Usage") + ": " + name;
        if (!app->get_subcommands([](const CLI::App* s) { return !s->get_name().empty(); }).empty())
            return out + " COMMAND [options]   (ngi help COMMAND: the command's options)\n";
        if (app->get_prefix_command())  // adapt: every argument is passed on as it is
            return out + " ARGS...   (" + name + " --help: the options)\n";
        bool optional = false;
        for (const CLI::Option* o : app->get_options()) {
            if (o == app->get_help_ptr() || o->get_positional()) continue;
            if (o->get_required()) out += " " + o->get_name(false, true) + " " + o->get_type_name();
            else optional = true;
        }
        for (const CLI::Option* o : app->get_options([](const CLI::Option* o) { return o->get_positional(); }))
            out += " " + make_option_usage(o);
        return out + (optional ? " [options]\n" : "\n");
    }
    std::string make_subcommand(const CLI::App* sub) const override {
        const std::string& d = sub->get_description();
        std::stringstream out;
        CLI::detail::format_help(out, sub->get_display_name(), d.substr(0, d.find('\n')), 14);
        return out.str();
    }
};

// The messages below read "--spp: needs an integer in 1..1048576, got '0'" (CLI11 puts the option's name first).
std::string needs(const std::string& what, const std::string& got) { return "needs " + what + ", got '" + got + "'"; }

// The whole string as a decimal integer (any size std::from_chars takes), rewritten in canonical form: CLI11's own
// conversion would read "010" as octal and "0x10" as hexadecimal.
CLI::Validator decimal_integer(const std::string& what) {
    return CLI::Validator(
        [what](std::string& s) -> std::string {
            long long v = 0;
            const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
            if (s.empty() || ec != std::errc() || end != s.data() + s.size()) return needs(what, s);
            s = std::to_string(v);
            return std::string();
        },
        "");
}

// The whole string as a finite decimal number, rewritten in its shortest round-trip form.
CLI::Validator finite_number(const std::string& what) {
    return CLI::Validator(
        [what](std::string& s) -> std::string {
            double v = 0;
            const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
            if (s.empty() || ec != std::errc() || end != s.data() + s.size() || !std::isfinite(v))
                return needs(what, s);
            s = num(v);
            return std::string();
        },
        "");
}

// CLI::Range with the message in the same words as the format's (CLI11's prints doubles as "48.000000"), and no
// description of its own in the help (the option's text gives the range).
CLI::Validator in_range(const CLI::Validator& range, const std::string& what) {
    return CLI::Validator(
        [range, what](std::string& s) -> std::string {
            std::string copy = s;
            return range(copy).empty() ? std::string() : needs(what, s);
        },
        "");
}

CLI::Validator non_empty() {
    return CLI::Validator([](std::string& s) { return s.empty() ? std::string("needs a non-empty value") : std::string(); },
                          "");
}

// A CLI11 validator without its description (the option's text says what it takes).
CLI::Validator quiet(CLI::Validator v) {
    v.description("");
    return v;
}

}  // namespace

CLI::App* add_command(CLI::App& app, const std::string& name, const std::string& summary, const std::string& details) {
    CLI::App* cmd = app.add_subcommand(name, details.empty() ? summary : summary + "\n" + details);
    cmd->group("Commands");
    return cmd;
}

CLI::Option* add_path(CLI::App& cmd, const std::string& name, std::string& value, const std::string& metavar,
                      const std::string& help, bool required) {
    CLI::Option* o = cmd.add_option(name, value, required ? "required: " + help : help)->type_name(metavar);
    if (required) o->required()->check(non_empty());
    return o;
}

CLI::Option* add_nonempty(CLI::App& cmd, const std::string& name, std::string& value, const std::string& metavar,
                          const std::string& help) {
    return add_path(cmd, name, value, metavar, help, false)->check(non_empty());
}

CLI::Option* add_device(CLI::App& cmd, std::string& device) {
    return cmd.add_option("--device", device,
                          "OpenCL device: cpu | gpu | P:D (platform:device, see `ngi devices`) | a platform name "
                          "(pocl, rusticl) [default: $NGI_DEVICE, else the first GPU, else the first CPU]")
        ->type_name("D")
        ->check(non_empty());  // --device '' meant the default silently; leaving the option out says that
}

CLI::Option* add_integer(CLI::App& cmd, const std::string& name, int& value, int lo, int hi, const std::string& metavar,
                         const std::string& help, const std::string& default_text) {
    const std::string range = std::to_string(lo) + ".." + std::to_string(hi), what = "an integer in " + range;
    const std::string text = help + " [" + range + default_part(std::to_string(value), default_text) + "]";
    return cmd.add_option(name, value, text)
        ->type_name(metavar)
        ->check(decimal_integer(what))
        ->check(in_range(CLI::Range(lo, hi), what));
}

CLI::Option* add_real(CLI::App& cmd, const std::string& name, double& value, double lo, double hi,
                      const std::string& metavar, const std::string& help, const std::string& default_text) {
    const bool unbounded = hi == std::numeric_limits<double>::max();
    const std::string range = unbounded ? ">= " + bound(lo) : "in " + bound(lo) + ".." + bound(hi);
    const std::string what = "a finite number " + range;
    const std::string text =
        help + " [" + (unbounded ? range : range.substr(3)) + default_part(num(value), default_text) + "]";
    return cmd.add_option(name, value, text)
        ->type_name(metavar)
        ->check(finite_number(what))
        ->check(in_range(CLI::Range(lo, hi), what));
}

CLI::Option* add_choice(CLI::App& cmd, const std::string& name, std::string& value,
                        const std::vector<std::string>& choices, const std::string& help,
                        const std::string& default_text) {
    std::string metavar;
    for (const auto& c : choices) metavar += (metavar.empty() ? "" : "|") + c;
    return cmd.add_option(name, value, help + " [" + default_part(value, default_text).substr(2) + "]")
        ->type_name(metavar)
        ->check(quiet(CLI::IsMember(choices)));
}

CLI::Option* add_switch(CLI::App& cmd, const std::string& name, bool& value, const std::string& help) {
    return cmd.add_flag(name, value, help)->disable_flag_override();
}

bool parse_integer(const std::string& s, int lo, int hi, int& out) {
    long long v = 0;
    const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (s.empty() || ec != std::errc() || end != s.data() + s.size() || v < lo || v > hi) return false;
    out = int(v);
    return true;
}

void configure_app(CLI::App& app, const std::string& version) {
    app.formatter(std::make_shared<HelpFormatter>());
    app.set_help_flag("-h,--help", "print this help and exit");
    app.set_version_flag("--version", version, "print the version (" + version + ") and exit");
    // One command per run; a second command name is an unexpected argument, not a second command.
    app.require_subcommand(0, 1);
    // "--spp 1 --spp 2" is an error, not the last one winning.
    app.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::Throw);
}

}  // namespace ngi_cli
