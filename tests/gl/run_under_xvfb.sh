#!/usr/bin/env bash
# Runs a GL program under its own virtual X server (Xvfb, Mesa llvmpipe) and leaves nothing running however it ends.
# xvfb-run did not: killed alone (an outer `timeout --foreground`, `timeout -k`, a SIGKILL) it left Xvfb and the
# program running, reparented to init (issue 51). Here both are started with a parent-death signal (`setpriv
# --pdeathsig`, util-linux), so even a SIGKILL of this script takes them down; TERM, INT and a normal end stop both
# and remove the server's files. Exit 77 (ctest's SKIP_RETURN_CODE for the GL tests) when Xvfb is not installed.
#
#   tests/gl/run_under_xvfb.sh PROGRAM [ARGS...]      NGI_XVFB_SCREEN=1280x720x24 for another screen (640x480x24)
set -u
if ! command -v Xvfb > /dev/null; then
  echo "SKIP: Xvfb not installed (Debian: xvfb)" >&2
  exit 77
fi
if [ $# -eq 0 ]; then
  echo "usage: $0 PROGRAM [ARGS...]" >&2
  exit 2
fi
pdeath=()
if setpriv --help 2>&1 | grep -q -- --pdeathsig; then pdeath=(setpriv --pdeathsig KILL --); fi
tmp=$(mktemp -d "${TMPDIR:-/tmp}/ngi-xvfb.XXXXXX")
xvfb_pid="" child=""
cleanup() {
  [ -n "$child" ] && kill -TERM "$child" 2> /dev/null
  [ -n "$xvfb_pid" ] && kill -TERM "$xvfb_pid" 2> /dev/null
  wait 2> /dev/null
  rm -rf "$tmp"
}
trap cleanup EXIT
trap 'exit 143' TERM
trap 'exit 130' INT
# -displayfd: the server picks a free display and writes its number once it accepts connections.
"${pdeath[@]}" Xvfb -displayfd 3 -screen 0 "${NGI_XVFB_SCREEN:-640x480x24}" -nolisten tcp 3> "$tmp/display" \
  2> "$tmp/xvfb.log" &
xvfb_pid=$!
for _ in $(seq 200); do
  [ -s "$tmp/display" ] && break
  if ! kill -0 "$xvfb_pid" 2> /dev/null; then
    echo "$0: Xvfb did not start:" >&2
    cat "$tmp/xvfb.log" >&2
    exit 1
  fi
  sleep 0.05
done
if [ ! -s "$tmp/display" ]; then
  echo "$0: Xvfb gave no display within 10 s" >&2
  exit 1
fi
DISPLAY=":$(head -n 1 "$tmp/display")" "${pdeath[@]}" "$@" <&0 &  # <&0: a background job keeps stdin
child=$!
wait "$child"
rc=$?
child=""
exit "$rc"
