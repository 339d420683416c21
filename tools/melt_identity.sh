#!/usr/bin/env bash
# Melts the same matrix of cases with two builds of meltlab and compares the run folders
# bitwise: the check that a change to the melt cycle (layout, scheduling, parallel code)
# leaves every melt identical. Snapshots are written as OBJ with 17 significant digits (the
# binary PLY stores float coordinates, which would hide differences in double runs);
# stats.csv is compared without its timing columns (tools/compare_trees.py).
#
#   tools/melt_identity.sh OLD_MELTLAB NEW_MELTLAB OUT_DIR
#
# The matrix: every deform mode x precision x kl field (none, experiments/configs/
# kl_source_and_ground.yaml) x thread count (1, 2) on the giraffe mold; the dumbbell (splits
# into two parts: repair, remnant check, compaction) with the open choices switched; the
# 75k-triangle bunny (many collapses, Morton order) and object C (UV sphere, file order) in
# both precisions and thread counts. OUT_DIR/old is reused if present (the reference build
# does not change between checks). Exit 0 when every file is identical.
set -euo pipefail
old=$(realpath "$1")
new=$(realpath "$2")
out=$3
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
kl="$here/experiments/configs/kl_source_and_ground.yaml"
cases=()
for prec in float double; do
  for threads in 1 2; do
    for deform in combined normal edge; do
      cases+=("giraffe-$deform-$prec-t$threads|--mesh giraffe --cycles 400 --deform $deform --precision $prec --threads $threads")
      cases+=("giraffe-$deform-$prec-t$threads-kl|--mesh giraffe --cycles 400 --deform $deform --precision $prec --threads $threads --kl $kl")
    done
    cases+=("dumbbell-$prec-t$threads|--mesh dumbbell --cycles 1500 --precision $prec --threads $threads")
    cases+=("dumbbell-$prec-t$threads-choices|--mesh dumbbell --cycles 1500 --precision $prec --threads $threads --merge pairwise --tie strict --edge-sum sum --kl $kl")
    cases+=("dumbbell-$prec-t$threads-norepair|--mesh dumbbell --cycles 600 --precision $prec --threads $threads --no-repair --order file")
    cases+=("bunny-$prec-t$threads|--mesh bunny00 --cycles 300 --precision $prec --threads $threads")
    cases+=("objc-$prec-t$threads|--mesh benchmark_c --cycles 600 --precision $prec --threads $threads --order file")
  done
done
run_all() {  # binary, folder
  local bin=$1 dir=$2
  mkdir -p "$dir"
  for c in "${cases[@]}"; do
    local name=${c%%|*} args=${c#*|}
    [ -f "$dir/$name/run.json" ] && continue
    # shellcheck disable=SC2086
    "$bin" simulate $args --snapshot-every 100 --snapshot-format obj --stats-every 5 --out "$dir/$name" >/dev/null ||
      echo "$name: exit status $? with $bin"
  done
}
run_all "$old" "$out/old"
rm -rf "$out/new"
run_all "$new" "$out/new"
echo "${#cases[@]} cases"
python3 "$here/tools/compare_trees.py" "$out/old" "$out/new"
