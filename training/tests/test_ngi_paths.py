"""Where `ngi adapt` finds things when installed (ctest training_adapt, a few seconds): the installation's ngi binary
(ngi_paths.installed_ngi) for every layout, a shallow one included; the user's cache folder (ngi_paths.user_cache_dir)
by the XDG rules, with a clear refusal where there is none; the training child's PYTHONPATH (adapt.child_pythonpath),
which keeps the order of the parent's sys.path.

    PYTHONPATH=training:build/python NGI_BIN=build/ngi /usr/bin/python3 -m pytest -q training/tests/test_ngi_paths.py
"""

import os
import sys
from pathlib import Path

import pytest

from ngi_train import adapt, ngi_paths


def executable(path):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("#!/bin/sh\n")
    path.chmod(0o755)
    return path


@pytest.fixture
def installed(monkeypatch):
    """The package as if installed (no repository), its folder given by the test."""
    monkeypatch.setattr(ngi_paths, "REPO", None)

    def at(parent):
        monkeypatch.setattr(ngi_paths, "PACKAGE_PARENT", Path(parent))
    return at


def test_installed_ngi_of_a_shallow_installation_is_none_not_an_error(installed, monkeypatch, tmp_path):
    # /app/ngi_train: no <prefix>/bin two levels above the package's folder.
    for parent in ("/app", "/"):
        installed(parent)
        assert ngi_paths.installed_ngi() is None
    # find_ngi looks at every candidate first: NGI_BIN still wins.
    ngi_bin = executable(tmp_path / "ngi")
    monkeypatch.setenv("NGI_BIN", str(ngi_bin))
    assert ngi_paths.find_ngi() == str(ngi_bin)


def test_installed_ngi_in_a_virtual_environment_is_the_real_binary(installed, tmp_path):
    site = tmp_path / "venv" / "lib" / "python3.11" / "site-packages"
    executable(tmp_path / "venv" / "bin" / "ngi")  # pip's entry point, which runs ngi/ngi-cli
    real = executable(site / "ngi" / "ngi-cli")
    installed(site)
    assert ngi_paths.installed_ngi() == str(real)


def test_installed_ngi_of_a_prefix_is_its_bin_ngi(installed, tmp_path):
    site = tmp_path / "prefix" / "lib" / "python3" / "dist-packages"
    (site / "ngi").mkdir(parents=True)
    installed(site)
    assert ngi_paths.installed_ngi() is None
    ngi_bin = executable(tmp_path / "prefix" / "bin" / "ngi")
    assert ngi_paths.installed_ngi() == str(ngi_bin)


def test_user_cache_dir_follows_xdg(monkeypatch, tmp_path):
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert ngi_paths.user_cache_dir() == tmp_path / "xdg" / "ngi"
    # A relative $XDG_CACHE_HOME is invalid (XDG Base Directory specification): ignored, not a folder in the
    # current one.
    for value in ("cache", "./cache", ""):
        monkeypatch.setenv("XDG_CACHE_HOME", value)
        assert ngi_paths.user_cache_dir() == tmp_path / "home" / ".cache" / "ngi"


def test_user_cache_dir_without_home_is_a_clear_error(installed, monkeypatch):
    installed(ngi_paths.PACKAGE_PARENT)
    monkeypatch.setenv("XDG_CACHE_HOME", "relative")
    for home in (None, "", "relative/home"):
        if home is None:
            monkeypatch.delenv("HOME", raising=False)
        else:
            monkeypatch.setenv("HOME", home)
        with pytest.raises(ngi_paths.CacheDirError, match="cannot find the user's cache folder"):
            ngi_paths.user_cache_dir()
        with pytest.raises(adapt.AdaptError, match="--work DIR"):
            adapt.default_work("room:seed=3")


def test_adapt_without_a_cache_folder_is_refused_before_any_work(installed, monkeypatch, tmp_path, capsys):
    installed(ngi_paths.PACKAGE_PARENT)
    monkeypatch.delenv("HOME", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    # A user without a passwd entry either (a container's arbitrary uid): nothing knows a home folder, and a
    # lookup that finds one anyway must not lead this test into the real one.
    monkeypatch.setattr("pwd.getpwuid", lambda uid: (_ for _ in ()).throw(KeyError(uid)))
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "m.safetensors"
    # A budget too small for any frame: should the folder be found after all, the run stops right after making it.
    assert adapt.main(["--scene", "knot:seed=1", "--out", str(out), "--budget-minutes", "0.001"]) == 2
    err = capsys.readouterr().err
    assert "cannot find the user's cache folder" in err and "Traceback" not in err, err
    assert list(tmp_path.iterdir()) == []


def test_training_child_pythonpath_keeps_the_order_of_sys_path():
    parent = str(ngi_paths.PACKAGE_PARENT)
    # The package's folder on the path already (an installation's site folder, behind the user's own): in place.
    path = ["/build/python", "/usr/lib/python311.zip", "/usr/local/lib/python3.11/dist-packages", parent,
            "/usr/lib/python3/dist-packages"]
    assert adapt.child_pythonpath(path) == os.pathsep.join(path)
    # Through another spelling of the same folder: still found.
    spelled = path[:3] + [parent + "/../" + Path(parent).name] + path[4:]
    assert adapt.child_pythonpath(spelled) == os.pathsep.join(spelled)
    # Not on it (the package run from elsewhere): first. The current folder ('') is never handed on.
    assert adapt.child_pythonpath(["", "/usr/lib/python3.11"]) == os.pathsep.join([parent, "/usr/lib/python3.11"])
    # By default this process's sys.path.
    assert adapt.child_pythonpath() == adapt.child_pythonpath(list(sys.path))
