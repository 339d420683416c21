#!/usr/bin/env bash
# End-to-end tests of `meltlab render` (frames of the ice material, the liquid figure).
# Usage: render_test.sh <meltlab binary> <case>
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh" "$@"

# benchmark_a: the 192-triangle stand-in of object A; small frames keep the suite fast.
MESH=benchmark_a

case "$CASE" in
  frames)
    # The documented example scene, at a small size.
    SCENE="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../experiments/configs" && pwd)/render_ice.yaml"
    run_ok "$M" render --mesh $MESH --scene "$SCENE" --cycles 6 --every 3 --width 64 --height 48 --mask-resolution 64 --out r
    for f in render.json frames.csv frames/frame_000000.png frames/frame_000000.exr frames/frame_000006.png; do
      [ -s "r/$f" ] || fail "r/$f missing"
    done
    py <<'PY'
import csv, json
rows = list(csv.DictReader(open('r/frames.csv')))
assert [int(r['cycle']) for r in rows] == [0, 3, 6], rows
assert rows[0]['bvh_update'] == 'rebuild', rows[0]
assert all(float(r['trace_ms']) > 0 for r in rows)
# The liquid grows from nothing once the object stands on the ground.
assert float(rows[0]['mask_sum']) == 0 and float(rows[-1]['mask_sum']) > 0, rows
j = json.load(open('r/render.json'))
assert j['frames'] == 3 and j['cycles']['run'] == 6, j['cycles']
assert j['scene']['ice']['fresnel'] == 'full' and j['liquid']['p_threshold'] == 0.5
assert j['camera']['type'] == 'pinhole'
PY
    # The PNG is an image of the requested size.
    python3 -c "
import struct; b=open('r/frames/frame_000000.png','rb').read(24)
w,h=struct.unpack('>II', b[16:24]); assert (w,h)==(64,48), (w,h)" || fail "PNG size"
    ;;
  sublimation_skips)
    # No liquid stage and no transmission: both are logged as skipped in render.json.
    cat > scene.yaml <<'Y'
width: 48
height: 32
ice: {ct: 0}
outputs: {exr: false}
Y
    run_ok "$M" render --mesh $MESH --scene scene.yaml --cycles 2 --every 2 --no-liquid --up y --out r
    [ -s r/frames/frame_000002.png ] || fail "frame missing"
    [ ! -e r/frames/frame_000002.exr ] || fail "exr written although outputs.exr is false"
    py <<'PY'
import json
j = json.load(open('r/render.json'))
s = ' | '.join(j['skipped'])
assert 'ice refraction and dispersion (ct = 0)' in s, s
assert 'liquid (no mask' in s, s
assert j['liquid'] == 'off (no liquid stage)'
assert j['mesh_up_axis'] == 'y' and j['mesh_lift_z'] != 0
PY
    ;;
  liquid_figure)
    run_ok "$M" render --mesh $MESH --liquid-figure --figure-cycles 5,20,40 --mask-resolution 64 --out fig
    for c in 000005 000020 000040; do [ -s "fig/liquid/mask_$c.png" ] || fail "mask $c missing"; done
    py <<'PY'
import csv
rows = list(csv.DictReader(open('fig/liquid/mask_sums.csv')))
assert [int(r['cycle']) for r in rows] == [5, 20, 40], rows
s = [float(r['mask_sum']) for r in rows]
assert all(x > 0 for x in s), s
assert int(rows[-1]['wet_texels']) > 0
PY
    # Fig. 7.7: the relief threshold texture (p in [p/2, 3p/2]) gives a different puddle;
    # the additive deposit holds more liquid than overwriting.
    run_ok "$M" render --mesh $MESH --liquid-figure --figure-cycles 40 --mask-resolution 64 --threshold-texture --out tex
    run_ok "$M" render --mesh $MESH --liquid-figure --figure-cycles 40 --mask-resolution 64 --deposit-blend add --out add
    py <<'PY'
import csv, json
last = lambda d: list(csv.DictReader(open(d + '/liquid/mask_sums.csv')))[-1]
base, tex, add = last('fig'), last('tex'), last('add')
assert tex['mask_sum'] == base['mask_sum'], (tex, base)       # the same liquid ...
assert tex['wet_texels'] != base['wet_texels'], (tex, base)   # ... wet in other places
assert float(add['mask_sum']) > float(base['mask_sum']), (add, base)
j = json.load(open('tex/render.json'))
assert j['liquid']['threshold_texture'].startswith('relief'), j['liquid']
assert json.load(open('add/render.json'))['liquid']['deposit_blend'] == 'add'
PY
    ;;
  bad_inputs)
    expect_exit 2 "$M" render --mesh nope.off --out r
    expect_one_line_err
    expect_no_dir r
    expect_exit 2 "$M" render --mesh $MESH --every 0 --out r
    expect_err "--every"
    expect_one_line_err
    printf 'ice: {cx: 1}\n' > bad.yaml
    expect_exit 2 "$M" render --mesh $MESH --scene bad.yaml --out r
    expect_err "unknown key 'cx'"
    expect_one_line_err
    expect_no_dir r
    printf 'ice: [1, 2\n' > broken.yaml
    expect_exit 2 "$M" render --mesh $MESH --scene broken.yaml --out r
    expect_one_line_err
    expect_exit 2 "$M" render --mesh $MESH --scene missing.yaml --out r
    expect_err "missing.yaml"
    expect_exit 2 "$M" render --mesh $MESH --liquid-figure --no-liquid --out r
    expect_one_line_err
    expect_exit 2 "$M" render --mesh $MESH --up w --out r
    expect_exit 2 "$M" render --mesh $MESH --threshold 0 --out r
    expect_err "--threshold"
    expect_no_dir r
    ;;
  *) fail "unknown case" ;;
esac
