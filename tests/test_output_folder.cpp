// OutputFolder: the all-or-nothing multi-file output of the CLI commands and write_frame. Every failure leaves
// neither a partial <dir> nor a staging folder, and an existing <dir> survives until the new one is complete.
#include <catch2/catch.hpp>
#include <filesystem>
#include <string>
#include <vector>

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
