#!/usr/bin/env bash
# End-to-end tests of `meltlab synth-sequence` and `meltlab compare`.
# Usage: compare_test.sh <meltlab binary> <case>
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh" "$@"

# A small sequence of the airplane mold (10.7k triangles): 12 photos, 20 cycles apart,
# 640x480 so the suite stays fast. The simulate run uses the same coefficients.
MESH=airplane
CYC=20
PHOTOS=12
synth() {  # synth DIR [extra args]
  local dir=$1; shift
  run_ok "$M" synth-sequence --mesh $MESH --photos $PHOTOS --cycles-per-photo $CYC --width 640 --height 480 \
    --seed "${SEED:-7}" --out "$dir" "$@"
}
simulate() {  # simulate DIR KG
  run_ok "$M" simulate --mesh $MESH --cycles $((CYC * (PHOTOS - 1))) --kg "$2" --out "$1"
}

case "$CASE" in
  inverse_crime)
    # Same model, same coefficients, a known camera shift: registration must undo the
    # shift and P must stay at the level of segmentation noise on every photo.
    synth seq --misalign 6,-4,1.5,1.0
    [ -f seq/manifest.yaml ] && [ -f seq/truth/truth.json ] && [ -f seq/frames/frame_0012.jpg ] || fail "sequence files"
    simulate run 1.0
    run_ok "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo $CYC --fixed-scale --out cmp
    for f in per_frame.csv p_curve.png compare.json overlays/frame_0001.png; do [ -s "cmp/$f" ] || fail "cmp/$f missing"; done
    py <<'PY'
import csv, json
rows = list(csv.DictReader(open('cmp/per_frame.csv')))
assert len(rows) == 12, len(rows)
assert all(r['status'] == 'ok' for r in rows), [r['status'] for r in rows]
P = [float(r['P']) for r in rows]
Pe = [float(r['P_exact']) for r in rows]
# Segmentation of a blurred, noisy JPEG moves the outline by well under a pixel; on a
# ~300 px wide object that is a P of about 0.01. 0.03 leaves room for the thin parts.
assert max(P) <= 0.03, P
assert max(Pe) <= 0.03, Pe
c = json.load(open('cmp/compare.json'))
r = c['registration']
# The photos were shifted by (6, -4) px and turned by 1.5 degrees about the image origin.
assert abs(r['angle_deg'] - 1.5) < 0.1, r
assert abs(r['tx_px'] - 6) < 0.5 and abs(r['ty_px'] + 4) < 0.5, r
assert c['summary']['frames_compared'] == 12
print('P', ['%.4f' % p for p in P])
PY
    ;;
  wrong_kg_grows)
    # The photos melt twice as fast as the simulation: P must grow along the sequence and
    # end well above the matched run's.
    synth seq --kg 1.0
    simulate run 0.5
    run_ok "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo $CYC --registration none --out cmp
    py <<'PY'
import csv
P = [float(r['P']) for r in csv.DictReader(open('cmp/per_frame.csv'))]
assert P[-1] > 3 * max(P[0], 0.005), P
assert P[-1] > 0.05, P
assert all(b >= a - 0.01 for a, b in zip(P, P[1:])), P
PY
    ;;
  seconds_mapping)
    # --seconds-per-cycle 2 with 40 s photos is 20 cycles per photo: identical results.
    synth seq
    simulate run 1.0
    run_ok "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo 20 --registration none --out a
    run_ok "$M" compare --sim run --observations seq/manifest.yaml --seconds-per-cycle 2 --registration none --out b
    cut -d, -f1-12 a/per_frame.csv > a.csv
    cut -d, -f1-12 b/per_frame.csv > b.csv
    cmp -s a.csv b.csv || fail "seconds-per-cycle mapping differs from cycles-per-photo"
    ;;
  bad_frames_skipped)
    # A missing, a truncated and an empty (all-black) photo are reported and skipped; the
    # others are compared as usual; frames beyond the run are 'beyond_run'.
    synth seq
    simulate run 1.0
    rm seq/frames/frame_0003.jpg
    head -c 2000 seq/frames/frame_0005.jpg > t && mv t seq/frames/frame_0005.jpg
    # the bare ground (the ice has gone): same scene, object far smaller than a pixel
    run_ok "$M" synth-sequence --mesh $MESH --photos 1 --width 640 --height 480 --fill 0.0001 --seed 7 --out tiny
    cp tiny/frames/frame_0001.jpg seq/frames/frame_0007.jpg
    run_ok "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo 25 --out cmp
    py <<'PY'
import csv
rows = {int(r['frame']): r for r in csv.DictReader(open('cmp/per_frame.csv'))}
assert rows[3]['status'] == 'missing', rows[3]
assert rows[5]['status'] == 'unreadable', rows[5]
assert rows[7]['status'] == 'empty_photo', rows[7]
# 25 cycles per photo: photo 10 (index 9) is cycle 225 > 220 cycles run
assert rows[10]['status'] == 'beyond_run', rows[10]
for k in (3, 5, 7, 10):
    assert rows[k]['P'] == '', rows[k]           # never counted as P = 0 or 1
assert rows[1]['status'] == 'ok' and rows[2]['status'] == 'ok'
PY
    grep -q "frame_0005.jpg" cmp/per_frame.csv || fail "per_frame.csv lacks the unreadable frame"
    ;;
  bad_inputs)
    synth seq
    simulate run 1.0
    expect_exit 2 "$M" compare --sim nowhere --observations seq/manifest.yaml --out c1
    expect_err "run.json"; expect_one_line_err
    [ ! -e c1 ] || fail "c1 created for a refused run"
    expect_exit 2 "$M" compare --sim run --observations seq/missing.yaml --out c2
    expect_err "missing.yaml"; expect_one_line_err
    sed 's/interval_s: 40/interval_s: -40/' seq/manifest.yaml > seq/neg.yaml
    expect_exit 2 "$M" compare --sim run --observations seq/neg.yaml --out c3
    expect_err "neg.yaml"; expect_err "interval_s"; expect_one_line_err
    sed 's/^object:/objekt:/' seq/manifest.yaml > seq/typo.yaml
    expect_exit 2 "$M" compare --sim run --observations seq/typo.yaml --out c4
    expect_err "typo.yaml:"; expect_err "objekt"; expect_one_line_err
    expect_exit 2 "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo -3 --out c5
    expect_err "--cycles-per-photo"; expect_one_line_err
    expect_exit 2 "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo 3 --seconds-per-cycle 2 --out c6
    run_ok "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo $CYC --out c7
    expect_exit 2 "$M" compare --sim run --observations seq/manifest.yaml --cycles-per-photo $CYC --out c7
    expect_err "compare.json"; expect_one_line_err
    expect_exit 2 "$M" synth-sequence --mesh $MESH --photos 0 --out s1
    expect_err "--photos"; expect_one_line_err
    [ ! -e s1 ] || fail "s1 created for a refused run"
    expect_exit 2 "$M" synth-sequence --mesh $MESH --misalign 1,2,x --out s2
    expect_err "--misalign"; expect_one_line_err
    for d in c7 seq; do [ -z "$(find $d -name '.*partial*')" ] || fail "temporary files left in $d"; done
    ;;
  deterministic)
    synth s1
    synth s2
    for f in s1/frames/*.jpg; do cmp -s "$f" "s2/frames/$(basename "$f")" || fail "$f differs between runs with one seed"; done
    SEED=8 synth s3
    ! cmp -s s1/frames/frame_0001.jpg s3/frames/frame_0001.jpg || fail "the seed changes nothing"
    ;;
  *) fail "unknown case" ;;
esac
echo "ok [$CASE]"
