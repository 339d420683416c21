#!/usr/bin/env bash
# End-to-end tests of the meltlab program. Usage: cli_test.sh <meltlab binary> <case>
# Each case exits non-zero with a message on the first failed expectation.
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh" "$@"

tetra_off='OFF
4 4 0
-1 0 1
0 0 -1
1 0 1
0 1 0
3 3 1 0
3 3 2 1
3 3 0 2
3 1 2 0'

case "$CASE" in
  help)
    expect_exit 0 "$M" --help
    grep -q simulate out.txt || fail "help lacks simulate"
    expect_exit 0 "$M" simulate --help
    grep -q -- "--kr" out.txt || fail "simulate help lacks --kr"
    expect_exit 0 "$M" --version
    grep -q "meltlab" out.txt || fail "version output"
    expect_exit 2 "$M"
    expect_exit 2 "$M" frobnicate
    ;;
  simulate_outputs)
    expect_exit 0 "$M" simulate --mesh dumbbell --cycles 120 --snapshot-every 50 --out run
    [ -f run/stats.csv ] && [ -f run/run.json ] || fail "outputs missing"
    rows=$(($(wc -l < run/stats.csv) - 1))
    [ "$rows" -eq 121 ] || fail "stats.csv has $rows rows, want 121 (cycles 0..120)"
    head -1 run/stats.csv | grep -q "^cycle,vertices,triangles,components,euler,genus,volume,area,Qs,Qd,Qq,max_d,ms" || fail "header"
    [ "$(json run/run.json "d['status']")" = completed ] || fail "status"
    [ "$(json run/run.json "d['cycles_run']")" = 120 ] || fail "cycles_run"
    for s in $(json run/run.json "' '.join(d['outputs']['snapshots'])"); do [ -s "run/$s" ] || fail "snapshot $s"; done
    [ "$(json run/run.json "len(d['outputs']['snapshots'])")" = 4 ] || fail "snapshots 0,50,100,120"
    # the statistics' own time is recorded, one entry per row
    [ "$(json run/run.json "d['timing']['stats_rows']")" = 121 ] || fail "timing.stats_rows"
    [ "$(json run/run.json "int(d['timing']['stats_row_ms_median'] > 0 and d['timing']['stats_ms_total'] >= d['timing']['stats_row_ms_median'])")" = 1 ] || fail "timing.stats_row_ms"
    grep -q "ms per statistics row" err.txt || fail "the last line lacks the statistics row time"
    # a row every 10th cycle: 13 rows (0, 10, ..., 120), and no hint to thin them
    expect_exit 0 "$M" simulate --mesh dumbbell --cycles 120 --stats-every 10 --out run10
    [ "$(json run10/run.json "d['timing']['stats_rows']")" = 13 ] || fail "--stats-every 10: timing.stats_rows"
    [ "$(($(wc -l < run10/stats.csv) - 1))" -eq 13 ] || fail "--stats-every 10: stats.csv rows"
    ! grep -q "stats-every K" err.txt || fail "hint to thin the rows although they are thinned"
    [ -z "$(find run -name '.*partial*')" ] || fail "temporary files left"
    # volume never grows along the run
    python3 - <<'PY' || fail "volume grew"
import csv
v=[float(r['volume']) for r in csv.DictReader(open('run/stats.csv'))]
assert all(b <= a for a, b in zip(v, v[1:])), v
PY
    ;;
  simulate_orders)
    # Each numbering melts to its own valid closed solid, recorded in run.json; a bad one is refused.
    for order in morton bfs file; do
      expect_exit 0 "$M" simulate --mesh dumbbell --cycles 60 --order "$order" --out "run_$order"
      [ "$(json "run_$order/run.json" "d['mesh']['order']")" = "$order" ] || fail "$order: mesh.order"
      [ "$(json "run_$order/run.json" "d['options']['order']")" = "$order" ] || fail "$order: options.order"
      tail -1 "run_$order/stats.csv" | awk -F, '{ exit !($5 == 0) }' || fail "$order: Euler characteristic of the last row is not 0"
    done
    # The same input: the counts of cycle 0 agree (the sums of volume and area may round differently).
    [ "$(sed -n 2p run_bfs/stats.csv | cut -d, -f2-6)" = "$(sed -n 2p run_morton/stats.csv | cut -d, -f2-6)" ] || fail "cycle 0 differs"
    expect_exit 2 "$M" simulate --mesh dumbbell --order sideways --out run; expect_err "--order"; expect_no_dir run
    ;;
  melts_away)
    expect_exit 0 "$M" simulate --mesh benchmark_a --cycles 5000 --out run
    [ "$(json run/run.json "d['status']")" = melted ] || fail "status should be melted"
    [ "$(json run/run.json "d['final']['triangles']")" = 0 ] || fail "triangles left"
    ;;
  missing_mesh)
    expect_exit 2 "$M" simulate --mesh nope.off --out run
    expect_err "nope.off: no such file"; expect_one_line_err; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh no_such_dataset --out run
    expect_err "no_such_dataset"; expect_one_line_err; expect_no_dir run
    ;;
  corrupt_mesh)
    printf 'OFF\n4 4 0\n-1 0 1\n0 0 -1\n' > trunc.off
    expect_exit 2 "$M" simulate --mesh trunc.off --out run
    expect_err "trunc.off"; expect_one_line_err; expect_no_dir run
    printf '%s\n' "$tetra_off" | head -n 9 > trunc2.off  # header says 4 faces, 3 present
    expect_exit 2 "$M" simulate --mesh trunc2.off --out run
    expect_err "trunc2.off: truncated OFF: header declares 4 faces, the file holds 3"; expect_no_dir run
    printf '%s\n' "$tetra_off" | sed 's/^1 0 1$/1 nan 1/' > nan.off
    expect_exit 2 "$M" simulate --mesh nan.off --out run
    expect_err "nan.off:line"; expect_err "not a finite number"; expect_one_line_err; expect_no_dir run
    : > empty.ply
    expect_exit 2 "$M" simulate --mesh empty.ply --out run
    expect_err "empty.ply: file is empty"; expect_no_dir run
    head -c 300 /dev/urandom > noise.stl
    expect_exit 2 "$M" simulate --mesh noise.stl --out run
    expect_err "noise.stl"; expect_one_line_err; expect_no_dir run
    ;;
  invalid_topology)
    printf '%s\n' "$tetra_off" | head -n 9 | sed 's/^4 4 0$/4 3 0/' > open.off
    expect_exit 2 "$M" simulate --mesh open.off --out run
    expect_err "open.off: open mesh: boundary edge"; expect_err "--repair"; expect_one_line_err; expect_no_dir run
    expect_exit 0 "$M" simulate --mesh open.off --repair --cycles 3 --out run
    [ "$(json run/run.json "d['mesh']['repairs'][0]")" = "filled 1 hole with 1 triangle" ] || fail "repair not recorded"
    # inside-out tetrahedron
    printf '%s\n' "$tetra_off" | sed 's/^3 \([0-9]\) \([0-9]\) \([0-9]\)$/3 \1 \3 \2/' > inv.off
    expect_exit 2 "$M" simulate --mesh inv.off --out run2
    expect_err "inside-out"; expect_no_dir run2
    ;;
  bad_numbers)
    expect_exit 2 "$M" simulate --mesh dumbbell --kg 1.5 --out run; expect_err "--kg"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --kg nan --out run; expect_err "--kg"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --kr -1 --out run; expect_err "--kr"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --ke abc --out run; expect_err "--ke"; expect_no_dir run
    # The simulator's parameter names come back as the options' names (kE: --ke, compact_after: --compact-after).
    expect_exit 2 "$M" simulate --mesh dumbbell --ke nan --out run; expect_err "--ke: must"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --compact-after -1 --out run; expect_err "--compact-after: must"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --compact-below 2 --out run; expect_err "--compact-below: must"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --cycles -5 --out run; expect_err "--cycles"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --precision half --out run; expect_err "--precision"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --deform sideways --out run; expect_err "--deform"; expect_no_dir run
    ;;
  bad_yaml)
    printf 'kl: {type: point_source, position: [0, 0], radius: 1}\n' > a.yaml
    expect_exit 2 "$M" simulate --mesh dumbbell --kl a.yaml --out run; expect_err "a.yaml:1"; expect_one_line_err; expect_no_dir run
    printf 'kl: [1, 2\n' > b.yaml
    expect_exit 2 "$M" simulate --mesh dumbbell --kl b.yaml --out run; expect_err "b.yaml:2: YAML syntax error"; expect_no_dir run
    printf 'kl: {type: constant, value: 0.5, extra: 1}\n' > c.yaml
    expect_exit 2 "$M" simulate --mesh dumbbell --kl c.yaml --out run; expect_err "unknown key 'extra'"; expect_no_dir run
    expect_exit 2 "$M" simulate --mesh dumbbell --kl missing.yaml --out run; expect_err "missing.yaml: no such file"; expect_no_dir run
    ;;
  kl_field)
    printf 'kl:\n  type: product\n  of:\n    - {type: point_source, position: [0.05, 0, 0], base: 0.2, strength: 0.8, radius: 0.02}\n    - {type: ground, up: [0, 0, 1], height: auto, base: 0.5, strength: 0.5, height_scale: 0.01}\n' > kl.yaml
    expect_exit 0 "$M" simulate --mesh dumbbell --kl kl.yaml --cycles 20 --out run
    [ "$(json run/run.json "d['parameters']['kl']['type']")" = product ] || fail "kl not recorded"
    [ "$(json run/run.json "d['parameters']['kl']['of'][1]['height'] < 0")" = True ] || fail "auto ground height not resolved"
    ;;
  existing_run)
    expect_exit 0 "$M" simulate --mesh benchmark_a --cycles 2 --out run
    expect_exit 2 "$M" simulate --mesh benchmark_a --cycles 2 --out run; expect_err "already holds a run"
    expect_exit 0 "$M" simulate --mesh benchmark_a --cycles 3 --out run --overwrite
    [ "$(json run/run.json "d['cycles_run']")" = 3 ] || fail "overwrite"
    ;;
  serial_equals_parallel)
    for t in 1 2; do
      expect_exit 0 "$M" simulate --mesh giraffe --cycles 150 --snapshot-every 50 --threads $t --out run$t
    done
    for s in 000050 000100 000150; do cmp -s run1/snapshots/cycle_$s.ply run2/snapshots/cycle_$s.ply || fail "snapshot $s differs"; done
    cut -d, -f1-12 run1/stats.csv > a.csv; cut -d, -f1-12 run2/stats.csv > b.csv
    cmp -s a.csv b.csv || fail "stats differ"
    [ "$(json run2/run.json "d['execution']")" = parallel ] || fail "threads 2 should run in parallel"
    ;;
  float_precision)
    expect_exit 0 "$M" simulate --mesh dumbbell --precision float --cycles 50 --out run
    [ "$(json run/run.json "d['precision']")" = float ] || fail "precision"
    ;;
  interrupt)
    "$M" simulate --mesh benchmark_c --cycles 1000000 --keep-going --out run >out.txt 2>err.txt &
    pid=$!
    # The run is staged in .run.partial-PID until it ends (then renamed to run): wait for the
    # staging folder, not for run, so that the signal arrives while the melt is running (the
    # whole run takes about 9 s on a quiet machine).
    for _ in $(seq 100); do compgen -G '.run.partial-*' >/dev/null && break; sleep 0.1; done
    sleep 1
    kill -INT $pid
    wait $pid; code=$?
    [ "$code" -eq 130 ] || fail "exit $code after SIGINT, want 130"
    [ "$(json run/run.json "d['status']")" = interrupted ] || fail "status"
    n=$(json run/run.json "d['cycles_run']")
    rows=$(($(wc -l < run/stats.csv) - 1))
    [ "$rows" -eq $((n + 1)) ] || fail "stats.csv has $rows rows for $n cycles"
    [ -z "$(find run -name '.*partial*')" ] || fail "temporary files left"
    ;;
  mesh_info)
    printf '%s\n' "$tetra_off" > tet.off
    expect_exit 0 "$M" mesh-info tet.off --self-intersections
    python3 - <<'PY' || fail "mesh-info JSON"
import json
d = json.load(open('out.txt'))
assert d['valid'] and d['triangles']['V'] == 4 and d['triangles']['E'] == 6 and d['triangles']['chi'] == 0
assert d['self_intersections']['intersects'] is False
assert abs(d['quality']['volume'] - 2/3) < 1e-12, d['quality']['volume']  # base area 2, height 1
PY
    printf 'OFF\n8 6 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 0 1\n1 0 1\n0 1 1\n1 1 1\n4 0 2 3 1\n4 4 5 7 6\n4 0 1 5 4\n4 2 6 7 3\n4 0 4 6 2\n4 1 3 7 5\n' > quads.off
    expect_exit 0 "$M" mesh-info quads.off
    [ "$(json out.txt "(d['polygons']['V'], d['polygons']['E'], d['polygons']['F'], d['polygons']['chi'])")" = "(8, 12, 6, 0)" ] || fail "Tab. 2.3 cube of quads"
    [ "$(json out.txt "(d['triangles']['E'], d['triangles']['F'])")" = "(18, 12)" ] || fail "Tab. 2.3 cube of triangles"
    printf '%s\n' "$tetra_off" | head -n 9 | sed 's/^4 4 0$/4 3 0/' > open.off
    expect_exit 1 "$M" mesh-info open.off
    [ "$(json out.txt "d['valid']")" = False ] || fail "open mesh reported valid"
    expect_exit 2 "$M" mesh-info nope.obj; expect_err "nope.obj"
    ;;
  dataset)
    expect_exit 0 "$M" dataset list
    grep -q "^bunny00 " out.txt || fail "bunny00 not listed"
    grep -q "^giraffe " out.txt || fail "giraffe not listed"
    expect_exit 0 "$M" dataset get benchmark_a
    [ -s "$(cat out.txt)" ] || fail "dataset get did not produce a file"
    expect_exit 2 "$M" dataset get no_such_thing; expect_err "no_such_thing"
    # Tab. 2.3 in polygon form: the tunnel cube (two faces with a hole each) has genus 1.
    expect_exit 0 "$M" dataset euler
    py <<'PY'
import json
j = json.load(open('out.txt'))
assert len(j) == 6, j.keys()
t = j['cube_with_tunnel']
assert (t['V'], t['E'], t['F'], t['H'], t['S'], t['G'], t['chi']) == (16, 24, 10, 2, 1, 1, 0), t
f = j['cube_with_face_hole']
assert (f['V'], f['E'], f['F'], f['H'], f['G']) == (16, 24, 11, 1, 0), f
PY
    expect_exit 2 "$M" dataset euler cube_with_nothing; expect_err "cube_with_nothing"; expect_one_line_err
    ;;
  *) fail "unknown case" ;;
esac
echo "ok [$CASE]"
