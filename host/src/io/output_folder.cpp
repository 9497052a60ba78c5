#include "ngi/output_folder.hpp"

#include <algorithm>
#include <filesystem>

#include "base/file_util.hpp"
#include "ngi/error.hpp"

namespace fs = std::filesystem;

namespace ngi {
namespace {

// "out/frame/" and "out/frame" name the same folder; the staging folder is a sibling of the last component.
std::string normalized(const std::string& dir, const std::string& what) {
    fs::path p = fs::path(dir).lexically_normal();
    if (p.filename().empty()) p = p.parent_path();
    if (p.empty() || p == "." || p == "..")
        throw InputError(what + " '" + dir + "': not usable as an output folder (name a folder to create)");
    return p.string();
}

}  // namespace

OutputFolder::OutputFolder(const std::string& dir, const std::string& what, std::vector<std::string> owned_files)
    : OutputFolder(dir, what, [owned = std::move(owned_files)](const std::string& existing) -> std::string {
          std::error_code ec;
          for (fs::directory_iterator it(existing, ec), end; !ec && it != end; it.increment(ec)) {
              const std::string name = it->path().filename().string();
              if (std::find(owned.begin(), owned.end(), name) == owned.end())
                  return "holds '" + name + "', which this command does not write";
          }
          if (ec) return "cannot be listed: " + ec.message();
          return "";
      }) {}

OutputFolder::OutputFolder(const std::string& dir, const std::string& what, ReplaceCheck may_replace)
    : what_(what), target_(normalized(dir, what)), may_replace_(std::move(may_replace)) {
    check_replaceable();
    staging_ = detail::temp_name(target_);
}

// Created on first use, not in the constructor: a command that checks its output folder first and then computes
// for minutes leaves nothing on disk if it is killed (or fails) before it writes.
void OutputFolder::stage() const {
    if (staged_) return;
    const fs::path target(target_);
    std::error_code ec;
    if (target.has_parent_path()) {
        fs::create_directories(target.parent_path(), ec);
        if (ec) throw InputError(what_ + " " + target_ + ": cannot create " + target.parent_path().string() + ": " +
                                 ec.message());
    }
    if (!fs::create_directory(staging_, ec) || ec)
        throw InputError(what_ + " " + target_ + ": cannot create " + staging_ + ": " +
                         (ec ? ec.message() : std::string("it already exists")));
    staged_ = true;
}

OutputFolder::~OutputFolder() {
    if (finished_ || !staged_) return;
    std::error_code ec;
    fs::remove_all(staging_, ec);  // best effort: a destructor cannot report
}

void OutputFolder::check_replaceable() const {
    std::error_code ec;
    const auto st = fs::symlink_status(target_, ec);
    if (ec || !fs::exists(st)) return;  // absent: nothing to replace
    if (!fs::is_directory(fs::status(target_, ec)))
        throw InputError(what_ + " " + target_ + ": exists and is not a directory; refusing to replace it");
    if (fs::is_empty(target_, ec) && !ec) return;
    if (const std::string why = may_replace_ ? may_replace_(target_) : std::string("it is not empty"); !why.empty())
        throw InputError(what_ + " " + target_ + ": exists and " + why +
                         "; refusing to replace it (remove it or choose another output folder)");
}

const std::string& OutputFolder::staging() const {
    stage();
    return staging_;
}

std::string OutputFolder::file(const std::string& name) const { return (fs::path(staging()) / name).string(); }

void OutputFolder::write(const std::string& name, const std::function<void(const std::string& path)>& writer) const {
    try {
        writer(file(name));
    } catch (const InputError& e) {
        std::string msg = e.what();
        for (std::size_t at = 0; (at = msg.find(staging_, at)) != std::string::npos; at += target_.size())
            msg.replace(at, staging_.size(), target_);
        throw InputError(msg + " (" + target_ + " was left unchanged)");
    }
}

void OutputFolder::write_text(const std::string& name, const std::string& text) const {
    write(name, [&](const std::string& path) { detail::write_file_atomic(path, text); });
}

void OutputFolder::commit() { finish_commit(commit_keep_old()); }

std::string OutputFolder::commit_keep_old() {
    if (finished_) throw Error(what_ + " " + target_ + ": committed twice");
    std::error_code ec;
    try {
        stage();              // (an output with no files is an empty folder)
        check_replaceable();  // again: the folder may have appeared or changed while the outputs were computed
        const bool exists = fs::exists(fs::symlink_status(target_, ec));
        // Between the two renames <dir> briefly does not exist; it is never partial.
        std::string old;
        if (exists) {
            old = detail::temp_name(target_ + ".old");
            fs::rename(target_, old, ec);
            if (ec)
                throw InputError(what_ + " " + target_ + ": cannot move the existing folder aside: " + ec.message());
        }
        fs::rename(staging_, target_, ec);
        if (ec) {
            const std::string reason = ec.message();
            if (exists) fs::rename(old, target_, ec);  // put the previous output back
            throw InputError(what_ + " " + target_ + ": cannot move the finished folder into place: " + reason);
        }
        finished_ = true;
        return old;
    } catch (...) {
        fs::remove_all(staging_, ec);
        finished_ = true;  // nothing left to clean up
        throw;
    }
}

void OutputFolder::finish_commit(const std::string& old) {
    std::error_code ec;
    if (!old.empty()) fs::remove_all(old, ec);
}

void OutputFolder::roll_back(const std::string& old) {
    // The new folder goes (it was in place for a moment only), the old one, if any, comes back.
    std::error_code ec;
    fs::remove_all(target_, ec);
    if (!old.empty()) fs::rename(old, target_, ec);
}

void OutputFolder::commit_all(const std::vector<OutputFolder*>& folders) {
    std::vector<std::pair<OutputFolder*, std::string>> done;  // committed, with the old folder kept aside
    try {
        for (OutputFolder* f : folders) {
            std::string old = f->commit_keep_old();
            done.emplace_back(f, std::move(old));
        }
    } catch (...) {
        for (auto it = done.rbegin(); it != done.rend(); ++it) it->first->roll_back(it->second);
        for (OutputFolder* f : folders) {  // those not reached yet: their staging folders go too
            std::error_code ec;
            if (!f->finished_ && f->staged_) fs::remove_all(f->staging_, ec);
            f->finished_ = true;
        }
        throw;
    }
    for (auto& [f, old] : done) f->finish_commit(old);
}

}  // namespace ngi
