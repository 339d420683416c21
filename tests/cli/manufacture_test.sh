#!/usr/bin/env bash
# End-to-end tests of `meltlab manufacture` (physically based sequences).
# Usage: manufacture_test.sh <meltlab binary> <case>
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh" "$@"

# A coarse, short version of the default set: 6 photos 15 minutes apart, 4 mm voxels,
# 640x480 (at 320x240 the legs are ~8 px wide and morphology alone costs P ~ 0.05).
small() { run_ok "$M" manufacture --mesh giraffe --photos 6 --interval-s 900 --voxel-mm 4 --width 640 --height 480 "$@"; }

case "$CASE" in
  outputs_and_truth)
    small --out a
    for f in manifest.yaml mass.csv truth/truth.json truth/initial_mesh.ply truth/masks/frame_0001.png frames/frame_0006.jpg; do
      [ -s "a/$f" ] || fail "a/$f missing"
    done
    python3 - <<'PY' || fail "truth checks"
import csv, json
t = json.load(open('a/truth/truth.json'))
f = t['frames']
# About 250 g at the start (voxelisation error of a 4 mm grid: < 1 %).
assert abs(f[0]['mass_g'] - 250) < 2.5, f[0]
m = [x['mass_g'] for x in f]
assert all(b < a for a, b in zip(m, m[1:])), m
# Issue 4: the default segmentation of the first photo matches the true outline, P <= 0.05.
assert f[0]['segmentation_P'] <= 0.05, f[0]
e = t['energy']
assert abs(e['heat_in_J'] - e['latent_J'] - e['sensible_J']) <= 0.005 * e['heat_in_J'], e
rows = list(csv.DictReader(open('a/mass.csv')))
assert len(rows) == 6 and float(rows[0]['mass_g']) == round(f[0]['mass_g'], 6) or abs(float(rows[0]['mass_g']) - f[0]['mass_g']) < 1e-5
print([round(x['segmentation_P'], 4) for x in f], m)
PY
    ;;
  deterministic)
    small --out a
    small --out b
    for f in a/frames/*.jpg; do cmp -s "$f" "b/frames/$(basename "$f")" || fail "$f differs for one seed"; done
    cmp -s a/mass.csv b/mass.csv || fail "mass.csv differs"
    small --out c --seed 2
    ! cmp -s a/frames/frame_0001.jpg c/frames/frame_0001.jpg || fail "the seed changes nothing"
    ;;
  observations_load)
    # The manifest is a valid observation sequence: compare accepts it.
    small --out a
    run_ok "$M" simulate --mesh giraffe --cycles 40 --out run
    run_ok "$M" compare --sim run --observations a/manifest.yaml --cycles-per-photo 7 --out cmp
    [ -s cmp/per_frame.csv ] || fail "compare output"
    ;;
  bad_inputs)
    expect_exit 2 "$M" manufacture --mesh giraffe --photos 0 --out x
    expect_err "--photos"; expect_one_line_err
    expect_exit 2 "$M" manufacture --mesh giraffe --voxel-mm 0 --out x
    expect_err "--voxel-mm"; expect_one_line_err
    expect_exit 2 "$M" manufacture --mesh nosuchmesh --out x
    expect_one_line_err
    [ ! -e x ] || fail "x created for a refused run"
    ;;
  *) fail "unknown case" ;;
esac
echo "ok [$CASE]"
