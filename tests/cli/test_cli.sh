#!/usr/bin/env bash
# End-to-end CLI checks (ctest cli_end_to_end): render a tiny frame, merge it, run a generator on it; then the
# bad-input cases must fail with exit code 1 (bad options: 2), name the offending file or option, never reach the
# "unexpected error" catch-all, and leave no output (not even a partial folder on a full disk) behind. The CLI
# conventions too: --version, --help of each command, one-line usage errors.
# Usage: test_cli.sh NGI_BINARY WORK_DIR
set -euo pipefail
ngi=$1 work=$2
rm -rf "$work" && mkdir -p "$work"
# A 6-level pix2pix generator from PyTorch (random weights): the CLI's plumbing, not the model, is under test.
# The script imports the Python package ngi of the build tree (<build>/python; ctest sets PYTHONPATH to it).
PYTHONPATH=${PYTHONPATH:-$(dirname "$ngi")/python} /usr/bin/python3 "$(dirname "$0")/../parity/make_parity.py" \
    --out "$work/parity" > "$work/parity.log" 2>&1
model=$work/parity/pix2pix_running.safetensors
fail() { echo "FAILED: $*" >&2; exit 1; }

# A 32 x 32 frame: global view 128 x 64, which the 6-level parity generator accepts.
"$ngi" render --scene room:seed=1 --face 32 --spp 4 --feature-spp 1 --out "$work/frame" > /dev/null
# render.json records the render for scripts (no parsing of the printed summary): scene size, camera, timings.
/usr/bin/python3 -c "import json, sys; r = json.load(open(sys.argv[1]))
assert r['scene']['size'] == [20, 8, 24] and r['camera']['frame'] == 0 and r['camera']['path_frames'] == 100, r
assert len(r['camera']['position']) == 3 and r['settings']['reference_spp'] == 4 and r['timing']['reference_ms'] > 0, r
" "$work/frame/render.json" || fail "ngi render: render.json lacks the scene, camera or timings"
# --path-seed: another camera path of the same kind (ngi_train.adapt's training views), recorded in render.json;
# the same seed twice is the same view, no seed is the dataset's path.
i=0
for s in 7101 7101 7102; do
  i=$((i + 1))
  "$ngi" render --scene room:seed=1 --face 8 --spp 1 --feature-spp 1 --path-seed $s --frame 3 --out "$work/path_$i" > /dev/null
done
"$ngi" render --scene room:seed=1 --face 8 --spp 1 --feature-spp 1 --frame 3 --out "$work/path_dataset" > /dev/null
/usr/bin/python3 -c "import json, sys
by = {}
for name in ('path_1', 'path_2', 'path_3', 'path_dataset'):
    r = json.load(open(sys.argv[1] + '/' + name + '/render.json'))
    by.setdefault(r['path_seed'], set()).add(tuple(r['camera']['position']))
assert set(by) == {7101, 7102, None}, by
assert len(by[7101]) == 1 and len({frozenset(v) for v in by.values()}) == 3, by
" "$work" || fail "ngi render --path-seed: not one view per seed, or the dataset's view"
"$ngi" merge --frame "$work/frame" --out "$work/merged" > /dev/null
for f in globalview_albedo.exr globalview_normal.exr coord.exr input.npy; do
  [ -s "$work/merged/$f" ] || fail "ngi merge did not write $f"
done
"$ngi" lightmap --frame "$work/frame" --model "$model" --out "$work/lm" > /dev/null 2> "$work/lm.err"
for f in lightmap.exr final.png compare.png metrics.json; do
  [ -s "$work/lm/$f" ] || fail "ngi lightmap did not write $f"
done
# The frame's direct light was rendered at 1 spp (render.json): noisy, which no engine's is (issue 45).
grep -q "the direct light was rendered at 1 spp" "$work/lm.err" || fail "lightmap did not warn of noisy light: $(cat "$work/lm.err")"
# An ssgi rung (no network) by its name: the light the six faces show, added to the direct light.
"$ngi" lightmap --frame "$work/frame" --model ssgi_surround --out "$work/lm_ssgi" > "$work/lm_ssgi.out" 2> /dev/null
grep -q "input none (ssgi, surround faces, 1 bounce)" "$work/lm_ssgi.out" || fail "lightmap with ssgi_surround: $(cat "$work/lm_ssgi.out")"
/usr/bin/python3 -c "import json, sys; m = json.load(open(sys.argv[1]))
assert m['output_mode'] == 'indirect' and m['scores_valid'] and m['network']['final_ldr']['psnr'] > 0, m
" "$work/lm_ssgi/metrics.json" || fail "lightmap with ssgi_surround: $(cat "$work/lm_ssgi/metrics.json")"
# At display resolution (issue 47): the same camera rendered at face 48 (not a multiple of 32), the lightmap's
# indirect light upsampled to it and composed with its own direct light; outputs and metrics at 48 x 48.
"$ngi" render --scene room:seed=1 --face 48 --spp 4 --feature-spp 1 --out "$work/frame48" > /dev/null
"$ngi" lightmap --frame "$work/frame" --display "$work/frame48" --model ssgi_surround --out "$work/lm_display" \
    > "$work/lm_display.out" 2> /dev/null
grep -q "lightmap.exr (48x48)" "$work/lm_display.out" || fail "lightmap --display: $(cat "$work/lm_display.out")"
/usr/bin/python3 -c "import json, sys; m = json.load(open(sys.argv[1]))
assert m['display']['size'] == 48 and m['display']['upsampler'] == 'jbu' and m['network']['final_ldr']['psnr'] > 0, m
" "$work/lm_display/metrics.json" || fail "lightmap --display: $(cat "$work/lm_display/metrics.json")"
"$ngi" render --scene room:seed=1 --face 48 --frame 7 --spp 4 --feature-spp 1 --no-reference --out "$work/frame48_moved" > /dev/null
if "$ngi" lightmap --frame "$work/frame" --display "$work/frame48_moved" --model ssgi_surround --out "$work/lm_moved" \
    > /dev/null 2> "$work/lm_moved.err"; then fail "lightmap --display with another camera ran"; fi
grep -q "display frame's camera" "$work/lm_moved.err" || fail "lightmap --display, other camera: $(cat "$work/lm_moved.err")"
[ ! -e "$work/lm_moved" ] || fail "lightmap --display, other camera: left $work/lm_moved behind"

# A frame whose front albedo is all NaN (issue 31, "a score that lies": it once ran with exit 0, "0 NaN/Inf
# sanitized" and MSE 0 / SSIM 1): it runs, the count per file is warned on stderr and printed, and every score in
# metrics.json is null with a note, scores_valid false, the file listed.
cp -r "$work/frame" "$work/frame_nan"
/usr/bin/python3 "$(dirname "$0")/write_exr.py" "$work/frame_nan/front_albedo.exr" 32 32 R,G,B nan
"$ngi" lightmap --frame "$work/frame_nan" --model "$model" --out "$work/lm_nan" > "$work/lm_nan.out" 2> "$work/lm_nan.err"
grep -q "warning: .*frame_nan: 3072 NaN/Inf values replaced on read (front_albedo.exr: 3072 NaN)" "$work/lm_nan.err" ||
  fail "lightmap on a NaN albedo did not warn: $(cat "$work/lm_nan.err")"
grep -q "NaN/Inf replaced: 3072 in the frame's files" "$work/lm_nan.out" || fail "lightmap's count: $(tail -1 "$work/lm_nan.out")"
/usr/bin/python3 -c "import json, sys; m = json.load(open(sys.argv[1]))
assert m['scores_valid'] is False and m['frame_sanitized'] == [{'file': 'front_albedo.exr', 'nan': 3072, 'inf': 0}], m
for side in ('network', 'direct_only'):
    for v in m[side].values():
        assert v['mse'] is None and v['psnr'] is None and v['ssim'] is None and 'front_albedo.exr' in v['note'], v
" "$work/lm_nan/metrics.json" || fail "lightmap on a NaN albedo: $(cat "$work/lm_nan/metrics.json")"
/usr/bin/python3 -c "import json, sys; assert json.load(open(sys.argv[1]))['scores_valid'] is True" "$work/lm/metrics.json" ||
  fail "a clean frame's metrics.json does not say scores_valid true"
# Negative depth is refused on read, naming the file (neural-gi refused it; lightmap once ran on it).
cp -r "$work/frame" "$work/frame_negdepth"
/usr/bin/python3 "$(dirname "$0")/write_exr.py" "$work/frame_negdepth/front_depth.exr" 32 32 Y 5.0 -1.0

# ngi metrics prints strict JSON: a PSNR/SSIM that is not a number is null with a note saying why
# (docs/CONVENTIONS.md, Metrics). check_metrics FILE_A FILE_B RANGE PYTHON_ASSERTION (m = the parsed output).
check_metrics() {
  "$ngi" metrics "$1" "$2" --range "$3" > "$work/metrics.out"
  /usr/bin/python3 -c "import json, sys; m = json.loads(open(sys.argv[1]).read()); assert $4, m" "$work/metrics.out" ||
    fail "ngi metrics $1 $2 --range $3: $(cat "$work/metrics.out")"
}
ref=$work/frame/reference.exr direct=$work/frame/front_direct.exr
check_metrics "$ref" "$ref" 1 \
  'm["mse"] == 0 and m["psnr"] is None and "+infinity" in m["psnr_note"] and m["ssim"] == 1 and "ssim_note" not in m'
check_metrics "$direct" "$ref" 0 \
  'm["mse"] > 0 and m["psnr"] is None and m["ssim"] is None and "data_range is 0" in m["psnr_note"] + m["ssim_note"]'
check_metrics "$direct" "$ref" 2 'set(m) == {"mse", "psnr", "ssim"} and all(type(v) is float for v in m.values())'

# expect_failure NAME CMD...: exit code 1, the message names $expect, no $work/NAME output folder.
expect_failure() {
  local name=$1; shift
  set +e
  "$@" > "$work/$name.out" 2> "$work/$name.err"
  local rc=$?
  set -e
  [ $rc -eq 1 ] || fail "$name: exit code $rc, expected 1"
  grep -q -- "$expect" "$work/$name.err" || fail "$name: message does not name $expect: $(cat "$work/$name.err")"
  [ ! -e "$work/out_$name" ] || fail "$name: left output behind in $work/out_$name"
}

cp -r "$work/frame" "$work/missing" && rm "$work/missing/left_depth.exr"
expect=left_depth.exr
expect_failure missing_merge "$ngi" merge --frame "$work/missing" --out "$work/out_missing_merge"
expect_failure missing_lightmap "$ngi" lightmap --frame "$work/missing" --model "$model" --out "$work/out_missing_lightmap"
expect="front_depth.exr: 1 of 1024 pixels have a negative depth"
expect_failure negative_depth "$ngi" lightmap --frame "$work/frame_negdepth" --model "$model" --out "$work/out_negdepth"

cp -r "$work/frame" "$work/truncated" && head -c 100 "$work/frame/up_normal.exr" > "$work/truncated/up_normal.exr"
expect=up_normal.exr
expect_failure truncated "$ngi" merge --frame "$work/truncated" --out "$work/out_truncated"

expect=nonexistent.safetensors
expect_failure no_model "$ngi" lightmap --frame "$work/frame" --model "$work/nonexistent.safetensors" --out "$work/out_no_model"

# Plans (python3 -m ngi.plan writes them; docs/MODEL_FORMAT.md, "Plans"): the rung's model relative to the plan's
# folder runs exactly as --model does; a switch runs its rung below the outside light share; bad plans are refused.
plan() { printf '%s\n' "$2" > "$work/$1.json"; }
plan plan_ok '{"format": "ngi-plan", "version": 1, "rung": "parity", "model": "parity/pix2pix_running.safetensors", "n": 32}'
"$ngi" lightmap --frame "$work/frame" --plan "$work/plan_ok.json" --out "$work/lm_plan" > "$work/plan_ok.out"
cmp -s "$work/lm/lightmap.exr" "$work/lm_plan/lightmap.exr" || fail "lightmap --plan differs from --model"
grep -q "rung parity" "$work/plan_ok.out" || fail "lightmap --plan: $(cat "$work/plan_ok.out")"
plan plan_switch '{"format": "ngi-plan", "version": 1, "rung": "parity", "model": "parity/pix2pix_running.safetensors",
  "n": 32, "switch": {"below_outside_light_share": 1, "rung": "parity_per_image", "n": 32,
  "model": "parity/pix2pix_running.safetensors", "bn_mode": "per_image"}}'
"$ngi" lightmap --frame "$work/frame" --plan "$work/plan_switch.json" --out "$work/lm_switch" > /dev/null
/usr/bin/python3 -c "import json, sys; p = json.load(open(sys.argv[1]))['plan']
assert p['rung'] == 'parity_per_image' and p['switched'] and 0 <= p['outside_light_share'] < 1, p" \
  "$work/lm_switch/metrics.json" || fail "lightmap --plan with a switch: $(cat "$work/lm_switch/metrics.json")"
cmp -s "$work/lm/lightmap.exr" "$work/lm_switch/lightmap.exr" && fail "the switch's bn_mode per_image was not applied"
plan plan_direct '{"format": "ngi-plan", "version": 1, "rung": "direct_only", "model": null, "n": 32}'
"$ngi" lightmap --frame "$work/frame" --plan "$work/plan_direct.json" --out "$work/lm_direct" > /dev/null
/usr/bin/python3 -c "import json, sys; m = json.load(open(sys.argv[1]))
assert m['plan']['rung'] == 'direct_only' and m['plan']['model'] is None and m['network'] == m['direct_only'], m" \
  "$work/lm_direct/metrics.json" || fail "lightmap --plan direct_only: $(cat "$work/lm_direct/metrics.json")"
plan plan_n64 '{"format": "ngi-plan", "version": 1, "rung": "big", "model": "parity/pix2pix_running.safetensors", "n": 64}'
expect="face size 64"
expect_failure plan_n64 "$ngi" lightmap --frame "$work/frame" --plan "$work/plan_n64.json" --out "$work/out_plan_n64"
plan plan_missing '{"format": "ngi-plan", "version": 1, "rung": "gone", "model": "nowhere.safetensors", "n": 32}'
expect="nowhere.safetensors does not exist (rung gone)"
expect_failure plan_missing "$ngi" lightmap --frame "$work/frame" --plan "$work/plan_missing.json" --out "$work/out_plan_missing"
# Issue 51: a repeated key once ran the last "model"; a model path that is a folder, a FIFO or a device was "does not
# exist".
plan plan_twice '{"format": "ngi-plan", "version": 1, "rung": "parity", "model": "parity/pix2pix_running.safetensors", "n": 32, "model": "nowhere.safetensors"}'
expect="the key 'model' appears twice in one object"
expect_failure plan_twice "$ngi" lightmap --frame "$work/frame" --plan "$work/plan_twice.json" --out "$work/out_plan_twice"
mkfifo "$work/fifo.safetensors"
for target in "parity:is a directory" "fifo.safetensors:is a FIFO, not a regular file" "/dev/zero:is a device, not a regular file"; do
  plan plan_kind "{\"format\": \"ngi-plan\", \"version\": 1, \"rung\": \"odd\", \"model\": \"${target%%:*}\", \"n\": 32}"
  expect="${target#*:} (rung odd)"
  expect_failure plan_kind "$ngi" lightmap --frame "$work/frame" --plan "$work/plan_kind.json" --out "$work/out_plan_kind"
done
plan plan_format '{"rung": "x", "model": "parity/pix2pix_running.safetensors", "n": 32}'
expect="plan_format.json: not a plan"
expect_failure plan_format "$ngi" lightmap --frame "$work/frame" --plan "$work/plan_format.json" --out "$work/out_plan_format"

# No reproducer below may reach main()'s catch-all: every failure is a typed error naming its file or option.
no_unexpected() { ! grep -q "unexpected error" "$work/$1.err" || fail "$1: untyped error: $(cat "$work/$1.err")"; }

# expect_usage NAME CMD...: exit code 2 (usage error), the message names $expect, no $work/out_NAME.
expect_usage() {
  local name=$1; shift
  set +e
  "$@" > "$work/$name.out" 2> "$work/$name.err"
  local rc=$?
  set -e
  [ $rc -eq 2 ] || fail "$name: exit code $rc, expected 2 (usage): $(cat "$work/$name.err")"
  grep -q -- "$expect" "$work/$name.err" || fail "$name: message does not name $expect: $(cat "$work/$name.err")"
  [ ! -e "$work/out_$name" ] || fail "$name: left output behind in $work/out_$name"
}

# ---- The per-frame guard (--guard T, or a plan's "guard"; docs/CONVENTIONS.md section 17): a frame whose lightmap adds
# more than T of its final image beyond direct light falls back to direct light. A tiny T makes the random-weight
# generator's frame fall back (its lightmap is then the direct-light rung's, and so are its scores); T = 1 never does.
# check_guard DIR FELL_BACK: metrics.json records the guard, and "network" is direct light exactly when it fell back.
check_guard() {
  /usr/bin/python3 -c "import json, sys; m = json.load(open(sys.argv[1])); g = m['guard']
assert set(g) == {'max_indirect_share', 'indirect_share', 'fell_back'} and 0 < g['indirect_share'] <= 1, g
assert g['fell_back'] is $2 and (m['network'] == m['direct_only']) is $2, m" "$work/$1/metrics.json" ||
    fail "lightmap guard in $1: $(cat "$work/$1/metrics.json")"
}
"$ngi" lightmap --frame "$work/frame" --model "$model" --guard 1e-9 --out "$work/lm_guard_low" > "$work/guard_low.out"
check_guard lm_guard_low True
cmp -s "$work/lm_direct/lightmap.exr" "$work/lm_guard_low/lightmap.exr" || fail "guard fallback: not the direct light"
grep -q "^guard      indirect share .* > 1e-09: direct light used" "$work/guard_low.out" ||
  fail "guard fallback: $(cat "$work/guard_low.out")"
"$ngi" lightmap --frame "$work/frame" --model "$model" --guard 1 --out "$work/lm_guard_keep" > "$work/guard_keep.out"
check_guard lm_guard_keep False
cmp -s "$work/lm/lightmap.exr" "$work/lm_guard_keep/lightmap.exr" || fail "guard 1 changed the network's lightmap"
grep -q "^guard      indirect share .* <= 1.000: network kept" "$work/guard_keep.out" ||
  fail "guard kept: $(cat "$work/guard_keep.out")"
plan plan_guard '{"format": "ngi-plan", "version": 1, "rung": "parity", "model": "parity/pix2pix_running.safetensors",
  "n": 32, "guard": {"max_indirect_share": 1e-9}}'
"$ngi" lightmap --frame "$work/frame" --plan "$work/plan_guard.json" --out "$work/lm_plan_guard" > /dev/null
check_guard lm_plan_guard True
"$ngi" lightmap --frame "$work/frame" --plan "$work/plan_guard.json" --guard 1 --out "$work/lm_plan_guard1" > /dev/null
check_guard lm_plan_guard1 False  # an explicit --guard overrides the plan's
cmp -s "$work/lm/lightmap.exr" "$work/lm_plan_guard1/lightmap.exr" || fail "--guard 1 over a plan's guard: not the network"
plan plan_guard0 '{"format": "ngi-plan", "version": 1, "rung": "parity", "model": "parity/pix2pix_running.safetensors",
  "n": 32, "guard": {"max_indirect_share": 0}}'
expect="guard.max_indirect_share must be a number with 0 < T <= 1, got 0"
expect_failure plan_guard0 "$ngi" lightmap --frame "$work/frame" --plan "$work/plan_guard0.json" --out "$work/out_plan_guard0"
plan plan_guard_key '{"format": "ngi-plan", "version": 1, "rung": "parity", "model": "parity/pix2pix_running.safetensors",
  "n": 32, "guard": {"max_indirect_shares": 0.5}}'
expect="guard has an unknown key 'max_indirect_shares'"
expect_failure plan_guard_key "$ngi" lightmap --frame "$work/frame" --plan "$work/plan_guard_key.json" --out "$work/out_plan_guard_key"
no_unexpected plan_guard0 && no_unexpected plan_guard_key
for t in 0 1.5 nan inf -0.5 0.5x ""; do
  expect=--guard; expect_usage "guard_$t" "$ngi" lightmap --frame "$work/frame" --model "$model" --guard "$t" --out "$work/out_guard_$t"
  no_unexpected "guard_$t"
done

# ---- Numeric options are parsed strictly: whole string, finite, in range; errors name the option (exit 2).
render=("$ngi" render --scene room:seed=1 --face 8 --spp 1 --feature-spp 1)
expect=--time;        expect_usage time_nan "${render[@]}" --time nan --out "$work/out_time_nan"
expect=--time;        expect_usage time_inf "${render[@]}" --time inf --out "$work/out_time_inf"
expect=--time;        expect_usage time_range "${render[@]}" --time 49 --out "$work/out_time_range"
expect=--path-frames; expect_usage path_frames "${render[@]}" --path-frames 2147483647 --out "$work/out_path_frames"
expect=--area-light;  expect_usage area_light_count "${render[@]}" --area-light 1,2,3 --out "$work/out_area_light_count"
expect=--area-light;  expect_usage area_light_nan "${render[@]}" --area-light 8,3,8,1,0,0,0,0,1,1,nan,1 --out "$work/out_area_light_nan"
# ngi neural-gi (seed 002): a frame lit by an area light through a random-weight neural_gi model (plumbing only),
# at full resolution and with joint bilateral upsampling; a frame without an area light and a generator are refused.
PYTHONPATH=${PYTHONPATH:-$(dirname "$ngi")/python} /usr/bin/python3 "$(dirname "$0")/../parity/make_neural_gi_parity.py" \
    --out "$work/ngi_parity" > "$work/ngi_parity.log" 2>&1
"$ngi" render --scene bleed:seed=3 --face 64 --spp 4 --feature-spp 1 --area-light 4,5.9,4,0.5,0,0,0,0,0.5,30,30,30 \
    --out "$work/area_frame" > /dev/null
for k in 1 2; do
  "$ngi" neural-gi --frame "$work/area_frame" --model "$work/ngi_parity/paper_mlp_f16.safetensors" --upsample $k \
      --out "$work/ngi_$k" > /dev/null
  for f in indirect.exr lighting.exr final.png compare.png metrics.json; do
    [ -s "$work/ngi_$k/$f" ] || fail "ngi neural-gi --upsample $k did not write $f"
  done
done
expect="no area light"
expect_failure ngi_no_light "$ngi" neural-gi --frame "$work/frame" --model "$work/ngi_parity/paper_mlp_f16.safetensors" --out "$work/out_ngi_no_light"
no_unexpected ngi_no_light
expect="is a pix2pix_unet model"
expect_failure ngi_generator "$ngi" neural-gi --frame "$work/area_frame" --model "$model" --out "$work/out_ngi_generator"
expect=--upsample;    expect_usage ngi_upsample "$ngi" neural-gi --frame "$work/area_frame" --model "$model" --upsample 0 --out "$work/out_ngi_upsample"
expect=--path-frames; expect_usage path_frames_overflow "${render[@]}" --path-frames 99999999999999999999 --out "$work/out_path_frames_overflow"
expect=--face;        expect_usage face_suffix "${render[@]}" --face 32x --out "$work/out_face_suffix"
expect=--spp;         expect_usage spp_zero "${render[@]}" --spp 0 --out "$work/out_spp_zero"
expect=--frame;       expect_usage frame_range "${render[@]}" --frame 100 --out "$work/out_frame_range"
expect=--tme;         expect_usage unknown_option "${render[@]}" --tme 12 --out "$work/out_unknown_option"
expect="--spp given twice"; expect_usage spp_twice "${render[@]}" --spp 3 --out "$work/out_spp_twice"
expect="unexpected argument 'stray'"; expect_usage stray "${render[@]}" stray --out "$work/out_stray"
# A --size whose images exceed the device's largest allocation is refused before the model runs (issue 31 item 6:
# 16384x16384 once reached 3.2 GB of host memory first). Only where the device's limit is below those 3 GiB.
max_alloc_mib=$("$ngi" devices --no-check | sed -n 's/.*max alloc \([0-9]*\) MiB.*/\1/p' | head -1)
if [ -n "$max_alloc_mib" ] && [ "$max_alloc_mib" -lt 3072 ]; then
  expect="beyond the device's largest allocation"
  expect_failure size_over_alloc "$ngi" lightmap --frame "$work/frame" --model "$model" --size 16384x16384 \
    --out "$work/out_size_over_alloc"
fi
# The host-memory limit (ngi/host_memory.hpp, issue 31 item 6): checked before allocating, named with the bytes
# needed and how to raise it; a malformed limit names the variable. A 32x32 RGB face decodes to 12 KB.
expect="host-memory limit of 8192 bytes"
NGI_HOST_MEMORY_LIMIT=8K expect_failure host_limit_read "$ngi" merge --frame "$work/frame" --out "$work/out_host_limit_read"
expect="ngi lightmap --size 4096x4096: needs 1610612736 bytes (1.5 GiB) of host memory at once"
NGI_HOST_MEMORY_LIMIT=256M expect_failure host_limit_size "$ngi" lightmap --frame "$work/frame" --model "$model" \
  --size 4096x4096 --out "$work/out_host_limit_size"
expect="render: a frame of face size 8192: needs"
NGI_HOST_MEMORY_LIMIT=1G expect_failure host_limit_render "$ngi" render --scene room:seed=1 --face 8192 --spp 1 \
  --out "$work/out_host_limit_render"
expect="NGI_HOST_MEMORY_LIMIT='lots'"
NGI_HOST_MEMORY_LIMIT=lots expect_failure host_limit_bad "$ngi" merge --frame "$work/frame" --out "$work/out_host_limit_bad"
expect=--size;        expect_usage size_bad "$ngi" lightmap --frame "$work/frame" --model "$model" --size 12x --out "$work/out_size_bad"
expect=--size;        expect_usage size_zero "$ngi" lightmap --frame "$work/frame" --model "$model" --size 0x8 --out "$work/out_size_zero"
expect=--plan;        expect_usage plan_and_model "$ngi" lightmap --frame "$work/frame" --model "$model" --plan "$work/plan_ok.json" --out "$work/out_plan_and_model"
expect="--model or --plan"; expect_usage no_model_no_plan "$ngi" lightmap --frame "$work/frame" --out "$work/out_no_model_no_plan"
expect=--range;       expect_usage range_nan "$ngi" metrics "$work/lm/final.png" "$work/lm/final.png" --range nan
expect=--mode;        expect_usage mode_bad "$ngi" merge --frame "$work/frame" --mode cubic --out "$work/out_mode_bad"

# ---- CLI conventions: --version, --help per command, one-line usage errors (exit 2), missing files (exit 1).
version=$(sed -n 's/^project(ngi VERSION \([0-9.]*\) .*/\1/p' "$(dirname "$0")/../../CMakeLists.txt")
[ -n "$version" ] || fail "--version: no project version in CMakeLists.txt"
out=$("$ngi" --version) || fail "ngi --version: exit code $?"
[ "$out" = "ngi $version" ] || fail "ngi --version printed '$out', expected 'ngi $version'"
for help in "--help" "help"; do
  "$ngi" $help > "$work/help.out" || fail "ngi $help: exit code $?"
  for word in devices generate metrics merge lightmap render dataset ao-data voxel-data probe-gi "exit codes" "3 device failure"; do
    grep -q -- "$word" "$work/help.out" || fail "ngi $help does not mention $word: $(cat "$work/help.out")"
  done
done
"$ngi" render --help > "$work/render_help.out" || fail "ngi render --help: exit code $?"
grep -q -- "--spp" "$work/render_help.out" || fail "ngi render --help does not mention --spp"
grep -q -- "default 64" "$work/render_help.out" || fail "ngi render --help does not give --spp's default"
! grep -q -- "--model" "$work/render_help.out" || fail "ngi render --help shows other commands' options"
"$ngi" help lightmap > "$work/lightmap_help.out" || fail "ngi help lightmap: exit code $?"
grep -q -- "--size" "$work/lightmap_help.out" && ! grep -q -- "--spp" "$work/lightmap_help.out" ||
  fail "ngi help lightmap: $(cat "$work/lightmap_help.out")"
"$ngi" merge --help | grep -q "thesis|equirect" || fail "ngi merge --help does not list --mode's values"
# A usage error is one line naming the option and where the options are listed, not the whole usage.
expect=--bogus; expect_usage bogus "$ngi" render --bogus 1
[ "$(wc -l < "$work/bogus.err")" -eq 1 ] || fail "bogus: more than one line: $(cat "$work/bogus.err")"
grep -q "run 'ngi render --help' for the options" "$work/bogus.err" || fail "bogus: no pointer to --help: $(cat "$work/bogus.err")"
! grep -q -- "lightmap\|--model" "$work/bogus.err" || fail "bogus: printed other commands' usage: $(cat "$work/bogus.err")"
expect="--spp: needs an integer"; expect_usage spp_abc "$ngi" render --spp abc
expect="--spp: needs an integer"; expect_usage spp_hex "$ngi" render --scene room:seed=1 --spp 0x10 --out "$work/out_spp_hex"
expect=--spp;         expect_usage spp_missing "$ngi" render --scene room:seed=1 --out "$work/out_spp_missing" --spp
expect=--out;         expect_usage out_missing "${render[@]}"
expect=--scene;       expect_usage scene_empty "$ngi" render --scene "" --out "$work/out_scene_empty"
expect=--no-reference; expect_usage flag_value "${render[@]}" --no-reference=1 --out "$work/out_flag_value"
expect=--bn-mode;     expect_usage bn_mode "$ngi" generate --model "$model" --input "$work/merged/input.npy" --output "$work/out_bn_mode.npy" --bn-mode train
expect="unknown command 'bogus'"; expect_usage bogus_command "$ngi" bogus
expect="unknown command 'bogus'"; expect_usage help_bogus "$ngi" help bogus
expect=nonexistent.png
expect_failure missing_file "$ngi" metrics "$work/nonexistent.png" "$work/lm/final.png"

# ---- Issue 51: a model whose outputs overflow (its first convolution's weights near float's limit: the batch norm
# after it makes Inf - Inf) once wrote all-NaN with exit 0 and no word; every non-finite output is now counted.
/usr/bin/python3 -c "import sys, numpy as np, ngi.model_file as mf
t, c = mf.read_model(sys.argv[1]); t = dict(t); t['model.model.0.weight'] = np.sign(t['model.model.0.weight']) * 3e38
mf.write_model(sys.argv[2], t, c)" "$model" "$work/huge.safetensors"
"$ngi" generate --model "$work/huge.safetensors" --input "$work/merged/input.npy" --output "$work/huge.npy" \
    > "$work/huge.out" 2> "$work/huge.err"
grep -q "warning: 24576 of 24576 output values are NaN or infinite" "$work/huge.err" || fail "generate, overflowing model: $(cat "$work/huge.err")"
grep -q "nonfinite  24576 of 24576" "$work/huge.out" || fail "generate, overflowing model: $(cat "$work/huge.out")"

# ---- A reference.exr that is not the face size is refused, naming the file and both sizes.
"$ngi" render --scene room:seed=1 --face 16 --spp 1 --feature-spp 1 --out "$work/frame16" > /dev/null
cp -r "$work/frame" "$work/badref" && cp "$work/frame16/reference.exr" "$work/badref/reference.exr"
expect="reference.exr: is 16x16.*32x32"
expect_failure badref_merge "$ngi" merge --frame "$work/badref" --out "$work/out_badref_merge"
expect_failure badref_lightmap "$ngi" lightmap --frame "$work/badref" --model "$model" --out "$work/out_badref_lightmap"

# ---- Directories and devices where files are expected: typed errors naming the path, never the catch-all.
expect="$work/frame: cannot open file: it is a directory"
expect_failure dir_model "$ngi" generate --model "$work/frame" --input "$work/merged/input.npy" --output "$work/out_dir_model.npy"
expect_failure dir_input "$ngi" generate --model "$model" --input "$work/frame" --output "$work/out_dir_input.npy"
expect_failure dir_config "$ngi" dataset --config "$work/frame" --out "$work/out_dir_config"
expect="/dev/zero: cannot open file: it is a device"
expect_failure zero_model "$ngi" generate --model /dev/zero --input "$work/merged/input.npy" --output "$work/out_zero_model.npy"
expect_failure zero_input "$ngi" generate --model "$model" --input /dev/zero --output "$work/out_zero_input.npy"
expect_failure zero_config "$ngi" dataset --config /dev/zero --out "$work/out_zero_config"
expect="/dev/full: exists and is not a regular file"
expect_failure dev_full_output "$ngi" generate --model "$model" --input "$work/merged/input.npy" --output /dev/full
[ -c /dev/full ] || fail "dev_full_output: /dev/full was replaced"
echo "precious" > "$work/precious"
expect="$work/precious: exists and is not a directory"
expect_failure out_is_file "$ngi" merge --frame "$work/frame" --out "$work/precious"
[ "$(cat "$work/precious")" = precious ] || fail "out_is_file: the file was changed"
expect="holds '.*', which this command does not write"  # a folder holding other files is never replaced
expect_failure out_foreign "$ngi" merge --frame "$work/frame" --out "$work/frame"
[ -s "$work/frame/left_albedo.exr" ] || fail "out_foreign: the frame folder was changed"
expect="$work/frame: exists and is not a regular file"  # --preview naming a folder: refused before rendering
expect_failure preview_dir "${render[@]}" --out "$work/out_preview_dir" --preview "$work/frame"
# --preview is written together with the frame folder, or not at all.
"${render[@]}" --out "$work/pv_frame" --preview "$work/pv.png" > /dev/null
[ -s "$work/pv.png" ] && [ -f "$work/pv_frame/camera.json" ] || fail "render --preview: missing output"
ls "$work" | grep -q "pv.png.tmp" && fail "render --preview: temporary left behind"
# stdout is output too: metrics' JSON to a full device is an error, not exit 0.
expect="cannot write to standard output"
expect_failure stdout_full sh -c '"$0" metrics "$1" "$1" > /dev/full' "$ngi" "$work/lm/final.png"
expect="not a frame folder"  # render refuses a foreign --out before rendering
expect_failure render_foreign "${render[@]}" --out "$work/merged"
no_unexpected render_foreign
for name in stdout_full preview_dir time_nan time_inf time_range path_frames path_frames_overflow face_suffix spp_zero frame_range \
            unknown_option spp_twice stray size_bad size_zero range_nan mode_bad badref_merge badref_lightmap dir_model dir_input \
            dir_config zero_model zero_input zero_config dev_full_output out_is_file out_foreign bogus spp_abc spp_hex \
            spp_missing out_missing scene_empty flag_value bn_mode bogus_command help_bogus missing_file; do
  no_unexpected $name
done

# ---- Re-running a command replaces its own earlier output as a whole.
"$ngi" merge --frame "$work/frame" --out "$work/merged" --npy-only > /dev/null
[ ! -e "$work/merged/coord.exr" ] && [ -s "$work/merged/input.npy" ] || fail "rerun: merge --npy-only did not replace $work/merged"

# ---- A full disk in the middle of a command: exit 1, nothing at --out, no staging folder left.
# A tmpfs sized from the real outputs lets the first files succeed and a later one fail (the partial-output
# case); without mount permission, a file size limit (ulimit -f) makes the first file fail instead.
full=$work/full
mkdir -p "$full"
pages() { local t=0 f; for f in "$@"; do t=$((t + ($(stat -c %s "$f") + 4095) / 4096)); done; echo $t; }
if mount -t tmpfs -o size=64k tmpfs "$full" 2> /dev/null; then
  trap 'umount "$full" 2> /dev/null || true' EXIT
  umount "$full"
  mode=tmpfs
else
  echo "cli_end_to_end: tmpfs mount not permitted; simulating a full disk with ulimit -f (the first file fails)"
  mode=ulimit
fi
# full_disk NAME PAGES EXPECT CMD... (the command writes to $full/out): with room for PAGES pages only.
full_disk() {
  local name=$1 pages=$2; expect=$3; shift 3
  local rc
  set +e
  if [ $mode = tmpfs ]; then
    mount -t tmpfs -o size=$((pages * 4096)) tmpfs "$full" || fail "$name: mount"
    "$@" > "$work/$name.out" 2> "$work/$name.err"
    rc=$?
  else
    (trap '' XFSZ; ulimit -f 4; exec "$@") > "$work/$name.out" 2> "$work/$name.err"
    rc=$?
  fi
  set -e
  local left
  left=$(ls -A "$full")
  [ $mode = tmpfs ] && umount "$full"
  [ $rc -eq 1 ] || fail "$name: exit code $rc on a full disk, expected 1"
  [ -z "$left" ] || fail "$name: left behind on the full disk: $left"
  grep -q -- "$expect" "$work/$name.err" || fail "$name: message does not name $expect: $(cat "$work/$name.err")"
  no_unexpected $name
}
lm=("$ngi" lightmap --frame "$work/frame" --model "$model" --out "$full/out")
if [ $mode = tmpfs ]; then
  # Room for lightmap.exr only: final.png fails (before: lightmap.exr stayed behind, exit 1).
  full_disk full_lightmap_final "$(pages "$work/lm/lightmap.exr")" "final.png: write failed" "${lm[@]}"
  # Room for everything but metrics.json (before: exit 0 with an empty metrics.json).
  full_disk full_lightmap_metrics "$(pages "$work/lm/lightmap.exr" "$work/lm/final.png" "$work/lm/compare.png")" \
    "metrics.json: write failed" "${lm[@]}"
  # merge: room for the first global view only (before: some global views stayed behind).
  "$ngi" merge --frame "$work/frame" --out "$work/merged_full" > /dev/null
  full_disk full_merge "$(pages "$work/merged_full/globalview_albedo.exr")" "globalview_normal.exr: write failed" \
    "$ngi" merge --frame "$work/frame" --out "$full/out"
  # render: room for a few faces of the frame folder.
  full_disk full_render 4 "write failed" "$ngi" render --scene room:seed=1 --face 32 --spp 1 --feature-spp 1 --out "$full/out"
else
  full_disk full_lightmap 0 "lightmap.exr: write failed" "${lm[@]}"
  full_disk full_merge 0 "write failed" "$ngi" merge --frame "$work/frame" --out "$full/out"
fi

# ---- dataset: a missing test-split .vox is found before any frame is written; the corrected config then works.
cat > "$work/ds_bad.json" <<JSON
{"n": 8, "feature_spp": 1, "reference_spp": 1, "max_bounces": 1, "frames_per_scene": 1,
 "train": [{"scene": "bleed:seed=1"}], "test": [{"vox": "missing_scene.vox"}]}
JSON
expect="missing_scene.vox"
expect_failure ds "$ngi" dataset --config "$work/ds_bad.json" --out "$work/out_ds"
no_unexpected ds
sed 's/{"vox": "missing_scene.vox"}/{"scene": "backlit:seed=2"}/' "$work/ds_bad.json" > "$work/ds_good.json"
"$ngi" dataset --config "$work/ds_good.json" --out "$work/out_ds" > /dev/null 2>&1 || fail "ds: the corrected config was refused"
[ -f "$work/out_ds/test/backlit_seed2/0000/camera.json" ] || fail "ds: the corrected config rendered no test frame"

# ---- seed 001's AO: orbit data of an object, then a shipped AO network on a view with a reference.
"$ngi" ao-data --scene sculpture:seed=1 --out "$work/aod" --views 2 --heldout-views 1 --n 32 --rays 16 > /dev/null 2>&1
for f in normal.npy face_normal.npy depth.npy ao.npy view.json; do
  [ -s "$work/aod/heldout/v0000/$f" ] || fail "ngi ao-data did not write $f"
done
"$ngi" ao-data --scene sculpture:seed=1 --out "$work/aod" --views 2 --heldout-views 1 --n 32 --rays 16 2>/dev/null |
  grep -q "(0 rendered now)" || fail "ngi ao-data re-rendered finished views"
ao_model=$(dirname "$0")/../../models/ao_sculpture_16x8.safetensors
"$ngi" ao --frame "$work/aod/heldout/v0000" --model "$ao_model" --out "$work/ao" > /dev/null
for f in ao.npy ao.png compare.png metrics.json; do
  [ -s "$work/ao/$f" ] || fail "ngi ao did not write $f"
done
/usr/bin/python3 -c "import json, sys; m = json.load(open(sys.argv[1])); assert m['object_pixels'] > 0 and 0 <= m['mse_object'] < 1, m" \
  "$work/ao/metrics.json" || fail "ngi ao metrics: $(cat "$work/ao/metrics.json")"
expect="an AO model is an"
expect_failure ao_generator "$ngi" ao --frame "$work/aod/heldout/v0000" --model "$model" --out "$work/out_ao_generator"
no_unexpected ao_generator
expect=normal.npy
expect_failure ao_missing "$ngi" ao --frame "$work/missing" --model "$ao_model" --out "$work/out_ao_missing"
expect=--radius
expect_usage ao_radius "$ngi" ao --frame "$work/aod/heldout/v0000" --model "$ao_model" --out "$work/out_ao_radius" --radius nan

# ---- seed 004's voxel field: per-voxel ground truth of a small scene, then frames lit from it.
"$ngi" voxel-data --scene room:seed=1 --out "$work/vd" --directions 16 --samples 4 --bounces 1 > /dev/null
for f in attributes.npy sh.npy normal.npy probe.npy exposed.npy direct.npy lighting.npy face_lighting.npy scene.json; do
  [ -s "$work/vd/$f" ] || fail "ngi voxel-data did not write $f"
done
/usr/bin/python3 - "$work/vd" <<'PY' || fail "ngi voxel-data: inconsistent outputs"
import json, sys
import numpy as np
d = sys.argv[1]
meta = json.load(open(d + "/scene.json"))
V = meta["voxels"]
shapes = {"attributes": (V, 10), "sh": (V, 27), "normal": (V, 3), "probe": (V, 3), "exposed": (V,), "direct": (V, 3),
          "lighting": (V, 3), "face_lighting": (V, 6, 3)}
for name, shape in shapes.items():
    a = np.load(f"{d}/{name}.npy")
    assert a.shape == shape and np.isfinite(a).all(), (name, a.shape, shape)
assert V > 100 and meta["grid"] == [20, 8, 24], meta
PY
"$ngi" probe-gi --scene room:seed=1 --field "$work/vd" --out "$work/pg" --face 16 --spp 4 --ltf-bounces 2 > /dev/null
for f in metrics.json reference.exr final_reference.png lightmap_pt_sh.exr final_ltf_physical.png compare_direct.png \
         field_ltf_as_written.npy field_ltf_physical.npy; do
  [ -s "$work/pg/$f" ] || fail "ngi probe-gi did not write $f"
done
/usr/bin/python3 -c "
import json, sys
m = json.load(open(sys.argv[1]))['methods']
assert set(m) == {'direct', 'pt_voxel_lighting', 'pt_sh', 'ltf_as_written', 'ltf_physical'}, sorted(m)
assert all(v['final_ldr']['ssim'] is not None for v in m.values()), m
assert m['ltf_physical']['field_ms'] > 0 and len(m['ltf_physical']['energy_per_iterate']) == 3, m['ltf_physical']
" "$work/pg/metrics.json" || fail "ngi probe-gi metrics: $(head -c 2000 "$work/pg/metrics.json")"
voxel_model=$(dirname "$0")/../../models/voxel_sh_set.safetensors
expect="voxel_sh_set.safetensors on room:seed=1: voxel_sh model: the scene's grid is 20x8x24, the model was trained on 40x40x40"
expect_failure probe_grid "$ngi" probe-gi --scene room:seed=1 --field "$work/vd" --model "$voxel_model" --face 16 \
  --spp 4 --ltf-bounces 0 --out "$work/out_probe_grid"
no_unexpected probe_grid
expect="not those of room:seed=1 at 23"  # the lamps are on at night: another emission attribute
expect_failure probe_field "$ngi" probe-gi --scene room:seed=1 --time 23 --field "$work/vd" --face 16 --spp 4 \
  --out "$work/out_probe_field"
expect=--sh
expect_usage probe_sh "$ngi" probe-gi --scene room:seed=1 --field "$work/vd" --sh nameless --out "$work/out_probe_sh"
expect=--directions
expect_usage voxel_dirs "$ngi" voxel-data --scene room:seed=1 --out "$work/out_voxel_dirs" --directions 0

# ---- Issue 31 (reliability, round two).
# probe-gi writes --out and --write-frame all or none: a frame folder that cannot be written leaves no --out behind
# (it was committed first, then the frame write failed: exit 1 with --out in place).
expect="write frame $work/precious/frame"
expect_failure probe_write_frame "$ngi" probe-gi --scene room:seed=1 --field "$work/vd" --face 16 --spp 4 \
  --ltf-bounces 0 --out "$work/out_probe_write_frame" --write-frame "$work/precious/frame"
no_unexpected probe_write_frame
# A FIFO named like a scene is refused at once by every command that reads scenes (the .vox loader blocked in open()).
mkfifo "$work/fifo.vox"
expect="fifo.vox: cannot open file: it is a FIFO"
expect_failure fifo_render timeout 60 "$ngi" render --scene "$work/fifo.vox" --face 8 --spp 1 --out "$work/out_fifo_render"
expect_failure fifo_voxel_data timeout 60 "$ngi" voxel-data --scene "$work/fifo.vox" --out "$work/out_fifo_voxel_data"
expect_failure fifo_ao_data timeout 60 "$ngi" ao-data --scene "$work/fifo.vox" --out "$work/out_fifo_ao_data"
# --device: a device this machine does not have is a device failure (exit 3, as documented); '' is a usage error.
set +e
"$ngi" generate --model "$model" --input "$work/merged/input.npy" --output "$work/out_device.npy" --device 9:9 \
  > "$work/device_99.out" 2> "$work/device_99.err"
rc=$?
set -e
[ $rc -eq 3 ] || fail "--device 9:9: exit code $rc, expected 3: $(cat "$work/device_99.err")"
grep -q "no device matches '9:9'" "$work/device_99.err" || fail "--device 9:9: $(cat "$work/device_99.err")"
[ ! -e "$work/out_device.npy" ] || fail "--device 9:9 wrote its output"
expect=--device; expect_usage device_empty "$ngi" generate --model "$model" --input "$work/merged/input.npy" \
  --output "$work/out_device_empty.npy" --device ""
# ao-data refuses a folder of foreign files, as every other command does (it wrote its views into any folder).
expect="which ngi ao-data does not write"
expect_failure ao_data_foreign "$ngi" ao-data --scene sculpture:seed=1 --out "$work/frame" --views 1 --heldout-views 0 --n 16 --rays 1
[ ! -e "$work/frame/orbit" ] && [ ! -e "$work/frame/ao_data.json" ] || fail "ao_data_foreign: wrote into the frame folder"
# Output names of 241..255 bytes: the staging name (<name>.tmp-<pid>-<n>) is shortened to fit NAME_MAX.
long=$(printf 'n%.0s' $(seq 1 255))
"$ngi" merge --frame "$work/frame" --out "$work/$long" --npy-only > /dev/null || fail "merge into a 255-byte name"
[ -s "$work/$long/input.npy" ] || fail "merge into a 255-byte name wrote no input.npy"
"$ngi" merge --frame "$work/frame" --out "$work/$long" --npy-only > /dev/null || fail "merge re-run into a 255-byte name"
"$ngi" generate --model "$model" --input "$work/merged/input.npy" --output "$work/${long:0:251}.npy" > /dev/null ||
  fail "generate --output with a 255-byte name"
ls "$work" | grep -q "\.tmp-" && fail "long names: staging left behind: $(ls "$work" | grep "\.tmp-")"
# neural-gi refuses a model whose input_layout is not what the frame's inputs are.
/usr/bin/python3 - "$work/ngi_parity/paper_mlp_f16.safetensors" "$work/ngi_layout.safetensors" <<'PY'
import json, struct, sys
b = open(sys.argv[1], "rb").read()
n = struct.unpack("<Q", b[:8])[0]
h = json.loads(b[8:8 + n])
c = json.loads(h["__metadata__"]["ngi"])
c["input_layout"] = ["depth"] + [f"c{i}" for i in range(1, c["input_nc"])]
h["__metadata__"]["ngi"] = json.dumps(c)
t = json.dumps(h).encode()
t += b" " * (-len(t) % 8)
open(sys.argv[2], "wb").write(struct.pack("<Q", len(t)) + t + b[8 + n:])
PY
expect="input_layout differs from the assembled inputs at channel 0: model 'depth', assembled 'position.x'"
expect_failure ngi_layout "$ngi" neural-gi --frame "$work/area_frame" --model "$work/ngi_layout.safetensors" --out "$work/out_ngi_layout"
# Camera paths are built whole to render one frame: bounded at 10,000 frames (1,000,000 took 69 s before frame 0).
expect=--path-frames; expect_usage path_frames_big "${render[@]}" --path-frames 1000000 --out "$work/out_path_frames_big"
expect="frames_per_scene"
printf '{"frames_per_scene": 20000, "train": [{"scene": "room:seed=1"}]}\n' > "$work/ds_frames.json"
expect_failure ds_frames "$ngi" dataset --config "$work/ds_frames.json" --out "$work/out_ds_frames"
# metrics: a data range whose SSIM constants are not float32 numbers (1e38: "ssim": null with an empty note; 1e-45:
# PSNR -892 dB) is a usage error.
expect=--range; expect_usage range_huge "$ngi" metrics "$work/lm/final.png" "$work/lm/final.png" --range 1e38
expect=--range; expect_usage range_tiny "$ngi" metrics "$work/lm/final.png" "$work/lm/final.png" --range 1e-45
for name in fifo_render fifo_voxel_data fifo_ao_data device_empty ao_data_foreign ngi_layout path_frames_big ds_frames \
            range_huge range_tiny; do
  no_unexpected $name
done

# ngi warmup (issue 48, cold start): into an empty program cache it builds the programs an ssgi rung's frame and a
# display view need; a second process finds them all there and builds none. A cache folder that cannot be made, or
# a model that is no frame rung, is refused (exit 1) before any work.
NGI_CACHE_DIR="$work/warm_cache" "$ngi" warmup --model ssgi_surround --n 16 --display 24 --json > "$work/warm2.json"
NGI_CACHE_DIR="$work/warm_cache" "$ngi" warmup --model ssgi_surround --n 16 --display 24 --json > "$work/warm3.json"
/usr/bin/python3 -c "import json, sys
a, b = (json.load(open(f))['models'][0] for f in sys.argv[2:4])
assert json.load(open(sys.argv[2]))['cache_dir'] == sys.argv[1], 'cache_dir is not NGI_CACHE_DIR'
assert a['programs_built'] > 0 and a['programs_from_cache'] == 0, a
assert b['programs_built'] == 0 and b['programs_from_cache'] == a['programs_built'], (a, b)
" "$work/warm_cache" "$work/warm2.json" "$work/warm3.json" || fail "ngi warmup: a second process built programs again"
echo x > "$work/warm_file"
expect="program cache folder"
NGI_CACHE_DIR="$work/warm_file/cache" expect_failure warm_unwritable "$ngi" warmup --model ssgi_surround --n 16
[ "$(cat "$work/warm_file")" = x ] || fail "ngi warmup: changed the file in the way of its cache"
expect="not a frame rung"
expect_failure warm_family "$ngi" warmup --model ao_blob_16x8 --n 16

echo "cli_end_to_end: 3 commands ran; bad inputs, bad options, full disks (${mode}) refused cleanly"
