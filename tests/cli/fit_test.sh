#!/usr/bin/env bash
# End-to-end tests of `meltlab fit` on inverse-crime sequences (made by the empirical model
# with known coefficients). Usage: fit_test.sh <meltlab binary> <case>
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh" "$@"

# The airplane mold melted with kg = 0.8, photographed every 40 cycles (16 photos, 640x480,
# noise, blur, JPEG) through a camera shifted by (5, -3) px and turned by 0.8 degrees.
# (With 20 cycles per photo the melt is too short: the segmentation's ~0.3 px bias then
# moves kg by about 1 %.)
synth() {
  run_ok "$M" synth-sequence --mesh airplane --kg 0.8 --photos 16 --cycles-per-photo 40 --width 640 --height 480 \
    --misalign 5,-3,0.8,1 --seed 3 --out seq "$@"
}

# A weighing experiment made by the empirical model: the icosphere melted with kg = 0.8
# (`meltlab simulate`, its volume every cycle), read as 250 g of ice on a scale every 10
# cycles at 6 s per cycle (one reading a minute), with 0.5 g of noise, in 0.1 g steps.
series() {
  run_ok "$M" simulate --mesh icosphere_3 --kg 0.8 --cycles 2000 --out sim
  mkdir -p w
  python3 - "$@" <<'PY' || fail "writing the series"
import csv, random, sys
rows = list(csv.DictReader(open('sim/stats.csv')))
v0 = float(rows[0]['volume'])
random.seed(5)
with open('w/mass.csv', 'w') as f:
    f.write('time_s,mass_g\n')
    for r in rows:
        c = int(r['cycle'])
        if c % 10:
            continue
        m = 250 * float(r['volume']) / v0 + (random.gauss(0, 0.5) if c else 0)
        f.write(f"{c * 6},{m:.1f}\n")
open('w/manifest.yaml', 'w').write('meltlab_observations: 1\nobject: icosphere\nmass_series: mass.csv\n')
PY
}

case "$CASE" in
  mass_only)
    # Issue 19: kg within 1 % with the time scale fixed, the time scale within 1 % with kg
    # fixed, and both together refused (a mass curve shows only kg / seconds_per_cycle).
    series
    run_ok "$M" fit --mesh icosphere_3 --observations w/manifest.yaml --seconds-per-cycle 6 --out f_kg
    cat err.txt
    [ -s f_kg/fit.json ] && [ -s f_kg/mass_curve.csv ] && [ -s f_kg/mass_curve.png ] || fail "outputs"
    [ ! -e f_kg/comparison ] || fail "a photo comparison without photos"
    run_ok "$M" fit --mesh icosphere_3 --observations w/manifest.yaml --fit seconds_per_cycle --kg 0.8 --out f_s
    cat err.txt
    py <<'PY'
import csv, json
j = json.load(open('f_kg/fit.json'))
kg = j['estimates']['kg']
assert abs(kg['value'] - 0.8) / 0.8 < 0.01, kg
assert j['estimates']['seconds_per_cycle'] == {**j['estimates']['seconds_per_cycle'], 'value': 6.0, 'fixed': True}
assert kg['standard_error'] and kg['standard_error_clustered'], kg
assert 'reg.tx_px' not in j['estimates'] and 'cycles_per_photo' not in j['estimates'], list(j['estimates'])
assert j['observations']['frames'] == 0 and j['observations']['series']['used'] == 106, j['observations']
assert j['initial_mass_g']['value'] == 250 and j['initial_mass_g']['density_kg_m3'] == 917, j['initial_mass_g']
c = j['series_comparison']
# The readings' noise: 0.5 g plus the 0.1 g steps (sigma 0.03 g); the fitted curve leaves it.
assert 0.35 < c['rmse_g'] < 0.7 and c['samples'] == 105, c
assert abs(c['time_to_melt_s']['fitted'] - c['time_to_melt_s']['observed']) < 60, c['time_to_melt_s']
assert j['uncertainty']['clusters'] > 10, j['uncertainty']
rows = list(csv.DictReader(open('f_kg/mass_curve.csv')))
assert len(rows) == 106 and all(r['used'] == '1' for r in rows), len(rows)
s = json.load(open('f_s/fit.json'))['estimates']['seconds_per_cycle']
assert abs(s['value'] - 6) / 6 < 0.01 and not s['fixed'], s
print('kg', kg['value'], '±', kg['standard_error'], 'seconds_per_cycle', s['value'], '±', s['standard_error'],
      'rmse', c['rmse_g'])
PY
    expect_exit 2 "$M" fit --mesh icosphere_3 --observations w/manifest.yaml --fit kg,seconds_per_cycle --out f_both
    expect_err "kg and seconds_per_cycle cannot both be fitted"; expect_err "--fix"; expect_one_line_err
    expect_no_dir f_both
    ;;
  series_bad_inputs)
    # Bad series are refused naming file:line, or (a spike) left out and listed; photo
    # options and parameters on a series alone are refused by name.
    series
    refuse() {  # refuse NAME CSV_TEXT EXPECTED_TEXT
      mkdir -p "b_$1"
      printf '%b' "$2" > "b_$1/s.csv"
      printf 'meltlab_observations: 1\nmass_series: s.csv\n' > "b_$1/m.yaml"
      expect_exit 2 "$M" fit --mesh icosphere_3 --observations "b_$1/m.yaml" --seconds-per-cycle 6 --out "o_$1"
      expect_err "$3"; expect_one_line_err; expect_no_dir "o_$1"
    }
    refuse nan 'time_s,mass_g\n0,250\n60,nan\n120,240\n' 's.csv:3'
    refuse backwards 'time_s,mass_g\n0,250\n60,245\n30,240\n' 's.csv:4: time_s 30 does not increase'
    refuse negative 'time_s,mass_g\n0,250\n60,200\n120,150\n180,-80\n240,50\n' 's.csv:5: -80 g is below zero'
    refuse rising 'time_s,mass_g\n0,250\n60,240\n120,230\n180,260\n240,262\n300,265\n' 's.csv:5: the mass rises'
    refuse one_row 'time_s,mass_g\n0,250\n' 'a melt series needs at least 3'
    refuse late_start 'time_s,mass_g\n60,250\n120,240\n180,230\n' '--mass-g'
    # A spike: left out, listed in fit.json and on stderr, and the fit is still right.
    python3 -c "
import csv
rows = open('w/mass.csv').read().splitlines()
t, m = rows[41].split(',')
rows[41] = f'{t},{float(m) + 30:.1f}'
open('w/spiked.csv', 'w').write('\n'.join(rows) + '\n')
open('w/spiked.yaml', 'w').write('meltlab_observations: 1\nmass_series: spiked.csv\n')
"
    run_ok "$M" fit --mesh icosphere_3 --observations w/spiked.yaml --seconds-per-cycle 6 --out f_spike
    expect_err "left out"; expect_err "spiked.csv:42"
    py <<'PY'
import json
j = json.load(open('f_spike/fit.json'))
left = j['observations']['series']['left_out']
assert len(left) == 1 and 'spiked.csv:42' in left[0], left
assert abs(j['estimates']['kg']['value'] - 0.8) / 0.8 < 0.01, j['estimates']['kg']
PY
    # Photo things on a series alone; the time scale missing.
    expect_exit 2 "$M" fit --mesh icosphere_3 --observations w/manifest.yaml --fit kg,reg --seconds-per-cycle 6 --out o1
    expect_err "reg needs photos"; expect_one_line_err; expect_no_dir o1
    expect_exit 2 "$M" fit --mesh icosphere_3 --observations w/manifest.yaml --seconds-per-cycle 6 --cycles-per-photo 7 --out o2
    expect_err "--cycles-per-photo"; expect_one_line_err; expect_no_dir o2
    expect_exit 2 "$M" fit --mesh icosphere_3 --observations w/manifest.yaml --out o3
    expect_err "needs the time scale"; expect_err "--seconds-per-cycle"; expect_one_line_err; expect_no_dir o3
    expect_exit 2 "$M" fit --mesh icosphere_3 --observations w/manifest.yaml --seconds-per-cycle -6 --out o4
    expect_err "--seconds-per-cycle"; expect_one_line_err; expect_no_dir o4
    ;;
  inverse_crime)
    synth
    run_ok "$M" fit --mesh airplane --observations seq/manifest.yaml --cycles-per-photo 40 --fit kg,reg --kg 0.5 --out fit
    cat err.txt
    [ -s fit/fit.json ] && [ -s fit/comparison/per_frame.csv ] && [ -s fit/comparison/p_curve.png ] || fail "outputs"
    py <<'PY'
import json
j = json.load(open('fit/fit.json'))
kg = j['estimates']['kg']
# Issue 5: kg within 1 % of the truth on photos rendered with noise.
assert abs(kg['value'] - 0.8) / 0.8 < 0.01, kg
assert kg['standard_error'] is not None and 0 < kg['standard_error'] < 0.01, kg
assert abs(j['truth']['kg_relative_error']) < 0.01, j['truth']
r = j['registration']
assert abs(r['angle_deg'] - 0.8) < 0.1, r
assert abs(r['tx_px'] - 5) < 0.5 and abs(r['ty_px'] + 3) < 0.5, r
assert abs(r['scale'] - 1) < 0.003, r
assert j['comparison']['P_max'] < 0.03, j['comparison']
assert len(j['kg_scan']) >= 5, j['kg_scan']
n = len(j['free'])
assert len(j['correlation']) == n and all(abs(j['correlation'][i][i] - 1) < 1e-9 for i in range(n))
print('kg', kg, 'time', j['time_s'], 'simulations', j['simulations'])
PY
    ;;
  small)
    # The whole fit path (synthesis, Ceres, registration, comparison, outputs) at a size the
    # sanitizer run can afford: 6 photos at 320x240. At this size the segmentation's bias
    # moves kg by a few per cent (report/fit_bench.py measures it), so the bound is loose.
    run_ok "$M" synth-sequence --mesh airplane --kg 0.8 --photos 6 --cycles-per-photo 40 --width 320 --height 240 \
      --misalign 2,-1,0.5,1 --seed 5 --out seq
    run_ok "$M" fit --mesh airplane --observations seq/manifest.yaml --cycles-per-photo 40 --fit kg,reg --kg 0.5 --out fit
    [ -s fit/fit.json ] && [ -s fit/comparison/per_frame.csv ] && [ -s fit/comparison/p_curve.png ] || fail "outputs"
    py <<'PY'
import json
j = json.load(open('fit/fit.json'))
kg = j['estimates']['kg']
assert abs(kg['value'] - 0.8) / 0.8 < 0.08, kg
assert kg['standard_error'] is not None and kg['standard_error'] > 0, kg
r = j['registration']
assert abs(r['tx_px'] - 2) < 1.5 and abs(r['ty_px'] + 1) < 1.5, r
print('kg', kg, 'time', j['time_s'], 'simulations', j['simulations'])
PY
    ;;
  holdout_and_time_scale)
    # Fit kg and the time scale on the first 60 % of the photos, predict the rest.
    synth
    run_ok "$M" fit --mesh airplane --observations seq/manifest.yaml --cycles-per-photo 32 \
      --fit kg,cycles_per_photo,reg --kg 0.6 --holdout 0.4 --out fit
    py <<'PY'
import json
j = json.load(open('fit/fit.json'))
e = j['estimates']
# kg and K are strongly correlated (a faster melt looks like more cycles per photo); the
# product kg*K (the melt per photo) is what the photos determine best.
assert abs(e['kg']['value'] * e['cycles_per_photo']['value'] - 32.0) / 32.0 < 0.02, e
assert j['P_held_out_frames']['frames'] == 7, j['P_held_out_frames']
assert j['P_held_out_frames']['P_max'] < 0.05, j['P_held_out_frames']
print(e['kg'], e['cycles_per_photo'], j['P_held_out_frames'])
PY
    ;;
  bad_frames_downweighted)
    # A photo of the wrong object (the ship) and a missing photo: reported, and the fit of
    # kg is still right.
    synth
    "$M" synth-sequence --mesh ship --photos 1 --width 640 --height 480 --seed 3 --out ship >/dev/null 2>&1 || fail "ship"
    cp ship/frames/frame_0001.jpg seq/frames/frame_0009.jpg
    rm seq/frames/frame_0004.jpg
    run_ok "$M" fit --mesh airplane --observations seq/manifest.yaml --cycles-per-photo 40 --fit kg,reg --kg 0.5 --out fit
    py <<'PY'
import json
j = json.load(open('fit/fit.json'))
assert any('frame 4' in s for s in j['frames_refused']), j['frames_refused']
assert abs(j['estimates']['kg']['value'] - 0.8) / 0.8 < 0.02, j['estimates']['kg']
rms = j['frame_rms_px']
worst = max(range(len(rms)), key=lambda i: rms[i])
assert rms[worst] > 5 * sorted(rms)[len(rms) // 2], rms   # the ship photo stands out
PY
    ;;
  kl_field)
    # A kl field parameter: the airplane melted with kg = 0.8 under a heat source of strength
    # 0.8 beside a wing tip (tests/assets/kl), 16 photos at 1600x1200. kg and the source's
    # strength are fitted together from kg = 0.5, strength = 0.4. The bias of both falls with
    # the photos' resolution (segmentation): kg/strength errors 5.5 %/9.6 % at 640x480,
    # 1.0 %/3.4 % at 1280x960, 0.87 %/2.2 % at 1600x1200 (where the truth's cost is within
    # noise of the optimum's).
    kl="$ASSETS/kl/airplane_wingtip_source.yaml"
    [ -f "$kl" ] || fail "missing $kl"
    run_ok "$M" synth-sequence --mesh airplane --kg 0.8 --kl "$kl" --photos 16 --cycles-per-photo 40 \
      --width 1600 --height 1200 --misalign 5,-3,0.8,1 --seed 3 --out seq
    sed 's/strength: 0.8/strength: 0.4/' "$kl" > start.yaml
    run_ok "$M" fit --mesh airplane --observations seq/manifest.yaml --cycles-per-photo 40 --kl start.yaml \
      --fit kg,kl.strength,reg --kg 0.5 --overlay-every 0 --out fit
    py <<'PY'
import json
j = json.load(open('fit/fit.json'))
e = j['estimates']
# Issue 5: kg within 1 %, field parameters within 5 %.
assert abs(e['kg']['value'] - 0.8) / 0.8 < 0.01, e['kg']
assert abs(e['kl.strength']['value'] - 0.8) / 0.8 < 0.05, e['kl.strength']
assert e['kl.strength']['standard_error'] is not None and e['kl.strength']['standard_error'] < 0.05, e['kl.strength']
assert j['free'][:2] == ['kg', 'kl.strength'], j['free']
print('kg', e['kg'], 'strength', e['kl.strength'], 'time', j['time_s'], 'simulations', j['simulations'])
PY
    ;;
  kn_shape)
    # The weight of the normal term, kN (Eq. 3.6), shapes the melt (flat sides creep at kN,
    # corners move at up to kE): a melt with kN = 4x the default (kE/25) is recovered with
    # kg from the default kN and kg 0.5.
    synth --kn 0.002
    run_ok "$M" fit --mesh airplane --observations seq/manifest.yaml --cycles-per-photo 40 --fit kg,kn,reg --kg 0.5 \
      --out fit
    py <<'PY'
import json
j = json.load(open('fit/fit.json'))
e = j['estimates']
# kg and kN trade off (correlation -0.86: a faster melt with a weaker normal term draws
# nearly the same outlines); at 640x480 the segmentation's ~0.3 px bias then moves them
# together (measured kg +3.4 %, kN -8.3 %, with a cost below the truth's). Tolerances: 5 %
# and 12 %; kN must have left its start (4x too small) for the truth.
assert abs(e['kg']['value'] - 0.8) / 0.8 < 0.05, e['kg']
assert abs(e['kn']['value'] - 0.002) / 0.002 < 0.12, e['kn']
assert e['kn']['initial'] == 0.0005, e['kn']
assert j['comparison']['P_max'] < 0.03, j['comparison']
print(e['kg'], e['kn'], j['comparison'])
PY
    ;;
  bad_inputs)
    synth
    expect_exit 2 "$M" fit --mesh airplane --observations seq/manifest.yaml --fit kg,bogus --out f1
    expect_err "bogus"; expect_one_line_err
    [ ! -e f1 ] || fail "f1 created"
    expect_exit 2 "$M" fit --mesh airplane --observations seq/manifest.yaml --fix kg=abc --out f2
    expect_err "--fix"; expect_one_line_err
    expect_exit 2 "$M" fit --mesh airplane --observations seq/manifest.yaml --fit kl.of.0.strength --out f3
    expect_err "--kl"; expect_one_line_err
    expect_exit 2 "$M" fit --mesh airplane --observations seq/manifest.yaml --fix kg=3 --out f4
    expect_err "kg"; expect_one_line_err
    printf 'time_s,volume_m3\n0,1e-4\n40,nan\n' > seq/volume.csv
    expect_exit 2 "$M" fit --mesh airplane --observations seq/manifest.yaml --volume-weight 10 --out f5
    expect_err "volume.csv:3"; expect_one_line_err
    for d in f1 f2 f3 f4 f5; do [ ! -e "$d/fit.json" ] || fail "$d/fit.json written for a refused fit"; done
    ;;
  *) fail "unknown case" ;;
esac
echo "ok [$CASE]"
