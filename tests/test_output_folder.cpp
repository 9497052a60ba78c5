// OutputFolder: the all-or-nothing multi-file output of the CLI commands and write_frame. Every failure leaves
// neither a partial <dir> nor a staging folder, and an existing <dir> survives until the new one is complete.
#include <catch2/catch.hpp>
#include <climits>
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "base/file_util.hpp"
#include "io_test_support.hpp"
#include "ngi/error.hpp"
#include "ngi/image_io.hpp"
#include "ngi/output_folder.hpp"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using ngi::test::TempDir;

namespace {

const std::vector<std::string> kOwned = {"a.txt", "b.txt", "big.exr"};

ngi::Image noise(int n) {  // incompressible enough that ZIP cannot shrink it below the size limit
    ngi::Image img(n, n, 3);
    unsigned s = 1;
    for (float& v : img.data) v = float((s = s * 1664525u + 1013904223u) >> 8) / 16777216.0f;
    return img;
}

}  // namespace

TEST_CASE("output folder: staged, committed, replaced", "[io][output]") {
    TempDir root("outfolder");
    const std::string dir = root / "out";
    {
        ngi::OutputFolder out(root / "deep/er/out", "write", kOwned);
        CHECK(root.list().empty());  // nothing on disk before the first file (a command may compute for long)
    }
    {
        ngi::OutputFolder out(dir, "write", kOwned);
        CHECK(root.list().empty());
        out.write_text("a.txt", "one");
        out.write_text("b.txt", "two");
        CHECK_FALSE(fs::exists(dir));  // nothing visible before commit()
        CHECK(fs::exists(out.file("a.txt")));
        out.commit();
    }
    CHECK(ngi::test::slurp(dir + "/a.txt") == "one");
    CHECK(root.list() == std::vector<std::string>{"out"});

    // A re-run replaces its own earlier output as a whole (b.txt of the old one is gone).
    {
        ngi::OutputFolder out(dir + "/", "write", kOwned);  // a trailing slash names the same folder
        out.write_text("a.txt", "three");
        out.commit();
    }
    CHECK(ngi::test::slurp(dir + "/a.txt") == "three");
    CHECK_FALSE(fs::exists(dir + "/b.txt"));
    CHECK(root.list() == std::vector<std::string>{"out"});

    // Not committed (an exception between the writes): the staging folder is removed, the old output stays.
    try {
        ngi::OutputFolder out(dir, "write", kOwned);
        out.write_text("a.txt", "half");
        throw ngi::InputError("bad input found late");
    } catch (const ngi::InputError&) {
    }
    CHECK(ngi::test::slurp(dir + "/a.txt") == "three");
    CHECK(root.list() == std::vector<std::string>{"out"});
}

TEST_CASE("output folder: refuses to replace what it does not own", "[io][output]") {
    TempDir root("outfolder-refuse");
    fs::create_directories(root / "home");
    ngi::test::spit(root / "home/thesis.tex", "precious");
    ngi::test::spit(root / "home/a.txt", "old");
    CHECK_THROWS_WITH(ngi::OutputFolder(root / "home", "write", kOwned),
                      Contains("home") && Contains("thesis.tex") && Contains("refusing"));
    CHECK(ngi::test::slurp(root / "home/thesis.tex") == "precious");
    ngi::test::spit(root / "file", "x");
    CHECK_THROWS_WITH(ngi::OutputFolder(root / "file", "write", kOwned), Contains("not a directory"));
    CHECK(ngi::test::slurp(root / "file") == "x");
    CHECK_THROWS_AS(ngi::OutputFolder(".", "write", kOwned), ngi::InputError);

    // The check is repeated at commit(): a foreign file that appeared meanwhile stops the replacement.
    fs::create_directories(root / "late");
    ngi::OutputFolder out(root / "late", "write", kOwned);
    out.write_text("a.txt", "new");
    ngi::test::spit(root / "late/notes.txt", "mine");
    CHECK_THROWS_WITH(out.commit(), Contains("notes.txt"));
    CHECK(ngi::test::slurp(root / "late/notes.txt") == "mine");
    CHECK(root.list() == std::vector<std::string>{"file", "home", "late"});
}

TEST_CASE("output folder: a full disk in the middle leaves nothing behind", "[io][output]") {
    TempDir root("outfolder-full");
    const std::string dir = root / "out";
    {
        ngi::OutputFolder out(dir, "write", kOwned);
        out.write_text("a.txt", "old");
        out.commit();
    }
    {
        ngi::test::FileSizeLimit limit(16 * 1024);
        ngi::OutputFolder out(dir, "write", kOwned);
        out.write_text("a.txt", "new");                     // fits
        CHECK_THROWS_WITH(ngi::write_exr(out.file("big.exr"), noise(128), ngi::ExrPixelType::Float),
                          Contains("big.exr"));             // ~190 KB: does not
        CHECK_THROWS_WITH(out.write_text("b.txt", std::string(64 * 1024, 'x')), Contains("b.txt"));
    }  // never committed
    CHECK(ngi::test::slurp(dir + "/a.txt") == "old");
    CHECK(root.list() == std::vector<std::string>{"out"});
}

TEST_CASE("OutputFolder::commit_all puts every folder in place or none", "[io][output]") {
    TempDir dir("output-commit-all");
    fs::create_directories(dir / "a");
    ngi::test::spit(dir / "a/x.txt", "old a");
    {  // Both staged; then b's target gains a foreign file, so b cannot be committed: a must stay as it was.
        ngi::OutputFolder a(dir / "a", "write", std::vector<std::string>{"x.txt"});
        ngi::OutputFolder b(dir / "b", "write", std::vector<std::string>{"y.txt"});
        a.write_text("x.txt", "new a");
        b.write_text("y.txt", "new b");
        fs::create_directories(dir / "b");
        ngi::test::spit(dir / "b/foreign.txt", "not ours");
        CHECK_THROWS_WITH(ngi::OutputFolder::commit_all({&a, &b}), Contains("foreign.txt"));
    }
    CHECK(ngi::test::slurp(dir / "a/x.txt") == "old a");
    CHECK(ngi::test::slurp(dir / "b/foreign.txt") == "not ours");
    CHECK(!fs::exists(dir / "b/y.txt"));
    CHECK(dir.list() == std::vector<std::string>{"a", "b"});  // no staging or .old folder left
    fs::remove_all(dir / "b");
    {  // Now both commit.
        ngi::OutputFolder a(dir / "a", "write", std::vector<std::string>{"x.txt"});
        ngi::OutputFolder b(dir / "b", "write", std::vector<std::string>{"y.txt"});
        a.write_text("x.txt", "new a");
        b.write_text("y.txt", "new b");
        ngi::OutputFolder::commit_all({&a, &b});
    }
    CHECK(ngi::test::slurp(dir / "a/x.txt") == "new a");
    CHECK(ngi::test::slurp(dir / "b/y.txt") == "new b");
    CHECK(dir.list() == std::vector<std::string>{"a", "b"});
}

TEST_CASE("output names up to NAME_MAX work: staging names are shortened to fit", "[io][output]") {
    TempDir dir("output-long-names");
    for (std::size_t len : {std::size_t(240), std::size_t(241), std::size_t(250), std::size_t(NAME_MAX)}) {
        INFO(len);
        const std::string name(len, 'n');
        const std::string tmp = ngi::detail::temp_name(dir / name);
        CHECK(fs::path(tmp).filename().string().size() <= std::size_t(NAME_MAX));
        CHECK(tmp.find(".tmp-") != std::string::npos);
        // A folder (the staging folder and the .old name of a re-run) and a single file (write_file_atomic).
        for (int run = 0; run < 2; ++run) {
            ngi::OutputFolder f(dir / name, "write", std::vector<std::string>{"a.txt"});
            f.write_text("a.txt", "run " + std::to_string(run));
            f.commit();
        }
        CHECK(ngi::test::slurp(dir / name + "/a.txt") == "run 1");
        fs::remove_all(dir / name);
        ngi::detail::write_file_atomic(dir / name, "file");
        CHECK(ngi::test::slurp(dir / name) == "file");
        fs::remove(dir / name);
    }
    CHECK(dir.list().empty());
    // A long name of multi-byte characters is cut at a character boundary.
    std::string wide;
    while (wide.size() + 2 <= 254) wide += "\xc3\xa9";  // U+00E9, two bytes
    const std::string cut = fs::path(ngi::detail::temp_name(dir / wide)).filename().string();
    const std::string stem = cut.substr(0, cut.find(".tmp-"));
    CHECK(stem.size() % 2 == 0);
    CHECK(cut.size() <= std::size_t(NAME_MAX));
}
