#!/usr/bin/env bash
# Runs a GL program under a virtual X server (Mesa llvmpipe). Exit 77 (ctest's SKIP_RETURN_CODE for the GL tests)
# when xvfb-run is not installed: no display, nothing to test against.
if ! command -v xvfb-run > /dev/null; then
  echo "SKIP: xvfb-run not installed (Debian: xvfb xauth)" >&2
  exit 77
fi
exec xvfb-run -a -s "-screen 0 640x480x24" "$@"
