// ngi adapt: a network fitted to one scene within a time budget (issue 46, docs/ADAPT.md). The adaptation itself is
// Python (ngi_train.adapt: renders with this ngi, fine-tunes with PyTorch, exports); this command runs it with the
// arguments exactly as given, in place of this process (exec), so that its exit code is the command's and Ctrl-C or
// SIGTERM reaches it directly (it stops after the step it is in, keeps what it has and resumes when run again).
// What it adds over `python3 -m ngi_train.adapt`: the interpreter ($NGI_PYTHON, else the one ngi's Python module was
// built for), the folders of this installation's or build tree's Python packages ngi and ngi_train (handed over in
// NGI_ADAPT_PYTHON_DIRS, put first on sys.path by the bootstrap only where Python does not search them already, so
// that a site folder such as /usr/lib/python3/dist-packages keeps its place behind /usr/local and ~/.local), this
// binary as the ngi the adaptation renders with (NGI_BIN), and a clear message when Python, NumPy, PyTorch, tqdm,
// ngi or ngi_train cannot be found. PYTHONPATH is left as the caller set it.
//
// Compile definitions (CMakeLists.txt): NGI_ADAPT_PYTHON (the default interpreter), NGI_ADAPT_PYTHON_REL_DIR (the
// installed Python packages relative to the installed bin/), NGI_ADAPT_TRAINING_SOURCE_DIR (a build tree's
// source training/ folder, or empty).
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <system_error>
#include <vector>

#include "commands.hpp"

#ifndef NGI_ADAPT_PYTHON
#define NGI_ADAPT_PYTHON "/usr/bin/python3"
#endif
#ifndef NGI_ADAPT_PYTHON_REL_DIR
#define NGI_ADAPT_PYTHON_REL_DIR "../lib/python3/dist-packages"
#endif
#ifndef NGI_ADAPT_TRAINING_SOURCE_DIR
#define NGI_ADAPT_TRAINING_SOURCE_DIR ""
#endif

namespace ngi_cli {

namespace {

namespace fs = std::filesystem;

// Run as `PYTHON -c kBootstrap ARGS...`: what `python3 -m ngi_train.adapt ARGS...` does, after checking that every
// package the adaptation (and its training child) imports can be found, so that a missing one is named with where
// to get it instead of a traceback halfway through. Exit code 1 when one is missing. Before that, sys.path:
// - without PYTHONSAFEPATH (Python < 3.11 ignores it) the current folder ('' for -c) is dropped from its front: a
//   folder named ngi there, e.g. bindings/python of a checkout, would hide the installed package;
// - each folder of NGI_ADAPT_PYTHON_DIRS (os.pathsep-separated, in order) goes to the front unless sys.path has it
//   already: a build tree's <build>/python and the source training/ come first, while an installation's site
//   folder (/usr/lib/python3/dist-packages) stays where Python's site put it, behind the user's packages.
const char kBootstrap[] = R"PY(import importlib.util, os, sys
def _real(p):
    try:
        return os.path.realpath(p or os.curdir)
    except OSError:
        return None
_cwd = _real("")
if not getattr(sys.flags, "safe_path", False) and sys.path and (sys.path[0] == "" or
                                                                 (_cwd and _real(sys.path[0]) == _cwd)):
    del sys.path[0]
_known, _ours = {_real(p) for p in sys.path if p}, []
for d in os.environ.get("NGI_ADAPT_PYTHON_DIRS", "").split(os.pathsep):
    if d and _real(d) not in _known:
        _known.add(_real(d))
        _ours.append(d)
sys.path[:0] = _ours
needed = (("numpy", "NumPy (Debian: python3-numpy; pip install numpy)"),
          ("torch", "PyTorch (Debian: python3-torch; pip install torch)"),
          ("tqdm", "tqdm (Debian: python3-tqdm; pip install tqdm)"),
          ("ngi", "ngi's Python package (installed with ngi in <prefix>/lib/python3/dist-packages; Debian: "
                  "python3-ngi; pip install . of the ngi sources; a build tree has it in <build>/python)"),
          ("ngi_train", "ngi's training package ngi_train (installed beside ngi's Python package; a checkout has "
                        "it in training/)"))
missing = []
for name, what in needed:
    try:
        found = importlib.util.find_spec(name) is not None
    except (ImportError, ValueError):
        found = False
    if not found:
        missing.append(what)
if missing:
    sys.stderr.write("ngi adapt: the adaptation runs in Python (ngi_train.adapt), and %s cannot import:\n%s"
                     "(searched: %s; $NGI_PYTHON picks another interpreter)\n"
                     % (sys.executable, "".join("  %s\n" % m for m in missing), os.pathsep.join(sys.path)))
    sys.exit(1)
from ngi_train import adapt
sys.exit(adapt.main(sys.argv[1:], prog="ngi adapt"))
)PY";

bool is_file(const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec);
}

fs::path canonical_or_normal(const fs::path& p) {
    std::error_code ec;
    fs::path c = fs::canonical(p, ec);
    return ec ? p.lexically_normal() : c;
}

// This binary (/proc/self/exe), or empty where that cannot be read.
fs::path self_path() {
    std::error_code ec;
    const fs::path p = fs::read_symlink("/proc/self/exe", ec);
    return ec ? fs::path() : p;
}

// The folders that hold the Python packages ngi and ngi_train that belong to the binary in `bin`, in the order
// Python should find them: an installation's Python folder (<prefix>/bin/../lib/python3/dist-packages, or the
// folder above ngi/ngi-cli of `pip install .`), else a build tree's <build>/python (ngi) and the source tree's
// training/ (ngi_train). Empty for a binary copied elsewhere: then Python's own path decides.
std::vector<fs::path> python_dirs(const fs::path& bin) {
    std::vector<fs::path> dirs;
    for (const fs::path& installed : {bin / NGI_ADAPT_PYTHON_REL_DIR, bin / ".."})
        if (is_file(installed / "ngi_train" / "adapt.py") && is_file(installed / "ngi" / "__init__.py")) {
            dirs.push_back(canonical_or_normal(installed));
            return dirs;
        }
    if (is_file(bin / "python" / "ngi" / "__init__.py")) {
        dirs.push_back(bin / "python");
        const fs::path training = NGI_ADAPT_TRAINING_SOURCE_DIR;
        if (!training.empty() && is_file(training / "ngi_train" / "adapt.py")) dirs.push_back(training);
    }
    return dirs;
}

}  // namespace

int run_adapt(const std::vector<std::string>& args) {
    const char* chosen = std::getenv("NGI_PYTHON");
    const std::string python = chosen && *chosen ? chosen : NGI_ADAPT_PYTHON;
    const fs::path self = self_path();
    // The folders for the bootstrap (kBootstrap), never PYTHONPATH: there they would come before everything, the
    // standard library included, and an installation's site folder would hide the user's own packages.
    std::string dirs;
    if (!self.empty())
        for (const fs::path& d : python_dirs(self.parent_path())) dirs += (dirs.empty() ? "" : ":") + d.string();
    if (dirs.empty())
        unsetenv("NGI_ADAPT_PYTHON_DIRS");  // a copied binary: Python's own path decides, not a caller's value
    else
        setenv("NGI_ADAPT_PYTHON_DIRS", dirs.c_str(), 1);
    if (!self.empty())
        setenv("NGI_BIN", self.c_str(), 1);  // the adaptation renders with this ngi (ngi_train.ngi_paths.find_ngi)
    // Python 3.11+: the current folder is not put first on sys.path (a folder named ngi there, e.g.
    // bindings/python of a checkout, would hide the installed package); the bootstrap drops it for older ones.
    setenv("PYTHONSAFEPATH", "1", 0);

    std::vector<std::string> argv_strings = {python, "-c", kBootstrap};
    argv_strings.insert(argv_strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& s : argv_strings) argv.push_back(s.data());
    argv.push_back(nullptr);
    std::fflush(stdout);
    std::fflush(stderr);
    // A name without a slash is looked up on PATH (NGI_PYTHON=python3), a path is run as it is.
    execvp(argv[0], argv.data());
    const int err = errno;  // only reached when the interpreter could not be started
    std::fprintf(stderr,
                 "ngi adapt: error: cannot run the Python interpreter %s: %s. The adaptation runs in Python 3 with "
                 "NumPy, PyTorch and tqdm (Debian: apt install python3 python3-numpy python3-torch python3-tqdm); "
                 "$NGI_PYTHON names another interpreter\n",
                 python.c_str(), std::strerror(err));
    return kExitInput;
}

Run add_adapt(CLI::App& app) {
    CLI::App* cmd = add_command(
        app, "adapt", "fit a GI network to one scene within a time budget (Python + PyTorch; `ngi adapt --help`)",
        "Renders the scene with the inputs an engine has, fine-tunes the SSGI-correcting base network on it and "
        "writes an F16 model every API runs, all within --budget-minutes (docs/ADAPT.md). `ngi adapt --help` lists "
        "its options: they are those of `python3 -m ngi_train.adapt`, passed as given; it runs in place of this "
        "process, so its exit code is the command's (0 written; 2 refused before any work: a bad option, a scene "
        "that does not load, a base that cannot be adapted, a budget too small; 130 interrupted: the same command "
        "resumes; 1 another failure, also Python, NumPy, PyTorch, tqdm or ngi's Python packages missing) and "
        "Ctrl-C or SIGTERM reaches it. The interpreter is $NGI_PYTHON, else " NGI_ADAPT_PYTHON "; the Python "
        "packages ngi and ngi_train of this installation (or build tree) come first on its sys.path unless it "
        "searches their folder already (NGI_ADAPT_PYTHON_DIRS), and NGI_BIN names this ngi.");
    // Everything after `adapt` is the adaptation's, --help included: no options of its own, nothing parsed. main()
    // hands `ngi adapt ARGS...` to run_adapt before CLI11 sees it (which would drop a leading "--"); this is for
    // the help and the command list.
    cmd->set_help_flag();
    cmd->prefix_command();
    return [cmd] { return run_adapt(cmd->remaining()); };
}

}  // namespace ngi_cli
