#!/usr/bin/env bash
# End-to-end tests of `meltlab fog` (seed 002's spotlights in fog: render, bench).
# Usage: fog_test.sh <meltlab binary> <case>
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh" "$@"

case "$CASE" in
  render_every_scene)
    # Every procedural scene renders and records its fsa.* choices and the tables' domains.
    for s in sphere street lamp_spot lamp_point; do
      run_ok "$M" fog render --scene "$s" --kt 0.1 --width 64 --height 48 --table-n 32 --out "r_$s"
      for f in image.png image.exr render.json; do [ -s "r_$s/$f" ] || fail "r_$s/$f missing"; done
    done
    # The source's choices: F table, no warp, the listing's cone logic, specular args, no view attenuation.
    run_ok "$M" fog render --scene sphere --kt 0.04 --width 64 --height 48 --table-n 32 --table-function F \
      --u-warp none --v-warp none --v-interp index --cone-solver source --specular-args source --view-attenuation source_omit --out r_source
    run_ok "$M" fog render --scene sphere --kt 0 --width 64 --height 48 --table-n 32 --terms direct --out r_direct
    py <<'PY'
import json, struct
for s, name in [('sphere', 'S1_sphere'), ('street', 'S2_street'), ('lamp_spot', 'S3_lamp_spot'), ('lamp_point', 'S3_lamp_point')]:
    j = json.load(open(f'r_{s}/render.json'))
    assert j['scene'] == name, j['scene']
    m = j['model']
    for k in ('fsa.phase.normalisation', 'fsa.medium.albedo', 'fsa.medium.kt', 'fsa.cone.solver', 'fsa.h_min',
              'fsa.surface.view_attenuation', 'fsa.errata.specular_args', 'fsa.table.N', 'fsa.table.axis_warp',
              'fsa.table.v_warp', 'fsa.table.v_interp',
              'fsa.table.F.domain', 'fsa.table.G.domain', 'fsa.table.beyond_domain'):
        assert k in m, (s, k)
    assert m['fsa.table.N'] == 32 and m['fsa.medium.kt'] == 0.1, m
    assert (m['fsa.table.axis_warp'], m['fsa.table.v_warp'], m['fsa.table.v_interp']) == ('cbrt', 'sqrt_hi', 'value'), m
    assert any('nodes' in t for t in m['tables']), m['tables']
    assert j['lit_pixels'] > 0 and j['table_lookups']['total'] > 0, j
    assert j['provenance']['meltlab']['version'], j['provenance']
    w, h = struct.unpack('>II', open(f'r_{s}/image.png', 'rb').read(24)[16:24])
    assert (w, h) == (64, 48), (s, w, h)
assert json.load(open('r_street/render.json'))['lights'] == 4
m = json.load(open('r_source/render.json'))['model']
assert m['fsa.table.function'] == 'F' and m['fsa.table.axis_warp'] == 'none', m
assert m['fsa.table.v_warp'] == 'none' and m['fsa.table.v_interp'] == 'index', m
assert m['fsa.cone.solver'] == 'source' and m['fsa.errata.specular_args'] == 'source', m
assert m['fsa.surface.view_attenuation'] == 'source_omit', m
assert json.load(open('r_direct/render.json'))['terms'] == 'direct'
PY
    ;;
  ice_renderer_matches_fog_render)
    # S1 through the Embree ice renderer with a fog: section (experiments/configs/fog_sphere.yaml:
    # S1 scaled by 0.05 on the 5 cm benchmark_c sphere, the ice and ground shading nothing
    # themselves) against `fog render --scene sphere` (analytic geometry): the same model, so the
    # images differ only by the sphere's tessellation (32 000 triangles) and Embree's floats.
    # Measured: mean |difference| 3.1e-5 (the image's mean 0.055), max 0.003 at the highlight.
    CONFIGS="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../experiments/configs" && pwd)"
    run_ok "$M" render --mesh benchmark_c --keep-position --cycles 0 --every 1 --scene "$CONFIGS/fog_sphere.yaml" --out a
    run_ok "$M" fog render --scene sphere --kt 0.1 --width 160 --height 120 --out b
    oiiotool a/frames/frame_000000.exr b/image.exr --diff > diff.txt 2>&1  # exits 1 when any pixel differs
    py <<'PY'
import json, re
t = open('diff.txt').read()
mean = float(re.search(r"Mean error = (\S+)", t).group(1))
peak = float(re.search(r"Max error\s+= (\S+)", t).group(1))
# 10x the measured differences: a wrong term, factor or attenuation moves the mean by > 1e-3.
assert mean < 3e-4 and peak < 0.03, t
f = json.load(open('a/render.json'))['scene']['fog']
assert f['fsa.table.function'] == 'H' and f['fog.spotlights'] == '1', f
assert len(f['spotlights']) == 1 and f['spotlights'][0]['intensity'] == 0.025, f
PY
    ;;
  bench_model)
    # The quickest study end to end (the model error against R-surf-true) into a CSV, the record with the load.
    run_ok "$M" fog bench --study model --repeats 1 --out b
    [ -s b/model.csv ] && [ -s b/bench.json ] || fail "bench outputs missing"
    py <<'PY'
import csv, json
j = json.load(open('b/bench.json'))
assert j['studies'] == ['model'] and j['mode'] == 'quick', j
assert 'load_average_start' in j and j['provenance']['meltlab']['version']
rows = list(csv.DictReader(open('b/model.csv')))
assert len(rows) == 12, len(rows)  # quick: 3 cone angles x 4 optical depths
for r in rows:
    assert float(r['model']) > 0 and float(r['true']) > 0, r
    assert 0 < float(r['fog_share']) < 1, r
# The model's a = 0, b = inf assumption overestimates the light scattered towards P.
assert all(float(r['rel_error']) > -0.05 for r in rows), rows
PY
    ;;
  bad_inputs)
    expect_exit 2 "$M" fog render --scene sphere --kt -1 --out r
    expect_err "--kt"
    expect_one_line_err
    expect_no_dir r
    expect_exit 2 "$M" fog render --scene sphere --table-n 1 --out r
    expect_err "--table-n"
    expect_one_line_err
    expect_no_dir r
    expect_exit 2 "$M" fog render --scene sphere --width 0 --out r
    expect_one_line_err
    expect_no_dir r
    expect_exit 2 "$M" fog render --scene sphere --u-warp log --out r
    expect_err "--u-warp"
    expect_one_line_err
    expect_exit 2 "$M" fog render --scene sphere --v-warp log --out r
    expect_err "--v-warp"
    expect_one_line_err
    expect_no_dir r
    expect_exit 2 "$M" fog render --scene sphere --v-interp cubic --out r
    expect_err "--v-interp"
    expect_one_line_err
    expect_no_dir r
    expect_exit 2 "$M" fog render --scene sphere --terms some --out r
    expect_err "--terms"
    expect_one_line_err
    expect_exit 2 "$M" fog render --scene moon --out r
    expect_exit 2 "$M" fog bench --study everything --out b
    expect_err "unknown study"
    expect_one_line_err
    expect_no_dir b
    # An existing output folder needs --overwrite.
    run_ok "$M" fog render --scene sphere --width 16 --height 12 --table-n 8 --out r
    expect_exit 2 "$M" fog render --scene sphere --width 16 --height 12 --table-n 8 --out r
    expect_err "--overwrite"
    run_ok "$M" fog render --scene sphere --width 16 --height 12 --table-n 8 --out r --overwrite
    ;;
  *) fail "unknown case" ;;
esac
