"""The `ngi` command of a pip-installed package (pyproject.toml [project.scripts]): runs the native CLI that
`pip install .` put beside this file (ngi/ngi-cli). A Debian package or `cmake --install` installs the CLI itself
as <prefix>/bin/ngi instead."""

import os
import sys
from pathlib import Path


def main():
    exe = Path(__file__).with_name("ngi-cli")
    if not os.access(exe, os.X_OK):
        sys.exit(f"ngi: the native command-line tool {exe} is not part of this installation (pip install . builds "
                 f"it; a CMake build has it as <build>/ngi)")
    # `ngi adapt` runs the Python adaptation with this interpreter (the one the package is installed for).
    os.environ.setdefault("NGI_PYTHON", sys.executable)
    os.execv(exe, ["ngi", *sys.argv[1:]])


if __name__ == "__main__":
    main()
