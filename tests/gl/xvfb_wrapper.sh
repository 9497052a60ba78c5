#!/usr/bin/env bash
# run_under_xvfb.sh leaves nothing running however it ends (issue 51: killed from outside, xvfb-run left Xvfb and the
# program running): a normal end passes the program's exit code; a SIGKILL of the wrapper alone (what `timeout
# --foreground -s KILL` or `timeout -k` does) takes its Xvfb and its program down; a SIGTERM stops both and removes
# the server's files. Exit 77 where Xvfb is missing.
set -u
wrapper="$(dirname "$0")/run_under_xvfb.sh"
command -v Xvfb > /dev/null || { echo "SKIP: Xvfb not installed" >&2; exit 77; }
fail() { echo "FAIL: $*" >&2; exit 1; }
export TMPDIR=$(mktemp -d)
trap 'rm -rf "$TMPDIR"' EXIT

bash "$wrapper" sh -c 'test -n "$DISPLAY" && exit 3'
[ $? -eq 3 ] || fail "the program's exit code (3) was not passed on"

alive() { kill -0 "$1" 2> /dev/null && ! grep -q '^State:.*Z' "/proc/$1/status" 2> /dev/null; }
for sig in KILL TERM; do
  marker="ngi-xvfb-test-$sig-$$"
  bash "$wrapper" bash -c "exec -a $marker sleep 60" &
  wrapper_pid=$!
  prog="" xvfb=""
  for _ in $(seq 100); do  # until the program runs (the server is up by then)
    prog=$(pgrep -f "^$marker" | head -n 1)
    [ -n "$prog" ] && break
    sleep 0.1
  done
  [ -n "$prog" ] || fail "the program did not start under the wrapper"
  xvfb=$(pgrep -P "$wrapper_pid" -x Xvfb | head -n 1)
  [ -n "$xvfb" ] || fail "no Xvfb child of the wrapper"
  kill -"$sig" "$wrapper_pid"
  wait "$wrapper_pid" 2> /dev/null
  for _ in $(seq 50); do
    alive "$prog" || alive "$xvfb" || break
    sleep 0.1
  done
  alive "$prog" && fail "SIG$sig of the wrapper left the program (pid $prog) running"
  alive "$xvfb" && fail "SIG$sig of the wrapper left Xvfb (pid $xvfb) running"
  echo "SIG$sig of the wrapper: Xvfb and the program ended"
done
left=$(ls "$TMPDIR" | grep -c ngi-xvfb || true)
# After the SIGKILL its folder (the display number file, the server log) stays: nothing can remove it. After the
# normal end and the SIGTERM, none does.
[ "$left" -le 1 ] || fail "the wrapper left $left folders in TMPDIR"
echo "ok"
