// All-or-nothing output folders: a command that writes several files writes them into a fresh staging folder
// next to the target and renames it into place only when every file is complete, so a failure (full disk,
// killed process, bad input found late) never leaves a partial output folder behind.
#pragma once
#include <functional>
#include <string>
#include <vector>

namespace ngi {

class OutputFolder {
public:
    // Decides whether an existing folder `dir` may be replaced: returns "" if so, else the reason it may not
    // (appended to the error message).
    using ReplaceCheck = std::function<std::string(const std::string& dir)>;

    // Stages the output for folder `dir`. Error messages read "<what> <dir>: <reason>" (what = e.g. "write"). An existing
    // `dir` is replaced at commit(), never before, and only if every entry in it is named in `owned_files`
    // (the files this command may write), so a re-run replaces its own earlier output while a mistyped --out
    // never deletes unrelated files. Checks that up front (InputError naming the folder if `dir` is a file or may
    // not be replaced); the staging folder "<dir>.tmp-<pid>-<n>" (and missing parents of `dir`) is created on the
    // first file(), write() or staging() call, so nothing is on disk while a command is still computing.
    OutputFolder(const std::string& dir, const std::string& what, std::vector<std::string> owned_files);
    OutputFolder(const std::string& dir, const std::string& what, ReplaceCheck may_replace);
    OutputFolder(const OutputFolder&) = delete;
    OutputFolder& operator=(const OutputFolder&) = delete;
    // Removes the staging folder unless commit() succeeded.
    ~OutputFolder();

    // The path of `name` inside the staging folder: write the outputs there (with ngi's writers, which check
    // every write and throw on failure).
    std::string file(const std::string& name) const;
    // Runs writer(file(name)) (e.g. a lambda calling ngi::write_exr). An InputError it throws is rethrown naming
    // the file by its final path (<dir>/<name>, not the staging folder) and saying that <dir> was left unchanged.
    void write(const std::string& name, const std::function<void(const std::string& path)>& writer) const;
    // write() of a text file, checked (a full disk is an InputError naming the file).
    void write_text(const std::string& name, const std::string& text) const;
    const std::string& staging() const;
    const std::string& target() const { return target_; }

    // Moves the staging folder to `dir`. An existing `dir` is moved aside first and deleted only after the new
    // folder is in place (if that rename fails, the old folder is put back). Throws InputError on failure, after
    // removing the staging folder.
    void commit();

    // Commits several folders as one: either every folder is in place afterwards, or none is and every target is
    // as it was (a command writing two folders, e.g. ngi probe-gi --out and --write-frame, must not leave one of
    // them behind when the other fails). Each existing target is moved aside first and deleted only after every
    // new folder is in place; on a failure the folders already moved in are removed again and the old ones put
    // back. Throws the first failure's InputError after that rollback (the staging folders are removed).
    static void commit_all(const std::vector<OutputFolder*>& folders);

private:
    void check_replaceable() const;
    void stage() const;
    // commit() in two steps: put the new folder in place, keeping the old one aside (its path is returned, "" if
    // there was none); then finish_commit deletes it, or roll_back restores it.
    std::string commit_keep_old();
    void finish_commit(const std::string& old);
    void roll_back(const std::string& old);

    std::string what_, target_, staging_;
    ReplaceCheck may_replace_;
    mutable bool staged_ = false;
    bool finished_ = false;
};

}  // namespace ngi
