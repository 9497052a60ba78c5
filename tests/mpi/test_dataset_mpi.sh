#!/usr/bin/env bash
# ngi-dataset-mpi end to end (ctest dataset_mpi): a small dataset rendered over K = 1, 2, 3 MPI ranks
# (--oversubscribe on 2 cores) is byte for byte the single-process `ngi dataset` result; a run with frames, a scene
# file and temporaries missing (as a killed run leaves them) resumes with another K to the same bytes; ranks given
# different configs, and a rerun with another config, are refused before anything is written.
# Usage: test_dataset_mpi.sh NGI NGI_DATASET_MPI WORK_DIR
set -euo pipefail
ngi=$1 mpi=$2 work=$3
rm -rf "$work" && mkdir -p "$work"
fail() { echo "FAILED: $*" >&2; exit 1; }
# CI runs as root; OpenMPI refuses that unless told. Shared memory and self only: no network at all.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader OMPI_MCA_rmaps_base_oversubscribe=1
run_mpi() { local k=$1; shift; mpirun -np "$k" "$mpi" "$@"; }

cat > "$work/config.json" <<'JSON'
{"n": 16, "feature_spp": 1, "reference_spp": 4, "max_bounces": 2, "frames_per_scene": 3, "keyframe_interval": 2,
 "train": [{"scene": "room:seed=1"}, {"scene": "bleed:seed=2", "frames": 4}], "test": [{"scene": "cave:seed=3"}]}
JSON
sed 's/"n": 16/"n": 24/' "$work/config.json" > "$work/other.json"

"$ngi" dataset --config "$work/config.json" --out "$work/single" > /dev/null 2> "$work/single.log"
frames=$(find "$work/single" -name camera.json | wc -l)
[ "$frames" -eq 10 ] || fail "the single-process dataset has $frames frames, expected 10"

for k in 1 2 3; do
  run_mpi "$k" --config "$work/config.json" --out "$work/mpi$k" > "$work/mpi$k.out" 2> "$work/mpi$k.log" ||
    { cat "$work/mpi$k.log" >&2; fail "mpirun -np $k failed"; }
  diff -r "$work/single" "$work/mpi$k" > /dev/null || fail "K = $k differs from the single-process dataset"
  grep -q "10/10 frames" "$work/mpi$k.log" || fail "K = $k: rank 0 did not report the whole job (10/10 frames)"
  grep -q "10 frames rendered by $k ranks" "$work/mpi$k.out" || fail "K = $k: $(cat "$work/mpi$k.out")"
  echo "dataset_mpi: K = $k identical to one process" >&2
done

# Resume: what a killed run leaves (missing frames, a missing scene.json, temporaries of unfinished frames).
cp -r "$work/mpi2" "$work/resume"
rm -rf "$work/resume/train/room_seed1/0001" "$work/resume/train/bleed_seed2/0003" "$work/resume/test/cave_seed3/scene.json"
mkdir "$work/resume/train/room_seed1/0001.tmp-12345-0" "$work/resume/test/cave_seed3/0002.tmp-777-1"
run_mpi 3 --config "$work/config.json" --out "$work/resume" > "$work/resume.out" 2> "$work/resume.log" ||
  { cat "$work/resume.log" >&2; fail "the resumed run failed"; }
diff -r "$work/single" "$work/resume" > /dev/null || fail "the run resumed with K = 3 differs from one process"
grep -q "2 frames rendered by 3 ranks" "$work/resume.out" || fail "resume rendered: $(cat "$work/resume.out")"
echo "dataset_mpi: killed run (K = 2) resumed with K = 3: identical, 2 frames rendered, temporaries gone" >&2

# Different configs on the ranks: refused by every rank, nothing written.
set +e
mpirun -np 1 "$mpi" --config "$work/config.json" --out "$work/mixed" : -np 1 "$mpi" --config "$work/other.json" \
  --out "$work/mixed" > /dev/null 2> "$work/mixed.log"
rc=$?
set -e
[ "$rc" -ne 0 ] && grep -q "different configs" "$work/mixed.log" || fail "mixed configs: exit $rc, $(cat "$work/mixed.log")"
[ ! -e "$work/mixed" ] || fail "mixed configs: $work/mixed was created"
# A rerun of a finished dataset with another config: refused naming what differs, the dataset untouched.
set +e
run_mpi 2 --config "$work/other.json" --out "$work/mpi2" > /dev/null 2> "$work/other.log"
rc=$?
set -e
[ "$rc" -eq 1 ] && grep -q "dataset.json" "$work/other.log" || fail "other config: exit $rc, $(cat "$work/other.log")"
diff -r "$work/single" "$work/mpi2" > /dev/null || fail "the refused rerun changed the dataset"
echo "dataset_mpi: mixed configs and a changed config refused, nothing written" >&2
echo "dataset_mpi: all checks passed" >&2
