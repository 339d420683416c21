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
  slicing_render)
    # Seed 003: method: slicing in every mode (the example scene, small), the gradient cache reused
    # on the second run, the vsi.* record, the combined mode flagged as the spec's interpretation.
    export MELTLAB_DATA_DIR="$PWD/data"
    for mode in blend mip combined; do
      sed -e "s/mode: combined /mode: $mode /" -e 's/dims: \[256, 256, 68\]/dims: [48, 48, 20]/' \
        "$CONFIGS/slicing_skull.yaml" > "s_$mode.yaml"
      run_ok "$M" volume render --scene "s_$mode.yaml" --width 80 --height 60 --frames 1 --out "r_$mode"
      for f in image.png image.exr render.json; do [ -s "r_$mode/$f" ] || fail "r_$mode/$f missing"; done
    done
    run_ok "$M" volume render --scene s_mip.yaml --width 80 --height 60 --frames 1 --out r_mip2
    cmp -s r_mip/image.png r_mip2/image.png || fail "the cached gradients gave another image"
    py <<'PY'
import json, struct
for mode in ['blend', 'mip', 'combined']:
    j = json.load(open(f'r_{mode}/render.json'))
    v = j['vsi']
    assert j['method'] == 'slicing' and v['vsi.mode'] == mode, v
    assert v['vsi.cpu.realisation'] == 'per-pixel ray-plane sampling' and v['vsi.mask.resolution'] == '100 x 100 x 100'
    assert v['vsi.combined.rule'].startswith('OUR INTERPRETATION'), v['vsi.combined.rule']
    assert j['stats']['samples'] > j['stats']['samples_past_mask'] > 0, j['stats']
    assert ('gradients' in j) == (mode != 'blend'), mode
    w, h = struct.unpack('>II', open(f'r_{mode}/image.png', 'rb').read(24)[16:24])
    assert (w, h) == (80, 60), (mode, w, h)
assert json.load(open('r_mip/render.json'))['gradients']['from_cache'] is False
assert json.load(open('r_mip2/render.json'))['gradients']['from_cache'] is True
PY
    ls data/slicing-gradients/*.grad >/dev/null || fail "no gradient cache file"
    # A .vlb's `normalise` reaches the image: a header range (0..4000) wider than the data (a ramp
    # 1000..3000) maps the data to [0.25, 0.75], which the renderer keeps (it must not stretch it back
    # to [0, 1] by its own scanned extrema); scanned and the equivalent value_range agree bit for bit.
    py <<'PY'
import struct
nx, ny, nz = 12, 10, 8
vals = [1000 + (2000 * i) // (nx - 1) for k in range(nz) for j in range(ny) for i in range(nx)]
hdr = f"VLB.1\n{nx} {ny} {nz}\nuint16\nlittle\n1 1 1\n0 4000\n0 1\n"
open('wide.vlb', 'wb').write(hdr.encode() + struct.pack(f'<{len(vals)}H', *vals))
PY
    for n in header scanned; do
      printf 'method: slicing\nvolume: {file: wide.vlb, normalise: %s}\ncamera: {type: pinhole, width: 24, height: 20, fov_deg: 30, eye: [40, -30, 30], target: [6, 5, 4]}\nslicing:\n  transfer_functions: [{r: [[0, 1]], g: [[0, 1]], b: [[0, 1]], a: [[0, 0], [1, 1]]}]\n' "$n" > "w_$n.yaml"
      run_ok "$M" volume render --scene "w_$n.yaml" --frames 1 --out "rw_$n"
    done
    sed -e 's/normalise: header/normalise: scanned/' -e '$a\  value_range: [0, 1]' w_header.yaml > w_given.yaml
    run_ok "$M" volume render --scene w_given.yaml --frames 1 --out rw_given
    cmp -s rw_header/image.png rw_scanned/image.png && fail "normalise: header rendered as scanned"
    cmp -s rw_scanned/image.png rw_given/image.png || fail "scanned and value_range [0, 1] differ"
    py <<'PY'
import json
v = {n: json.load(open(f'rw_{n}/render.json'))['vsi'] for n in ('header', 'scanned', 'given')}
assert v['header']['vsi.data.norm_source'].startswith('header (at load') and v['header']['vsi.data.norm_range'] == [0, 4000], v['header']
assert v['scanned']['vsi.data.norm_range'] == [1000, 3000] and v['header']['vsi.data.scanned_range'] == [1000, 3000]
assert v['given']['vsi.data.norm_source'] == 'given [0, 1]', v['given']
PY
    # A bad key inside the slicing section: file:line, nothing written.
    printf 'method: slicing\nvolume: {generate: {kind: constant, size: 4}}\ncamera: {type: pinhole, width: 8, height: 8, fov_deg: 30, eye: [400, 0, 0], target: [0, 0, 0]}\nslicing:\n  quality_class: 0\n  transfer_functions: [{a: [[0, 1]]}]\n' > bad_s.yaml
    expect_exit 2 "$M" volume render --scene bad_s.yaml --out rb
    expect_err "bad_s.yaml:5"
    expect_one_line_err
    expect_no_dir rb
    ;;
  seed001_generate_and_info)
    # Seed 001's shapes volume in both orders: the file sizes of the spec's arithmetic (§2.1),
    # the header read back, the generator's statistics, the naive writer's bytes.
    run_ok "$M" volume generate --kind shapes --size 40 --shapes 12 --object-size 9 --out lin.clv
    [ "$(stat -c %s lin.clv)" -eq $((26 + 40 * 40 * 40)) ] || fail "linear size $(stat -c %s lin.clv)"
    grep -q "100 %" err.txt || fail "no progress lines: $(cat err.txt)"
    cp out.txt gen.json
    # n_b = ceil(39 / 7) = 6 blocks of 8^3 per axis.
    run_ok "$M" volume generate --kind shapes --size 40 --shapes 12 --object-size 9 --layout blocked --block-side 8 \
      --quiet --out blk.clv
    [ "$(stat -c %s blk.clv)" -eq $((26 + 6 * 6 * 6 * 512)) ] || fail "blocked size $(stat -c %s blk.clv)"
    [ ! -s err.txt ] || fail "--quiet printed: $(cat err.txt)"
    run_ok "$M" volume generate --kind shapes --size 40 --shapes 12 --object-size 9 --batch 1 --quiet --out naive.clv
    cmp -s lin.clv naive.clv || fail "the naive writer wrote other bytes than the batched one"
    run_ok "$M" volume info blk.clv
    py <<'PY'
import json
g = json.load(open('gen.json'))
assert g['dims'] == [40, 40, 40] and g['order'] == 'linear' and g['file_bytes'] == 26 + 40 ** 3, g
st = g['statistics']
assert 0 < st['fraction_visible_shapes_tf'] <= st['occupancy'] < 1, st
assert g['generator']['seed'] == '2' and g['generator']['shapes'] == '12', g['generator']
i = json.load(open('out.txt'))
assert i['order'] == 'blocked' and i['block_side'] == 8 and i['dims'] == [40, 40, 40], i
assert i['file_bytes'] == 26 + 6 ** 3 * 512 and i['sample_type'] == 'uint8', i
PY
    # The skull phantom (Table 5.1's stand-in): its default size is the source's 68 x 256 x 256.
    run_ok "$M" volume generate --kind skull --dims 48,40,12 --quiet --out skull.clv
    [ "$(stat -c %s skull.clv)" -eq $((26 + 48 * 40 * 12)) ] || fail "skull size"
    json out.txt "d['statistics']['occupancy']" | python3 -c "import sys; x = float(sys.stdin.read()); assert 0.2 < x < 1, x" \
      || fail "skull occupancy"
    expect_exit 2 "$M" volume generate --kind shapes --size 40 --out lin.clv
    expect_err "--overwrite"
    expect_one_line_err
    ;;
  seed001_render)
    # The transfer-function model on a .clv file: linear and blocked files, image and object
    # order, RAM and mmap give the same image (the identities of the spec's §5, targets 1, 2).
    run_ok "$M" volume generate --kind shapes --size 40 --shapes 12 --object-size 9 --quiet --out lin.clv
    run_ok "$M" volume generate --kind shapes --size 40 --shapes 12 --object-size 9 --layout blocked --block-side 8 \
      --quiet --out blk.clv
    scene() {  # scene NAME FILE MEMORY TRAVERSAL
      cat > "$1.yaml" <<Y
model: transfer_function
volume: {file: $2, memory: $3}
camera: {type: pinhole, width: 48, height: 40, fov_deg: 50, eye: [110, -70, 60], target: [20, 20, 20], up: [0, 0, 1]}
sampling: {ds_rule: fixed_step, step: 0.2}
transfer_function: {table: shapes}
acceleration: {ert_transmittance: 0.01}
traversal: {method: $4, tile: 8}
Y
    }
    scene lin_io lin.clv mmap image_order
    scene lin_ram lin.clv ram image_order
    scene blk_io blk.clv mmap image_order
    scene blk_oo blk.clv mmap object_order
    for s in lin_io lin_ram blk_io blk_oo; do
      run_ok "$M" volume render --scene "$s.yaml" --sample-counts --out "r_$s"
      for f in image.png image.exr samples.png render.json; do [ -s "r_$s/$f" ] || fail "r_$s/$f missing"; done
    done
    cmp -s r_lin_io/image.png r_lin_ram/image.png || fail "RAM and mmap differ"
    cmp -s r_lin_io/image.png r_blk_io/image.png || fail "linear and blocked layouts differ"
    py <<'PY'
import json, struct
def png_size(f):
    return struct.unpack('>II', open(f, 'rb').read(24)[16:24])
for s in ('lin_io', 'lin_ram', 'blk_io', 'blk_oo'):
    j = json.load(open(f'r_{s}/render.json'))
    assert j['model'] == 'transfer_function', j['model']
    c = j['clv']
    assert c['clv.tf.table'] == 'shapes' and c['clv.tf.opacity_exponent'] == 's_over_s0', c
    assert c['clv.sampling.step'].startswith('0.2'), c['clv.sampling.step']
    assert j['stats']['samples'] > 0 and j['stats']['rays'] > 0, j['stats']
    assert png_size(f'r_{s}/image.png') == (48, 40) and png_size(f'r_{s}/samples.png') == (48, 40)
io, oo = json.load(open('r_blk_io/render.json')), json.load(open('r_blk_oo/render.json'))
assert oo['clv']['clv.traversal'] == 'object_order' and oo['volume']['layout'] == 'blocked', oo['volume']
assert oo['stats']['order_violations'] == 0, oo['stats']
assert json.load(open('r_lin_ram/render.json'))['clv']['clv.memory'] == 'ram'
PY
    # Serial and parallel (object order) agree within 1/255 per channel (target 2).
    python3 - <<'PY' || fail "object order differs from image order by more than 1/255"
import zlib, struct
def pixels(f):
    d = open(f, 'rb').read()
    w, h, depth, ctype = struct.unpack('>IIBB', d[16:26])
    assert depth == 8, depth
    idat, i = b'', 8
    while i < len(d):
        n, = struct.unpack('>I', d[i:i + 4]); t = d[i + 4:i + 8]
        if t == b'IDAT': idat += d[i + 8:i + 8 + n]
        i += 12 + n
    raw = zlib.decompress(idat)
    bpp = {0: 1, 2: 3, 4: 2, 6: 4}[ctype]
    stride = w * bpp
    out, prev = [], bytearray(stride)
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - bpp] if x >= bpp else 0
            b, c = prev[x], prev[x - bpp] if x >= bpp else 0
            if f == 1: line[x] = (line[x] + a) & 255
            elif f == 2: line[x] = (line[x] + b) & 255
            elif f == 3: line[x] = (line[x] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c; pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[x] = (line[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line; prev = line
    return out
a, b = pixels('r_blk_io/image.png'), pixels('r_blk_oo/image.png')
assert len(a) == len(b) and max(abs(x - y) for x, y in zip(a, b)) <= 1, max(abs(x - y) for x, y in zip(a, b))
assert max(a) > 0, "an empty image"
PY
    # A user's own raw 8-bit CT through a small JSON header (volume_io.h), blocked in memory: value_scale 1
    # keeps the stored numbers (the TF's units; the header's default for 8-bit samples is 1/255).
    python3 -c "open('ct.raw', 'wb').write(bytes((x * 7 + y * 3 + z) % 256 for x in range(24) for y in range(20) for z in range(16)))"
    printf '{"format": "meltlab-volume", "version": 1, "dims": [16, 20, 24], "sample_type": "uint8", "value_scale": 1, "placement": "nodes", "data": "ct.raw"}\n' > ct.json
    cat > ct.yaml <<'Y'
model: transfer_function
volume: {file: ct.json, layout: blocked, block_side: 8}
camera: {type: pinhole, width: 24, height: 24, fov_deg: 50, eye: [60, -40, 40], target: [8, 10, 12], up: [0, 0, 1]}
sampling: {ds_rule: fixed_step, step: 0.5}
transfer_function: {table: skull}
traversal: {method: object_order}
Y
    run_ok "$M" volume render --scene ct.yaml --out r_ct
    json r_ct/render.json "d['stats']['samples']" | grep -qv '^0$' || fail "no samples on the user's volume"
    ;;
  seed003_bench)
    # Seed 003's studies (volume bench --study seed003-*) on the three phantom scenes made tiny
    # (40 x 40 x 18 samples, 100 x 73 pixels), then the report module on their output.
    export MELTLAB_DATA_DIR="$PWD/data"
    scenes=""
    for s in ones open cavity; do
      sed -e 's/dims: \[256, 256, 113\]/dims: [40, 40, 18]/' -e 's/width: 1000, height: 730/width: 100, height: 73/' \
        "$CONFIGS/slicing_phantom_$s.yaml" > "slicing_phantom_$s.yaml"
      scenes="$scenes${scenes:+,}slicing_phantom_$s.yaml"
    done
    run_ok "$M" volume bench --study seed003-figures,seed003-table3,seed003-table4,seed003-pareto --warmup 0 \
      --repeats 1 --slicing-scenes "$scenes" --sizes 2x2x2,20x20x9,40x40x18 --out exp/bench
    py <<'PY'
import csv, json, os
B = 'exp/bench/'
rd = lambda f: list(csv.DictReader(open(B + f)))
fig = {(r['scene'], r['mode']): r for r in rd('slicing_figures.csv')}
assert len(fig) == 9, fig.keys()
for r in fig.values():
    assert os.path.getsize(B + r['png']) > 0 and os.path.getsize(B + r['png_bloom']) > 0, r
    assert (int(r['width']), int(r['height'])) == (50, 36), r   # quick: half the scene's size
past = {s: int(fig[('slicing_phantom_' + s, 'blend')]['samples_past_mask']) for s in ('ones', 'open', 'cavity')}
assert past['open'] < past['ones'] == past['cavity'], past   # index 0 cuts samples away; index 2 does not
t3 = {(r['mode'], float(r['qc'])): r for r in rd('slicing_table3.csv')}
# quick: the source's 13 QCs
assert sorted({q for _, q in t3}) == [0.2, 0.4, 0.8, 1, 1.5, 2, 2.5, 3, 3.5, 4, 5, 6, 7], t3.keys()
assert {m for m, _ in t3} == {'blend', 'combined'}
for q in (0.2, 0.4, 1, 1.5, 2, 2.5, 3, 3.5):   # halving the spacing doubles the planes (mid-interval planes: +-1)
    assert abs(int(t3[('blend', q)]['slices']) - 2 * int(t3[('blend', 2 * q)]['slices'])) <= 1, q
    assert int(t3[('blend', q)]['samples']) == int(t3[('combined', q)]['samples']), q
assert 0 < float(t3[('blend', 1)]['coverage']) < 1
t4 = rd('slicing_table4.csv')
assert [r['dims'] for r in t4] == ['2x2x2', '20x20x9', '40x40x18'], t4
assert len({r['samples'] for r in t4}) == 1 and len({r['slices'] for r in t4}) == 1, t4   # constant slice count
pa = rd('slicing_pareto.csv')
sl = {float(r['qc']): float(r['rmse']) for r in pa if r['method'] == 'slicing'}
assert sorted(sl) == [0.5, 1, 2, 4] and len([r for r in pa if r['method'] == 'ray_casting']) == 4, pa
assert sl[0.5] < sl[4], sl   # finer planes are closer to the fine ray-cast reference
co = {(r['knob'], r['state']): r for r in rd('slicing_costs.csv')}
assert co[('mask', 'all_ones')]['same_image_as_off'] == 'yes', co
assert float(co[('bloom', 'on')]['post_ms']) > 0
j = json.load(open(B + 'bench.json'))
assert {'seed003_figures', 'seed003_table3', 'seed003_table4', 'seed003_pareto'} <= set(j), j.keys()
PY
    # --qcs picks the grid (sorted; the bench record names it)
    run_ok "$M" volume bench --study seed003-table3 --warmup 0 --repeats 1 --slicing-scenes "$scenes" --qcs 8,0.5 \
      --out exp_qcs
    py <<'PY'
import csv, json
assert [(r['mode'], float(r['qc'])) for r in csv.DictReader(open('exp_qcs/slicing_table3.csv'))] == \
    [('blend', 0.5), ('combined', 0.5), ('blend', 8), ('combined', 8)]
assert json.load(open('exp_qcs/bench.json'))['seed003_table3']['qcs'] == [0.5, 8]
PY
    REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
    /usr/bin/python3 "$REPO/report/experiment_report.py" slicing_seed003 exp > rep.txt 2>&1 || fail "report: $(cat rep.txt)"
    for f in report.json figures.png table_3.csv table_3_fits.csv table_4.csv pareto.png costs.csv; do
      [ -s "exp/$f" ] || fail "report: exp/$f missing"
    done
    grep -q "GOAL Blend QC 1" exp/report.json || fail "no goal verdict"
    # The report's statistics on hand-worked cases: Spearman's rho (reversed ranks -1; one tie: 0.9487,
    # by hand with average ranks) and the t = t0 + k/QC fit (exact on a line: R² 1).
    REPO="$REPO" /usr/bin/python3 - <<'PY' || fail "report statistics"
import math, os, sys
sys.path.insert(0, os.environ['REPO'] + '/report')
from experiments.slicing_seed003 import spearman, fit_inverse
assert spearman([1, 2, 3, 4], [4, 3, 2, 1]) == -1.0
assert abs(spearman([1, 2, 2, 3], [1, 2, 3, 4]) - 4.5 / math.sqrt(22.5)) < 1e-12
t0, k, r2 = fit_inverse([0.5, 1, 2, 4], [20 + 100 / q for q in (0.5, 1, 2, 4)])
assert abs(t0 - 20) < 1e-9 and abs(k - 100) < 1e-9 and abs(r2 - 1) < 1e-12, (t0, k, r2)
PY
    # Bad options: one line, exit 2, nothing written.
    expect_exit 2 "$M" volume bench --study seed003-table3 --out nb
    expect_err "--slicing-scenes"
    expect_one_line_err
    expect_no_dir nb
    expect_exit 2 "$M" volume bench --study seed003-table4 --slicing-scenes slicing_phantom_ones.yaml --sizes 1x1x1 --out nb
    expect_err "--sizes"
    expect_one_line_err
    expect_no_dir nb
    printf 'volume: {generate: {kind: constant, size: 4}}\ncamera: {type: pinhole, width: 8, height: 8, fov_deg: 30, eye: [400, 0, 0], target: [0, 0, 0]}\n' > rc.yaml
    expect_exit 2 "$M" volume bench --study seed003-table3 --slicing-scenes rc.yaml --out nb
    expect_err "rc.yaml"
    expect_one_line_err
    expect_no_dir nb
    ;;
  *) fail "unknown case" ;;
esac
