"""The source checks of tools/ci on small synthetic trees: each finds what it exists for and passes clean code."""
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent
CONSTANTS = 'LIGHT_MAX = 65504.0\nREC709_LUMA = (0.2126, 0.7152, 0.0722)\nENGINE_FEATURE_SPP = 1024\n'


def run(script, *args):
    return subprocess.run([sys.executable, str(HERE / script), *map(str, args)], capture_output=True, text=True)


def test_constant_copies_by_value_and_name(tmp_path):
    (tmp_path / "c.py").write_text(CONSTANTS)
    (tmp_path / "training").mkdir()
    (tmp_path / "kernels").mkdir()
    (tmp_path / "training" / "ok.py").write_text("from ngi import _constants\nCAP = _constants.LIGHT_MAX\nN = 1024\n")
    (tmp_path / "kernels" / "ok.cl").write_text("#define TILE 16\n")
    clean = run("check_constant_copies.py", tmp_path, tmp_path / "c.py")
    assert clean.returncode == 0, clean.stdout
    (tmp_path / "training" / "copy.py").write_text("CAP = 65504.0\nLUMA = (0.2126, 0.7152, 0.0722)\n"
                                                   "ENGINE_FEATURE_SPP = 1024\n")
    (tmp_path / "kernels" / "copy.cl").write_text("#define HALF_MAX 65504.0f\n")
    found = run("check_constant_copies.py", tmp_path, tmp_path / "c.py")
    assert found.returncode == 1
    for what in ("copy.py:1: CAP", "copy.py:2: LUMA", "copy.py:3: ENGINE_FEATURE_SPP", "copy.cl:1: HALF_MAX"):
        assert what in found.stdout, found.stdout


def test_unity_names_clash_across_files_of_one_library(tmp_path):
    render = tmp_path / "host" / "src" / "render"
    render.mkdir(parents=True)
    (tmp_path / "bindings" / "c").mkdir(parents=True)
    (render / "a.cpp").write_text("namespace {\n// struct Builder in a comment\nusing Clock = int;\n"
                                  "struct Builder { int x; };\nint helper(int v) { return v; }\n}\n")
    (render / "b.cpp").write_text('namespace {\nusing Clock = int;\nconst char* s = "struct Builder {";\n'
                                  "int other(int v);\nint other(int v) { return v; }\n}\n")
    assert run("check_unity_names.py", tmp_path).returncode == 0
    (render / "c.cpp").write_text("namespace ngi {\nnamespace {\nstruct Builder {\n};\n}\n}\n")
    found = run("check_unity_names.py", tmp_path)
    assert found.returncode == 1 and "'Builder'" in found.stdout and "a.cpp:4" in found.stdout and "c.cpp:3" in found.stdout


def test_unity_names_static_functions_and_uninitialized_variables(tmp_path):
    io = tmp_path / "host" / "src" / "io"
    io.mkdir(parents=True)
    (tmp_path / "bindings" / "c").mkdir(parents=True)
    (io / "a.cpp").write_text("static int format(int v) { return v; }\nnamespace ngi {\nnamespace {\n"
                              "thread_local int g_last;\n}\nstatic const char* kName = \"a\";\n"
                              "struct Local { static int count(int v) { return v; } };\n}\n")
    (io / "b.cpp").write_text("namespace ngi {\nint count(int v) { return v; }\n}\n")
    assert run("check_unity_names.py", tmp_path).returncode == 0  # members and external functions do not count
    (io / "c.cpp").write_text("namespace ngi::detail {\nstatic int format(int v);\nstatic int format(int v) { return v; }\n}\n"
                              "namespace {\nthread_local int g_last;\n}\nnamespace ngi { static const char* kName = \"c\"; }\n")
    found = run("check_unity_names.py", tmp_path)
    assert found.returncode == 1
    for name in ("'format'", "'g_last'", "'kName'"):
        assert name in found.stdout, found.stdout


def test_layers_refuse_single_file_source_lists(tmp_path):
    src = tmp_path / "host" / "src"
    for d in ("base", "io"):
        (src / d).mkdir(parents=True)
    (src / "base" / "npy.cpp").write_text('#include "base/npy.hpp"\n')
    (src / "base" / "npy.hpp").write_text("")
    (src / "io" / "exr.cpp").write_text('#include "base/npy.hpp"\n')
    (tmp_path / "docs").mkdir()
    (tmp_path / "docs" / "ARCHITECTURE.md").write_text("## Map\n```\npath\ndocs/\nhost/src/base/\nhost/src/io/\n```\n")
    cmake = ("file(GLOB NGI_CORE_SOURCES ${NGI_SRC}/base/*.cpp)\nfile(GLOB NGI_IO_SOURCES ${NGI_SRC}/io/*.cpp)\n"
             "target_link_libraries(ngi_io PUBLIC ngi_core)\n")
    (tmp_path / "CMakeLists.txt").write_text(cmake)
    subprocess.run(["git", "init", "-q", str(tmp_path)], check=True)
    subprocess.run(["git", "-C", str(tmp_path), "add", "-A"], check=True)
    clean = run("check_layers.py", tmp_path)
    assert clean.returncode == 0, clean.stdout
    for extra in ("list(APPEND NGI_CORE_SOURCES ${NGI_SRC}/io/exr.cpp)\n",
                  "target_sources(ngi_core PRIVATE ${NGI_SRC}/io/exr.cpp)\n"):
        (tmp_path / "CMakeLists.txt").write_text(cmake + extra)
        found = run("check_layers.py", tmp_path)
        assert found.returncode == 1 and "io/exr.cpp between libraries" in found.stdout, found.stdout


def test_test_names_refuse_semicolons(tmp_path):
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "a.cpp").write_text('TEST_CASE("fine, with [brackets] and commas", "[x]") {}\n'
                                              'TEST_CASE("split "\n          "over lines", "[x]") {}\n')
    assert run("check_test_names.py", tmp_path).returncode == 0
    (tmp_path / "tests" / "b.cpp").write_text('TEST_CASE("one; two", "[x]") {}\nTEST_CASE(" padded", "[x]") {}\n')
    found = run("check_test_names.py", tmp_path)
    assert found.returncode == 1 and "b.cpp:1" in found.stdout and "b.cpp:2" in found.stdout, found.stdout
