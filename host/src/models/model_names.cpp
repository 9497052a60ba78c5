// Shipped models by name: the search path and the name -> file map (ngi/model.hpp, "Shipped models by name").
// The folders come from the environment, from where the running binary is installed, and from compile definitions
// set in CMakeLists.txt: NGI_MODELS_REL_DIRS (the models folder relative to the install's bin, lib and Python
// package folders, '|'-separated), NGI_MODELS_INSTALL_DIR (absolute, the configured prefix's) and
// NGI_MODELS_SOURCE_DIR (the source tree's models/, or empty).
#include "ngi/model.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <system_error>

#include "ngi/error.hpp"

#ifndef NGI_MODELS_REL_DIRS
#define NGI_MODELS_REL_DIRS ""
#endif
#ifndef NGI_MODELS_INSTALL_DIR
#define NGI_MODELS_INSTALL_DIR ""
#endif
#ifndef NGI_MODELS_SOURCE_DIR
#define NGI_MODELS_SOURCE_DIR ""
#endif

namespace ngi {
namespace {

namespace fs = std::filesystem;

std::vector<std::string> split(const std::string& s, char sep) {
    std::vector<std::string> out;
    std::string part;
    std::istringstream in(s);
    while (std::getline(in, part, sep))
        if (!part.empty()) out.push_back(part);
    return out;
}

bool is_dir(const fs::path& p) {
    std::error_code ec;
    return fs::is_directory(p, ec);
}

bool is_file(const fs::path& p) {
    std::error_code ec;
    return fs::is_regular_file(p, ec);
}

// The folders of the binaries that hold this code: the shared object ngi is linked into (libngi_c.so, the Python
// module), first, then the program (/proc/self/exe; the same file when ngi is linked into the program).
std::vector<fs::path> binary_dirs() {
    std::vector<fs::path> dirs;
    std::error_code ec;
    Dl_info info{};
    if (dladdr(reinterpret_cast<void*>(&model_search_path), &info) != 0 && info.dli_fname &&
        info.dli_fname[0] == '/') {
        const fs::path obj = fs::weakly_canonical(info.dli_fname, ec);
        if (!ec) dirs.push_back(obj.parent_path());
    }
    const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
    if (!ec && (dirs.empty() || exe.parent_path() != dirs.front())) dirs.push_back(exe.parent_path());
    return dirs;
}

// The name -> file entries of one models folder: zoo.json rungs with a file, then *.safetensors stems of the folder
// and of its direct subfolders (sorted, so a clash is settled the same way everywhere: first seen wins).
void add_folder(const fs::path& dir, std::map<std::string, std::string>& names) {
    const fs::path zoo = dir / "zoo.json";
    if (is_file(zoo)) {
        nlohmann::json j;
        try {
            std::ifstream f(zoo);
            j = nlohmann::json::parse(f);
        } catch (const std::exception& e) {
            throw InputError("model names: read " + zoo.string() + ": not valid JSON: " + e.what());
        }
        if (!j.is_object() || !j.contains("format") || j["format"] != "ngi-zoo" || !j.contains("rungs") ||
            !j["rungs"].is_array())
            throw InputError("model names: read " + zoo.string() +
                             ": not a zoo manifest (\"format\": \"ngi-zoo\" with a \"rungs\" list)");
        for (const nlohmann::json& r : j["rungs"]) {
            if (!r.is_object() || !r.contains("name") || !r["name"].is_string())
                throw InputError("model names: read " + zoo.string() + ": a rung without a \"name\" string");
            const std::string name = r["name"].get<std::string>();
            if (!r.contains("file") || r["file"].is_null()) continue;  // the direct-light rung: nothing to load
            if (!r["file"].is_string())
                throw InputError("model names: read " + zoo.string() + ": rung '" + name +
                                 "': \"file\" is not a string");
            // A batch-norm variant ("x@running") names the same file as its rung with another bn_mode: a name
            // that only gives a path would drop that mode, so it is not a model name.
            if (name.find('@') != std::string::npos) continue;
            names.emplace(name, (dir / r["file"].get<std::string>()).lexically_normal().string());
        }
    }
    std::vector<fs::path> files;
    std::vector<fs::path> subdirs;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        if (e.is_directory(ec)) subdirs.push_back(e.path());
        else if (e.path().extension() == ".safetensors") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());
    std::sort(subdirs.begin(), subdirs.end());
    for (const fs::path& d : subdirs) {
        std::vector<fs::path> inner;
        for (const auto& e : fs::directory_iterator(d, ec))
            if (e.path().extension() == ".safetensors") inner.push_back(e.path());
        std::sort(inner.begin(), inner.end());
        files.insert(files.end(), inner.begin(), inner.end());
    }
    for (const fs::path& f : files) names.emplace(f.stem().string(), f.lexically_normal().string());
}

std::string joined(const std::vector<std::string>& items, const std::string& sep) {
    std::string out;
    for (const std::string& s : items) out += (out.empty() ? "" : sep) + s;
    return out;
}

}  // namespace

std::vector<std::string> model_search_path() {
    std::vector<std::string> dirs;
    std::set<std::string> seen;
    auto add = [&](const fs::path& p) {
        std::error_code ec;
        fs::path c = fs::weakly_canonical(p, ec);
        if (ec) c = p.lexically_normal();
        if (!is_dir(c)) return;
        if (seen.insert(c.string()).second) dirs.push_back(c.string());
    };
    if (const char* e = std::getenv("NGI_MODEL_PATH"); e && *e)
        for (const std::string& d : split(e, ':')) add(d);
    for (const fs::path& bin : binary_dirs()) {
        add(bin / "models");
        for (const std::string& rel : split(NGI_MODELS_REL_DIRS, '|')) add(bin / rel);
    }
    if (*NGI_MODELS_INSTALL_DIR) add(NGI_MODELS_INSTALL_DIR);
    // The system's places (a program linking ngi's static libraries from a package built with another prefix).
    add("/usr/local/share/ngi/models");
    add("/usr/share/ngi/models");
    if (*NGI_MODELS_SOURCE_DIR) add(NGI_MODELS_SOURCE_DIR);
    return dirs;
}

std::vector<std::pair<std::string, std::string>> model_names() {
    std::map<std::string, std::string> names;
    for (const std::string& d : model_search_path()) {
        std::map<std::string, std::string> here;
        add_folder(d, here);
        for (auto& [name, file] : here) names.emplace(name, file);  // an earlier folder keeps its entry
    }
    return {names.begin(), names.end()};
}

std::string resolve_model(const std::string& name_or_path) {
    const std::string& s = name_or_path;
    if (s.empty()) throw InputError("model: empty name or path");
    if (is_file(s) || s.find('/') != std::string::npos ||
        (s.size() >= 12 && s.compare(s.size() - 12, 12, ".safetensors") == 0))
        return s;
    // Folder by folder: the first that has the name answers (a later folder's zoo.json is not even read).
    const std::vector<std::string> dirs = model_search_path();
    for (const std::string& d : dirs) {
        std::map<std::string, std::string> here;
        add_folder(d, here);
        const auto it = here.find(s);
        if (it == here.end()) continue;
        if (!is_file(it->second))
            throw InputError("model '" + s + "': its file " + it->second + " does not exist (" + d +
                             "/zoo.json names it)");
        return it->second;
    }
    std::vector<std::string> known;
    for (const auto& n : model_names()) known.push_back(n.first);
    throw InputError("model '" + s + "': not a file and not a known model name (searched: " +
                     (dirs.empty() ? std::string("no models folder found; set NGI_MODEL_PATH") : joined(dirs, ", ")) +
                     "); known names: " + (known.empty() ? std::string("none") : joined(known, ", ")));
}

}  // namespace ngi
