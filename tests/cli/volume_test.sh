#!/usr/bin/env bash
# End-to-end tests of `meltlab volume` (generate, render, info).
# Usage: volume_test.sh <meltlab binary> <case>
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh" "$@"
CONFIGS="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../experiments/configs/volume" && pwd)"

case "$CASE" in
  generate_and_info)
    run_ok "$M" volume generate --kind turbulence_sphere --size 24 --box 0,0,0,300,300,300 --out vol/cloud.json
    [ -s vol/cloud.raw ] || fail "raw file missing"
    [ "$(stat -c %s vol/cloud.raw)" -eq $((24 * 24 * 24 * 4)) ] || fail "raw size"
    run_ok "$M" volume generate --kind turbulence_sphere --size 24 --quantization uint8 --out vol/cloud8.vdb
    run_ok "$M" volume info vol/cloud.json
    py <<'PY'
import json
j = json.load(open('out.txt'))
assert j['dims'] == [24, 24, 24] and j['sample_type'] == 'float32', j
assert j['domain']['lo'] == [-150, -150, -150] and j['domain']['hi'] == [150, 150, 150], j['domain']
assert 0 == j['value_range'][0] < j['value_range'][1] <= 1, j['value_range']
h = json.load(open('vol/cloud.json'))
assert h['generator']['kind'] == 'turbulence_sphere' and h['generator']['octaves'] == 4, h['generator']
assert h['content_hash'] == j['content_hash']
PY
    run_ok "$M" volume info vol/cloud8.vdb
    json out.txt "d['dims']" | grep -q "2" || fail "vdb info"
    # The same generator twice gives the same samples (same hash); --overwrite is required.
    expect_exit 2 "$M" volume generate --kind turbulence_sphere --size 24 --box 0,0,0,300,300,300 --out vol/cloud.json
    expect_err "--overwrite"
    run_ok "$M" volume generate --kind turbulence_sphere --size 24 --box 0,0,0,300,300,300 --out vol/cloud.json --overwrite
    ;;
  render_every_model)
    # Every example scene renders (small, one frame) and records its vlr.* choices.
    for s in absorption_cloud emission_flame ea_fireball hg hg_attenuated; do
      run_ok "$M" volume render --scene "$CONFIGS/$s.yaml" --width 48 --height 48 --frames 1 --samples 32 --out "r_$s"
      for f in image.png image.exr render.json; do [ -s "r_$s/$f" ] || fail "r_$s/$f missing"; done
    done
    py <<'PY'
import json, struct
for s, model in [('absorption_cloud', 'absorption'), ('emission_flame', 'emission'), ('ea_fireball', 'emission_absorption'),
                 ('hg', 'hg'), ('hg_attenuated', 'hg_attenuated')]:
    j = json.load(open(f'r_{s}/render.json'))
    assert j['model'] == model, (s, j['model'])
    v = j['vlr']
    assert v['vlr.sampling.n'] == '32' and v['vlr.slab.swap'].startswith('per axis'), v
    assert v['vlr.errata.isotropic'] == 'isotropic phase = 1/(4 pi)'
    assert j['stats']['rays'] > 0 and j['stats']['samples'] > 0, j['stats']
    assert len(j['timing_ms']['frames']) == 1
    assert j['provenance']['meltlab']['version'], j['provenance']
    w, h = struct.unpack('>II', open(f'r_{s}/image.png', 'rb').read(24)[16:24])
    assert (w, h) == (48, 48), (s, w, h)
assert json.load(open('r_hg_attenuated/render.json'))['vlr']['vlr.shadow.method'] == 'cache'
PY
    ;;
  scene_from_file_and_composite)
    # A user's own volume (a .vdb) composited over a background image.
    run_ok "$M" volume generate --kind turbulence_box --size 16 --box 0,0,0,300,300,300 --out smoke.vdb
    python3 - <<'PY'
import struct, zlib
w, h = 40, 30
raw = b''.join(b'\x00' + bytes(v for x in range(w) for v in ((x * 6) % 256, (y * 8) % 256, 128)) for y in range(h))
def chunk(t, d): return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
open('bg.png', 'wb').write(b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, 8, 2, 0, 0, 0))
                         + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b''))
PY
    cat > scene.yaml <<'Y'
model: absorption
volume: {file: smoke.vdb}
camera: {type: pinhole, width: 40, height: 30, fov_deg: 50, eye: [400, -550, 300], target: [0, 0, 0], up: [0, 0, 1]}
optics: {kappa: 0.05}
output: {mode: composite, background_image: bg.png}
Y
    run_ok "$M" volume render --scene scene.yaml --out r
    py <<'PY'
import json
j = json.load(open('r/render.json'))
assert j['vlr']['vlr.output.mode'] == 'composite', j['vlr']
assert j['volume']['file'].endswith('smoke.vdb')
assert j['image']['background'].endswith('bg.png')
PY
    ;;
  bad_inputs)
    printf 'model: hg\nvolume: {generate: {kind: turbulence_box, size: 8}}\ncamera: {type: pinhole, width: 8, height: 8, fov_deg: 40, eye: [400, 0, 0], target: [0, 0, 0]}\noptics: {kappa: 0.01, hg_c: 1.5}\n' > bad_c.yaml
    expect_exit 2 "$M" volume render --scene bad_c.yaml --out r
    expect_err "bad_c.yaml:4"
    expect_err "hg_c"
    expect_one_line_err
    expect_no_dir r
    printf 'model: hg\nvolume: {generate: {kind: turbulence_box, size: 8}}\ncamera: {type: pinhole, width: 8, height: 8, fov_deg: 40, eye: [400, 0, 0], target: [0, 0, 0]}\nsmaples: {n: 3}\n' > typo.yaml
    expect_exit 2 "$M" volume render --scene typo.yaml --out r
    expect_err "unknown key 'smaples'"
    expect_one_line_err
    # The camera inside the box: refused by default (vlr.camera.inside: reject).
    printf 'model: absorption\nvolume: {generate: {kind: constant, size: 4}}\ncamera: {type: pinhole, width: 8, height: 8, fov_deg: 40, eye: [10, 0, 0], target: [100, 0, 0]}\n' > inside.yaml
    expect_exit 2 "$M" volume render --scene inside.yaml --out r
    expect_err "inside the volume's box"
    expect_one_line_err
    expect_no_dir r
    expect_exit 2 "$M" volume generate --kind smoke --out v.json
    expect_exit 2 "$M" volume generate --size 0 --out v.json
    expect_exit 2 "$M" volume generate --out v.png
    expect_err "NAME.json"
    expect_one_line_err
    expect_exit 2 "$M" volume info missing.json
    expect_err "missing.json"
    expect_one_line_err
    ;;
  *) fail "unknown case" ;;
esac
