#!/usr/bin/env python3
"""Malformed inputs against every reader and option of `meltlab`, as a new user might give them.

Usage: hostile_corpus.py MELTLAB [--asan] [--only SUBSTRING] [--list]

Every case runs one meltlab command on one bad input (a file written by this script, or a bad
option) and must end with
  - the expected exit code (2 = bad input; 1 = `mesh-info` found the mesh invalid),
  - exactly one line on stderr, naming the file (or the option) that is wrong,
  - no output folder left behind (not `--out`, not a hidden staging folder),
  - within a time cap, under a memory cap (address space via setrlimit; under AddressSanitizer,
    which reserves terabytes of address space, its own hard_rss_limit_mb instead).
Exit code 0 when every case passes; the failures are listed otherwise.
"""
import argparse
import os
import resource
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

MEMORY_CAP_BYTES = 3 << 30       # a reader may not need more than this for a tiny bad file
TIME_CAP_S = 30                  # generous: the slowest case is a CGAL repair attempt
ASAN_TIME_CAP_S = 180
ASAN_RSS_LIMIT_MB = 3072

TETRA_V = [(-1, 0, 1), (0, 0, -1), (1, 0, 1), (0, 1, 0)]
TETRA_F = [(3, 1, 0), (3, 2, 1), (3, 0, 2), (1, 2, 0)]


def off_text(v=TETRA_V, f=TETRA_F, header=None):
    h = header if header is not None else f"{len(v)} {len(f)} 0"
    return "OFF\n" + h + "\n" + "".join(f"{a} {b} {c}\n" for a, b, c in v) + "".join(
        f"{len(x)} " + " ".join(map(str, x)) + "\n" for x in f)


def ply_header(fmt, nv=4, nf=4, vprops="property float x\nproperty float y\nproperty float z\n",
               fprops="property list uchar int vertex_indices\n"):
    return (f"ply\nformat {fmt} 1.0\nelement vertex {nv}\n{vprops}element face {nf}\n{fprops}end_header\n")


def ply_binary(nv=4, faces=TETRA_F, count_fmt="<B", list_count=None):
    body = b"".join(struct.pack("<3f", *p) for p in TETRA_V)
    for f in faces:
        n = list_count if list_count is not None else len(f)
        body += struct.pack(count_fmt, n) + struct.pack(f"<{len(f)}i", *f)
    return ply_header("binary_little_endian", nv, len(faces)).encode() + body


def stl_binary(tris, count=None):
    n = len(tris) if count is None else count
    out = b"\0" * 80 + struct.pack("<I", n)
    for t in tris:
        out += struct.pack("<3f", 0, 0, 1) + b"".join(struct.pack("<3f", *p) for p in t) + b"\0\0"
    return out


def png_claiming(w, h):
    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xffffffff)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(b"\0" * 64)) + chunk(b"IEND", b""))


def exr_claiming(w, h):
    def attr(name, typ, value):
        return name.encode() + b"\0" + typ.encode() + b"\0" + struct.pack("<i", len(value)) + value
    hdr = (b"\x76\x2f\x31\x01" + struct.pack("<I", 2) +
           attr("channels", "chlist", b"R\0" + struct.pack("<iBBBBii", 1, 0, 0, 0, 0, 1, 1) + b"\0") +
           attr("compression", "compression", b"\0") +
           attr("dataWindow", "box2i", struct.pack("<4i", 0, 0, w - 1, h - 1)) +
           attr("displayWindow", "box2i", struct.pack("<4i", 0, 0, w - 1, h - 1)) +
           attr("lineOrder", "lineOrder", b"\0") + attr("pixelAspectRatio", "float", struct.pack("<f", 1)) +
           attr("screenWindowCenter", "v2f", struct.pack("<2f", 0, 0)) +
           attr("screenWindowWidth", "float", struct.pack("<f", 1)) + b"\0")
    return hdr + b"\0" * 64


class Case:
    def __init__(self, name, args, files=None, code=2, names=None):
        self.name = name
        self.args = args          # {tokens} are replaced: {f} = the first file, {out}, {run}, {seq}
        self.files = files or {}  # file name -> bytes or str
        self.code = code
        self.names = names        # what stderr must name (default: the first file's name)


def mesh_cases():
    cases = []
    bad_off = {
        "negative_vertex_count": "OFF\n-4 4 0\n",
        "negative_face_count": "OFF\n4 -4 0\n",
        "huge_counts_one_line_of_data": "OFF\n2147483647 2147483647 0\n0 0 0\n",
        "counts_beyond_int64": "OFF\n99999999999999999999 4 0\n",
        "counts_not_numbers": "OFF\nfour four 0\n",
        "fractional_count": "OFF\n4.5 4 0\n",
        "counts_missing": "OFF\n",
        "header_lies_vertices": off_text(header="400 4 0"),
        "header_lies_faces": off_text(header="4 400 0"),
        "truncated_in_vertices": off_text()[:30],
        "truncated_in_faces": off_text()[:-10],
        "nan_coordinate": off_text().replace("1 0 1\n", "1 nan 1\n", 1),
        "inf_coordinate": off_text().replace("0 1 0\n", "0 inf 0\n", 1),
        "two_coordinates": off_text().replace("0 1 0\n", "0 1\n", 1),
        "face_of_a_billion_corners": off_text().replace("3 3 1 0\n", "1000000000 3 1 0\n", 1),
        "face_of_two_corners": off_text().replace("3 3 1 0\n", "2 3 1\n", 1),
        "face_index_negative": off_text().replace("3 3 1 0\n", "3 -1 1 0\n", 1),
        "face_index_beyond": off_text().replace("3 3 1 0\n", "3 4 1 0\n", 1),
        "face_index_huge": off_text().replace("3 3 1 0\n", "3 99999999999 1 0\n", 1),
        "four_dimensional": "4OFF\n" + off_text()[4:],
        "not_off_magic": "FFO\n4 4 0\n",
        "binary_noise": bytes(range(256)) * 4,
        "binary_off_lies": b"OFF BINARY\n" + struct.pack("<3I", 1000000, 1000000, 0) + b"\0" * 40,
        "binary_off_colours": b"COFF BINARY\n" + struct.pack("<3I", 4, 4, 0) + b"\0" * 200,
        "binary_off_face_corners_lie": b"OFF BINARY\n" + struct.pack("<3I", 3, 1, 0) + struct.pack("<9f", *range(9)) +
                                       struct.pack("<I", 4000000000) + struct.pack("<3I", 0, 1, 2),
        "empty": "",
        "only_comments": "# nothing here\n# at all\n",
    }
    for n, text in bad_off.items():
        cases.append(Case(f"off/{n}/simulate", ["simulate", "--mesh", "{f}", "--cycles", "2", "--out", "{out}"],
                          {"m.off": text}))
    for n in ["negative_vertex_count", "huge_counts_one_line_of_data", "face_of_a_billion_corners", "binary_off_lies"]:
        cases.append(Case(f"off/{n}/mesh-info", ["mesh-info", "{f}"], {"m.off": bad_off[n]}))
    bad_ply = {
        "negative_vertex_count": ply_header("ascii", nv=-4),
        "huge_vertex_count": ply_header("ascii", nv=2**40),
        "count_not_number": ply_header("ascii").replace("vertex 4", "vertex four"),
        "no_end_header": "ply\nformat ascii 1.0\nelement vertex 4\n",
        "not_ply": "plx\nformat ascii 1.0\n",
        "format_version_2": ply_header("ascii").replace("1.0", "2.0"),
        "format_unknown": ply_header("ascii").replace("ascii", "binary_middle_endian"),
        "unknown_type": ply_header("ascii").replace("float x", "float128 x"),
        "property_before_element": "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
        "vertex_without_z": ply_header("ascii", vprops="property float x\nproperty float y\n") + "0 0\n" * 4,
        "face_without_indices": ply_header("ascii", fprops="property int flags\n") + "0 0 0\n" * 4 + "0\n" * 4,
        "float_list_count": ply_header("ascii", fprops="property list float int vertex_indices\n"),
        "ascii_truncated": ply_header("ascii") + "-1 0 1\n0 0 -1\n",
        "ascii_garbage_token": ply_header("ascii") + "-1 0 1\n0 zero -1\n1 0 1\n0 1 0\n3 3 1 0\n" * 4,
        "ascii_index_beyond": ply_header("ascii") + "".join(f"{a} {b} {c}\n" for a, b, c in TETRA_V) + "3 7 1 0\n" * 4,
        "ascii_list_count_lies": ply_header("ascii") + "".join(f"{a} {b} {c}\n" for a, b, c in TETRA_V) + "200 3 1 0\n" * 4,
        "binary_list_count_lies": ply_binary(count_fmt="<I", list_count=4000000000),
        "binary_truncated": ply_binary()[:-9],
        "binary_face_of_two": ply_binary(faces=[(0, 1)] * 4),
        "binary_negative_list_count": ply_binary(count_fmt="<b", list_count=-3),
        "big_endian_body_little": ply_binary().replace(b"binary_little_endian", b"binary_big_endian"),
        "duplicate_element": ply_header("ascii") + "element vertex 4\nend_header\n",
    }
    for n, text in bad_ply.items():
        cases.append(Case(f"ply/{n}", ["simulate", "--mesh", "{f}", "--cycles", "2", "--out", "{out}"], {"m.ply": text}))
    tetra_obj = "".join(f"v {a} {b} {c}\n" for a, b, c in TETRA_V)
    bad_obj = {
        "nan_vertex": "v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "vertex_two_coordinates": "v 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "index_zero": tetra_obj + "f 0 1 2\n",
        "index_beyond": tetra_obj + "f 1 2 99999999\n",
        "relative_index_too_far": tetra_obj + "f -1 -2 -9\n",
        "empty_index": tetra_obj + "f /1 2 3\n",
        "face_two_corners": tetra_obj + "f 1 2\n",
        "forward_reference": "f 1 2 3\n" + tetra_obj,
        "no_faces": tetra_obj,
        "no_vertices": "f 1 2 3\n",
        "binary_noise": bytes(range(1, 256)) * 3,
    }
    for n, text in bad_obj.items():
        cases.append(Case(f"obj/{n}", ["simulate", "--mesh", "{f}", "--cycles", "2", "--out", "{out}"], {"m.obj": text}))
    tri = [(0, 0, 0), (1, 0, 0), (0, 1, 0)]
    bad_stl = {
        "binary_count_lies_high": stl_binary([tri], count=0xFFFFFFFF)[:-1],
        "ascii_facet_two_vertices": "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid t\n",
        "ascii_vertex_outside_facet": "solid t\nvertex 0 0 0\nendsolid t\n",
        "ascii_nan": "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 nan 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n",
        "ascii_unterminated_facet": "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n",
        "ascii_four_vertices": "solid t\nfacet normal 0 0 1\nouter loop\n" + "vertex 0 0 0\n" * 4 + "endloop\nendfacet\n",
        "noise": bytes(range(256)) * 2,
        "binary_nan": stl_binary([[(0, 0, float("nan")), (1, 0, 0), (0, 1, 0)]]),
        "empty": "",
    }
    for n, text in bad_stl.items():
        cases.append(Case(f"stl/{n}", ["simulate", "--mesh", "{f}", "--cycles", "2", "--out", "{out}"], {"m.stl": text}))
    # Readable but not a closed solid: mesh-info reports it (exit 1), simulate refuses it (2).
    open_tetra = off_text(f=TETRA_F[:3])
    nonmanifold = off_text(v=TETRA_V + [(0, -1, 0)], f=TETRA_F + [(3, 1, 4)])
    inside_out = off_text(f=[tuple(reversed(t)) for t in TETRA_F])
    for n, text in {"open": open_tetra, "non_manifold": nonmanifold, "inside_out": inside_out}.items():
        cases.append(Case(f"topology/{n}/mesh-info", ["mesh-info", "{f}"], {"m.off": text}, code=1, names=[]))
        cases.append(Case(f"topology/{n}/simulate", ["simulate", "--mesh", "{f}", "--cycles", "2", "--out", "{out}"],
                          {"m.off": text}))
    cases.append(Case("mesh/unknown_extension", ["simulate", "--mesh", "{f}", "--out", "{out}"], {"m.xyz": off_text()}))
    cases.append(Case("mesh/is_a_folder", ["simulate", "--mesh", "{d}", "--out", "{out}"], names=["meshdir"]))
    cases.append(Case("mesh/missing", ["simulate", "--mesh", "nowhere.off", "--out", "{out}"], names=["nowhere.off"]))
    cases.append(Case("mesh/over_the_limit", ["--limits", "mesh_elements=3", "simulate", "--mesh", "{f}", "--out", "{out}"],
                      {"m.off": off_text()}))
    return cases


def manifest_cases():
    cam = "{type: orthographic, width: 64, height: 48, pixels_per_mm: 2, centre_m: [0, 0]}"
    base = f"meltlab_observations: 1\ninterval_s: 40\ncamera: {cam}\nframes:\n  - {{image: frames/frame_0001.jpg}}\n"
    bad = {
        "yaml_syntax": "meltlab_observations: 1\nframes: [a, b\n",
        "yaml_bad_escape": 'meltlab_observations: 1\nobject: "\\q"\n',
        "yaml_deep_nesting": "a: " + "[" * 20000 + "]" * 20000 + "\n",
        "not_a_map": "- 1\n- 2\n",
        "unknown_key": base + "objekt: x\n",
        "negative_interval": base.replace("interval_s: 40", "interval_s: -40"),
        "interval_not_number": base.replace("interval_s: 40", "interval_s: [1, 2]"),
        "camera_unknown_type": base.replace("type: orthographic", "type: fisheye"),
        "camera_zero_width": base.replace("width: 64", "width: 0"),
        "camera_huge": base.replace("width: 64, height: 48", "width: 2000000000, height: 2000000000"),
        "frames_missing_file": base.replace("frame_0001", "nope"),
        "frames_glob_matches_nothing": base.replace("frames:\n  - {image: frames/frame_0001.jpg}\n", "frames: 'frames/*.tif'\n"),
        "frames_empty": base.replace("frames:\n  - {image: frames/frame_0001.jpg}\n", "frames: []\n"),
        "mass_series_missing": base + "mass_series: nope.csv\n",
        "version_2": base.replace("meltlab_observations: 1", "meltlab_observations: 2"),
        "empty_file": "",
        "whitespace_only": "\n   \n",
    }
    cases = []
    for n, text in bad.items():
        cases.append(Case(f"manifest/{n}", ["compare", "--sim", "{run}", "--observations", "{f}", "--out", "{out}"],
                          {"seq/m.yaml": text}))
    jbad = {
        "json_number_overflow": '{"meltlab_observations": 1, "interval_s": 5e555}',
        "json_truncated": '{"meltlab_observations": 1, "frames": [',
        "json_not_object": "[1, 2, 3]",
    }
    for n, text in jbad.items():
        cases.append(Case(f"manifest/{n}", ["compare", "--sim", "{run}", "--observations", "{f}", "--out", "{out}"],
                          {"seq/m.json": text}))
    # Photos that a manifest names: hostile image files.
    photos = {
        "png_header_30000x30000": png_claiming(30000, 30000),
        "exr_header_2e9_rows": exr_claiming(64, 2 ** 30),
        "png_truncated": png_claiming(64, 48)[:40],
        "zero_bytes": b"",
        "text_named_png": b"this is not an image\n",
    }
    for n, data in photos.items():
        ext = "exr" if n.startswith("exr") else "png"
        man = base.replace("frames/frame_0001.jpg", f"frames/bad.{ext}")
        cases.append(Case(f"photo/{n}", ["fit", "--mesh", "benchmark_a", "--observations", "{f}", "--fit", "kg",
                                          "--cycles-per-photo", "2", "--out", "{out}"],
                          {"seq/m.yaml": man, f"seq/frames/bad.{ext}": data}, names=[f"bad.{ext}"]))
    series = {
        "series_nan": "time_s,mass_g\n0,nan\n",
        "series_unknown_column": "time_s,mass_lb\n0,1\n",
        "series_missing_cell": "time_s,mass_g\n0,1\n1\n",
        "series_empty": "",
        "series_header_only": "time_s,mass_g\n",
        "series_binary": bytes(range(256)),
    }
    for n, text in series.items():
        cases.append(Case(f"series/{n}", ["fit", "--mesh", "benchmark_a", "--observations", "{f}", "--fit", "kg",
                                           "--volume-weight", "1", "--cycles-per-photo", "2", "--out", "{out}"],
                          {"seq/m.yaml": base + "mass_series: s.csv\n", "seq/s.csv": text}, names=["s.csv"]))
    # A weighing experiment (a mass series, no photos; issue 19): series a melt cannot make,
    # refused by `fit` and by `predict`, naming the file (and the line where there is one).
    melt_series = {
        "weighing_nan": ("time_s,mass_g\n0,250\n60,nan\n120,240\n", "s.csv:3"),
        "weighing_time_backwards": ("time_s,mass_g\n0,250\n60,245\n30,240\n", "s.csv:4"),
        "weighing_negative_mass": ("time_s,mass_g\n0,250\n60,200\n120,150\n180,-80\n240,50\n", "s.csv:5"),
        "weighing_mass_rises": ("time_s,mass_g\n0,250\n60,240\n120,230\n180,260\n240,262\n300,265\n", "s.csv:5"),
        "weighing_one_row": ("time_s,mass_g\n0,250\n", "s.csv"),
        "weighing_two_rows": ("time_s,mass_g\n0,250\n60,240\n", "s.csv"),
        "weighing_no_ice": ("time_s,mass_g\n0,0\n60,0\n120,0\n", "s.csv:2"),
        "weighing_time_before_start": ("time_s,mass_g\n-60,250\n0,240\n60,230\n", "s.csv:2"),
        "weighing_too_many_spikes": ("time_s,mass_g\n" + "".join(
            f"{60 * k},{250 - 2 * k + (40 if k % 3 == 1 else 0)}\n" for k in range(12)), "s.csv"),
        "weighing_header_only": ("time_s,mass_g\n", "s.csv"),
    }
    weighing = "meltlab_observations: 1\nmass_series: s.csv\n"
    for n, (text, where) in melt_series.items():
        cases.append(Case(f"series/{n}/fit", ["fit", "--mesh", "benchmark_a", "--observations", "{f}",
                                               "--seconds-per-cycle", "6", "--out", "{out}"],
                          {"w/m.yaml": weighing, "w/s.csv": text}, names=[where]))
        cases.append(Case(f"series/{n}/predict", ["predict", "--mesh", "benchmark_a", "--mass-g", "50",
                                                   "--observations", "{f}", "--out", "{out}"],
                          {"w/m.yaml": weighing, "w/s.csv": text}, names=[where]))
    good = "time_s,mass_g\n0,250\n60,240\n120,230\n180,220\n"
    weighing_misuse = {
        "weighing_kg_and_time_scale": (["--fit", "kg,seconds_per_cycle"], ["seconds_per_cycle", "--fix"]),
        "weighing_registration": (["--fit", "kg,reg", "--seconds-per-cycle", "6"], ["reg"]),
        "weighing_no_time_scale": ([], ["--seconds-per-cycle"]),
        "weighing_cycles_per_photo": (["--seconds-per-cycle", "6", "--cycles-per-photo", "7"], ["--cycles-per-photo"]),
        "weighing_negative_seconds": (["--seconds-per-cycle", "-6"], ["--seconds-per-cycle"]),
        "weighing_mass_zero": (["--seconds-per-cycle", "6", "--mass-g", "0"], ["--mass-g"]),
    }
    for n, (extra, names) in weighing_misuse.items():
        cases.append(Case(f"series/{n}", ["fit", "--mesh", "benchmark_a", "--observations", "{f}"] + extra +
                          ["--out", "{out}"], {"w/m.yaml": weighing, "w/s.csv": good}, names=names))
    weighing_manifests = {
        "weighing_camera_without_frames": weighing + "camera: {type: orthographic, width: 64, height: 48}\n",
        "weighing_both_series": weighing + "volume_series: s.csv\n",
        "weighing_no_frames_no_series": "meltlab_observations: 1\nobject: cube\n",
    }
    cases.append(Case("manifest/weighing_compared", ["compare", "--sim", "{run}", "--observations", "{f}",
                                                     "--out", "{out}"], {"w/m.yaml": weighing, "w/s.csv": good},
                      names=["m.yaml"]))
    for n, text in weighing_manifests.items():
        cases.append(Case(f"manifest/{n}", ["fit", "--mesh", "benchmark_a", "--observations", "{f}",
                                             "--seconds-per-cycle", "6", "--out", "{out}"],
                          {"w/m.yaml": text, "w/s.csv": good}, names=["m.yaml"]))
    return cases


def kl_cases():
    bad = {
        "yaml_syntax": "kl: {type: constant, value: [\n",
        "no_kl_key": "k: 1\n",
        "unknown_type": "kl: {type: magnetic}\n",
        "unknown_key": "kl: {type: constant, valeu: 1}\n",
        "value_out_of_range": "kl: {type: constant, value: 7}\n",
        "value_not_number": "kl: {type: constant, value: [1]}\n",
        "point_source_bad_position": "kl: {type: point_source, position: [0, 0], strength: 1, radius: 1}\n",
        "product_empty": "kl: {type: product, of: []}\n",
        "grid_missing_file": "kl: {type: grid, file: nope.grid}\n",
        "bad_escape": 'kl: "\\q"\n',
    }
    cases = [Case(f"kl/{n}", ["simulate", "--mesh", "benchmark_a", "--kl", "{f}", "--out", "{out}"], {"kl.yaml": t})
             for n, t in bad.items()]
    grids = {
        "dims_overflow": "meltlab-kl-grid 1\ndims 2097152 2097152 4194304\norigin 0 0 0\nspacing 1 1 1\nvalues\n",
        "dims_huge": "meltlab-kl-grid 1\ndims 10000 10000 10000\norigin 0 0 0\nspacing 1 1 1\nvalues\n0.5\n",
        "dims_negative": "meltlab-kl-grid 1\ndims -2 2 2\norigin 0 0 0\nspacing 1 1 1\nvalues\n",
        "too_few_values": "meltlab-kl-grid 1\ndims 2 2 2\norigin 0 0 0\nspacing 1 1 1\nvalues\n0 0 0\n",
        "value_nan": "meltlab-kl-grid 1\ndims 1 1 1\norigin 0 0 0\nspacing 1 1 1\nvalues\nnan\n",
        "bad_magic": "meltlab-kl-grod 1\n",
        "spacing_zero": "meltlab-kl-grid 1\ndims 1 1 1\norigin 0 0 0\nspacing 0 1 1\nvalues\n0.5\n",
    }
    for n, t in grids.items():
        cases.append(Case(f"kl_grid/{n}", ["simulate", "--mesh", "benchmark_a", "--kl", "{f}", "--out", "{out}"],
                          {"kl.yaml": "kl: {type: grid, file: g.grid}\n", "g.grid": t}, names=["g.grid"]))
    return cases


def scene_cases():
    bad = {
        "yaml_syntax": "ice: [1, 2\n",
        "unknown_key": "ice: {cx: 1}\n",
        "width_negative": "width: -5\n",
        "width_huge": "width: 99999999\nheight: 99999999\n",
        "bad_escape": 'ice: {model: "\\q"}\n',
        "env_file_missing": "environment: {file: nope.exr}\n",
        "env_png_claims_30000": "environment: {file: env.png}\n",
        "ground_texture_truncated": "ground: {texture: tex.png}\n",
        "deep_nesting": "ice: " + "{a: " * 5000 + "1" + "}" * 5000 + "\n",
        # The fog section (seed 002, render/fog/scene_fog.h).
        "fog_no_spotlights": "fog: {kt: 0.1}\n",
        "fog_spotlights_empty": "fog: {kt: 0.1, spotlights: []}\n",
        "fog_kt_nan": "fog: {kt: .nan, spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}]}\n",
        "fog_target_is_position": "fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 3]}]}\n",
        "fog_table_n_huge": "fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}], table: {n: 100000000}}\n",
        "fog_table_v_warp_bad": "fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}], table: {v_warp: log}}\n",
        "fog_table_v_interp_bad": "fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0]}], table: {v_interp: cubic}}\n",
        "fog_point_with_target": "fog: {spotlights: [{kind: point, position: [0, 0, 3], target: [0, 0, 0]}]}\n",
        "fog_half_angle_90": "fog: {spotlights: [{position: [0, 0, 3], target: [0, 0, 0], half_angle_deg: 90}]}\n",
    }
    files = {"env.png": png_claiming(30000, 15000), "tex.png": png_claiming(64, 64)[:50]}
    cases = []
    for n, t in bad.items():
        names = {"env_png_claims_30000": ["env.png"], "ground_texture_truncated": ["tex.png"],
                 "env_file_missing": ["nope.exr"]}.get(n)
        cases.append(Case(f"scene/{n}", ["render", "--mesh", "benchmark_a", "--scene", "{f}", "--cycles", "0", "--out", "{out}"],
                          {"scene.yaml": t, **files}, names=names))
    return cases


def reproduce_cases():
    bad = {
        "yaml_syntax": "name: x\nsteps: [\n",
        "bad_name": "name: Bad-Name!\nsteps: []\n",
        "unknown_key": "name: x\nstepz: []\n",
        "unknown_variable": "name: x\nsteps:\n  - {name: a, meltlab: [simulate, --out, '${nope}']}\n",
        "step_not_map": "name: x\nsteps: [1, 2]\n",
        "bad_escape": 'name: "\\q"\n',
        "step_named_slurm": "name: x\nsteps:\n  - {name: slurm, meltlab: [simulate]}\n",
        "slurm_bad_mem": "name: x\nslurm: {mem: lots}\nsteps:\n  - {name: a, meltlab: [simulate]}\n",
        "slurm_bad_time": "name: x\nsteps:\n  - {name: a, meltlab: [simulate], slurm: {time: soon}}\n",
        "slurm_unknown_key": "name: x\nslurm: {gpus: 2}\nsteps:\n  - {name: a, meltlab: [simulate]}\n",
        "slurm_cpus_zero": "name: x\nslurm: {cpus: 0}\nsteps:\n  - {name: a, meltlab: [simulate]}\n",
    }
    cases = [Case(f"reproduce/{n}", ["reproduce", "--configs", "{d}", "--out", "{out}"], {"cfg/e.yaml": t},
                  names=["e.yaml"]) for n, t in bad.items()]
    ok = {"cfg/e.yaml": "name: x\nsteps:\n  - {name: a, meltlab: [mesh-info, cube_triangles]}\n"}
    for n, opts, name in (("executor_unknown", ["--executor", "pbs"], "--executor"),
                          ("mem_text", ["--executor", "slurm", "--mem", "lots"], "--mem"),
                          ("time_text", ["--executor", "slurm", "--time", "soon"], "--time"),
                          ("cpus_zero", ["--executor", "slurm", "--cpus", "0"], "--cpus"),
                          ("partition_spaces", ["--executor", "slurm", "--partition", "a b"], "--partition"),
                          ("poll_zero", ["--executor", "slurm", "--poll-seconds", "0"], "--poll-seconds")):
        cases.append(Case(f"reproduce/option_{n}", ["reproduce", "--configs", "{d}", "--out", "{out}"] + opts, ok,
                          names=[name]))
    return cases


def sweep_cases():
    m = "measures: [{name: v, file: run.json, json: final.volume}]\n"
    bad = {
        "yaml_syntax": "name: s\ngrid: [\n",
        "no_points": "name: s\ncommand: simulate\n" + m,
        "no_measures": "name: s\ncommand: simulate\ngrid: {--kg: [1]}\n",
        "option_without_dashes": "name: s\ncommand: simulate\ngrid: {kg: [1]}\n" + m,
        "out_swept": "name: s\ncommand: simulate\ngrid: {--out: [a]}\n" + m,
        "out_in_args": "name: s\ncommand: simulate\nargs: [--out, x]\ngrid: {--kg: [1]}\n" + m,
        "empty_values": "name: s\ncommand: simulate\ngrid: {--kg: []}\n" + m,
        "nested_value": "name: s\ncommand: simulate\ngrid: {--kg: [[1, 2]]}\n" + m,
        "points_differ": "name: s\ncommand: simulate\npoints: [{--kg: 1}, {--kr: 2}]\n" + m,
        "swept_and_fixed": "name: s\ncommand: simulate\nargs: [--kg, '1']\ngrid: {--kg: [1]}\n" + m,
        "command_sweep": "name: s\ncommand: sweep\ngrid: {--kg: [1]}\n" + m,
        "measure_both": "name: s\ncommand: simulate\ngrid: {--kg: [1]}\n"
                        "measures: [{name: v, file: a.csv, json: x, column: y}]\n",
        "measure_outside": "name: s\ncommand: simulate\ngrid: {--kg: [1]}\n"
                           "measures: [{name: v, file: ../../etc/passwd, json: x}]\n",
        "x_not_swept": "name: s\ncommand: simulate\ngrid: {--kg: [1]}\nx: --kr\n" + m,
        "too_many_points": "name: s\ncommand: simulate\ngrid: {--kg: [" + ",".join(map(str, range(200))) +
                           "], --kr: [" + ",".join(map(str, range(200))) + "]}\n" + m,
        "unknown_key": "name: s\ncommand: simulate\ngrid: {--kg: [1]}\nmesaures: []\n" + m,
        "bad_slurm": "name: s\ncommand: simulate\ngrid: {--kg: [1]}\nslurm: {mem: x}\n" + m,
    }
    cases = [Case(f"sweep/{n}", ["sweep", "--config", "{f}", "--out", "{out}"], {"s.yaml": t}) for n, t in bad.items()]
    cases.append(Case("sweep/config_missing", ["sweep", "--config", "nowhere.yaml", "--out", "{out}"],
                      names=["nowhere.yaml"]))
    cases.append(Case("sweep/no_out", ["sweep", "--config", "{f}"],
                      {"s.yaml": "name: s\ncommand: simulate\ngrid: {--kg: [1]}\n" + m}, names=["--out"]))
    return cases


def option_cases():
    o = ["simulate", "--mesh", "benchmark_a"]
    long_name = "x" * 300
    return [
        Case("option/cycles_negative", o + ["--cycles", "-5", "--out", "{out}"], names=["--cycles"]),
        Case("option/kg_nan", o + ["--kg", "nan", "--out", "{out}"], names=["--kg"]),
        Case("option/kg_text", o + ["--kg", "abc", "--out", "{out}"], names=["--kg"]),
        Case("option/threads_negative", o + ["--threads", "-1", "--out", "{out}"], names=["--threads"]),
        Case("option/snapshot_format", o + ["--snapshot-format", "gltf", "--out", "{out}"], names=["--snapshot-format"]),
        Case("option/out_name_too_long", o + ["--out", long_name], names=["--out"]),
        Case("option/out_component_too_long", o + ["--out", f"a/{long_name}/b"], names=["--out"]),
        Case("option/out_under_a_file", o + ["--out", "{file}/sub"], {"afile": "x"}, names=["--out"]),
        Case("option/out_is_a_file", o + ["--out", "{file}"], {"afile": "x"}, names=["--out"]),
        Case("option/out_in_proc", o + ["--out", "/proc/meltlab-cannot-be-here"], names=["--out"]),
        Case("option/out_non_empty_folder", o + ["--out", "{d}"], {"full/keep.txt": "mine"}, names=["--out"]),
        Case("option/limits_unknown", ["--limits", "bogus=1"] + o + ["--out", "{out}"], names=["--limits"]),
        Case("option/limits_zero", ["--limits", "mesh_elements=0"] + o + ["--out", "{out}"], names=["--limits"]),
        Case("option/limits_text", ["--limits", "mesh_elements=lots"] + o + ["--out", "{out}"], names=["--limits"]),
        Case("option/compare_no_run", ["compare", "--sim", "nowhere", "--observations", "{seq}/manifest.yaml",
                                       "--out", "{out}"], names=["nowhere"]),
        Case("option/fit_unknown_parameter", ["fit", "--mesh", "benchmark_a", "--observations", "{seq}/manifest.yaml",
                                              "--fit", "kq", "--out", "{out}"], names=["kq"]),
        Case("option/synth_zero_photos", ["synth-sequence", "--mesh", "benchmark_a", "--photos", "0", "--out", "{out}"],
             names=["--photos"]),
        Case("option/render_every_zero", ["render", "--mesh", "benchmark_a", "--every", "0", "--out", "{out}"],
             names=["--every"]),
        Case("option/predict_mesh_and_shape", ["predict", "--mesh", "benchmark_a", "--shape", "box:10x10x10",
                                               "--out", "{out}"], names=["--shape"]),
        Case("option/predict_no_body", ["predict", "--mass-g", "50", "--out", "{out}"], names=["--mesh"]),
        Case("option/predict_shape_unknown", ["predict", "--shape", "cone:3x4", "--out", "{out}"], names=["--shape"]),
        Case("option/predict_shape_size_zero", ["predict", "--shape", "box:10x0x3", "--out", "{out}"],
             names=["--shape"]),
        Case("option/predict_shape_size_nan", ["predict", "--shape", "sphere:nan", "--out", "{out}"],
             names=["--shape"]),
        Case("option/predict_mesh_without_mass", ["predict", "--mesh", "benchmark_a", "--out", "{out}"],
             names=["--mass-g"]),
        Case("option/predict_warm_ice", ["predict", "--shape", "sphere:30", "--ice-C", "5", "--out", "{out}"],
             names=["--ice-C"]),
        Case("option/predict_voxel_huge", ["predict", "--shape", "sphere:30", "--voxel-mm", "500", "--out", "{out}"],
             names=["--voxel-mm"]),
        Case("option/predict_photos_without_times", ["predict", "--shape", "sphere:30", "--observations", "{f}",
                                                      "--out", "{out}"],
             {"seq/m.yaml": "meltlab_observations: 1\ncamera: {type: orthographic, width: 64, height: 48, "
                            "pixels_per_mm: 2, centre_m: [0, 0]}\nframes:\n  - {image: frames/frame_0001.jpg}\n"},
             names=["m.yaml"]),
        Case("option/text_limit", ["--limits", "text_bytes=16", "simulate", "--mesh", "{mesh}", "--kl", "{f}",
                                   "--out", "{out}"], {"kl.yaml": "kl: {type: constant, value: 0.5}\n"}),
    ]


def volume_cases():
    """Volume files (raw + JSON header, .vdb) and volume scenes: lying sizes, overflowing dims,
    broken headers and files, refused before anything is allocated."""
    def header(dims, typ="uint8", extra=""):
        return ('{"format": "meltlab-volume", "version": 1, "dims": %s, "sample_type": "%s", "data": "v.raw"%s}\n'
                % (dims, typ, extra))
    cam = "camera: {type: pinhole, width: 8, height: 8, fov_deg: 40, eye: [400, 0, 0], target: [0, 0, 0]}\n"
    files = {
        "raw_shorter_than_header": (header("[4, 4, 4]"), b"\1" * 63),
        "raw_longer_than_header": (header("[4, 4, 4]"), b"\1" * 65),
        "dims_overflow_int64": (header("[2147483647, 2147483647, 2147483647]"), b"\1"),
        "dims_over_the_limit": (header("[4096, 4096, 1024]"), b"\1"),
        "dims_zero": (header("[0, 4, 4]"), b""),
        "dims_negative": (header("[-4, 4, 4]"), b"\1"),
        "dims_fraction": (header("[2.5, 4, 4]"), b"\1"),
        "dims_two": (header("[4, 4]"), b"\1" * 16),
        "type_unknown": (header("[2, 2, 2]", "int128"), b"\1" * 8),
        "float_nan": (header("[2, 1, 1]", "float32"), b"\0\0\x80\x3f\0\0\xc0\x7f"),
        "hash_mismatch": (header("[2, 2, 2]", "uint8", ', "content_hash": "0123456789abcdef"'), b"\1" * 8),
        "unknown_key": (header("[2, 2, 2]", "uint8", ', "colour": 3'), b"\1" * 8),
        "wrong_format": ('{"format": "nrrd", "version": 1}\n', b""),
        "version_2": ('{"format": "meltlab-volume", "version": 2}\n', b""),
        "json_truncated": ('{"format": "meltlab-volume", "dims": [', b""),
        "raw_missing": (header("[2, 2, 2]").replace("v.raw", "w.raw"), None),
        "spacing_zero": (header("[2, 2, 2]", "uint8", ', "spacing": [1, 0, 1]'), b"\1" * 8),
    }
    # The file each refusal names: the raw file for its size and contents, else the header.
    named = {"raw_shorter_than_header": "v.raw", "raw_longer_than_header": "v.raw", "float_nan": "v.raw",
             "hash_mismatch": "v.raw", "raw_missing": "w.raw"}
    cases = []
    for n, (h, raw) in files.items():
        fs = {"v.json": h}
        if raw is not None:
            fs["v.raw"] = raw
        names = [named.get(n, "v.json")]
        cases.append(Case(f"volume/{n}/info", ["volume", "info", "{f}"], fs, names=names))
        scene = "model: absorption\nvolume: {file: v.json}\n" + cam
        cases.append(Case(f"volume/{n}/render", ["volume", "render", "--scene", "{f}", "--out", "{out}"],
                          {"s.yaml": scene, **fs}, names=names))
    vdb = {
        "vdb_text": b"this is not an OpenVDB file\n",
        "vdb_magic_only": b"\x20\x42\x44\x56\x00\x00\x00\x00",
        "vdb_random": bytes((i * 97 + 13) % 256 for i in range(4096)),
        "vdb_empty": b"",
    }
    for n, data in vdb.items():
        cases.append(Case(f"volume/{n}", ["volume", "info", "{f}"], {"v.vdb": data}, names=["v.vdb"]))
    scenes = {
        "scene_unknown_key": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "smaples: {n: 3}\n",
        "scene_bad_model": "model: plasma\nvolume: {generate: {kind: constant, size: 4}}\n" + cam,
        "scene_hg_c_one": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "optics: {hg_c: 1}\n",
        "scene_kappa_negative": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "optics: {kappa: -1}\n",
        "scene_samples_zero": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "sampling: {n: 0}\n",
        "scene_size_huge": "model: hg\nvolume: {generate: {kind: constant, size: 100000}}\n" + cam,
        "scene_two_sources": "model: hg\nvolume: {generate: {kind: constant, size: 4}, file: v.json}\n" + cam,
        "scene_orthographic": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n"
                              "camera: {type: orthographic, width: 8, height: 8, pixels_per_unit: 1}\n",
        "scene_eye_inside": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n"
                            "camera: {type: pinhole, width: 8, height: 8, fov_deg: 40, eye: [1, 0, 0], target: [100, 0, 0]}\n",
        "scene_light_zero_dir": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam +
                                "lights: [{type: directional, to_light: [0, 0, 0]}]\n",
        "scene_composite_no_image": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam +
                                    "output: {mode: composite}\n",
        "scene_background_claims_30000": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam +
                                         "output: {mode: composite, background_image: bg.png}\n",
        "scene_fov_and_fx": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam.replace("fov_deg: 40", "fov_deg: 40, fx: 9"),
        # seed 003's slicing renderer (method: slicing)
        "slicing_no_tfs": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  mode: blend\n",
        "slicing_tf_x_not_increasing": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{a: [[0.5, 0.1], [0.2, 0.3]]}]\n",
        "slicing_tf_alpha_above_one": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 1.5]]}]\n",
        "slicing_tf_short_row": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1]]}]\n",
        "slicing_five_tfs": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{a: [[0, 1]]}, {a: [[0, 1]]}, {a: [[0, 1]]}, {a: [[0, 1]]}, {a: [[0, 1]]}]\n",
        "slicing_qc_zero": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  quality_class: 0\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n",
        "slicing_mode_unknown": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  mode: xray\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n",
        "slicing_mask_index_5": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  mask: {edits: [{shape: box, centre: [0.5, 0.5, 0.5], size: [1, 1, 1], index: 5}]}\n",
        "slicing_mask_shape_unknown": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  mask: {edits: [{shape: cone, centre: [0.5, 0.5, 0.5], index: 0}]}\n",
        "slicing_mask_zero_size": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  mask: {edits: [{shape: ellipsoid, centre: [0.5, 0.5, 0.5], radii: [0, 1, 1], index: 0}]}\n",
        "slicing_mask_resolution_huge": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  mask: {resolution: [100000, 1, 1]}\n",
        "slicing_gradient_bits_6": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  gradient: {bits: 6}\n",
        "slicing_with_ray_caster_key": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\nsampling: {n: 10}\n",
        "slicing_section_without_method": "model: hg\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n",
        "slicing_bloom_sigma_zero": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  bloom: {enabled: true, sigma: 0}\n",
        "slicing_skip_cell_3": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  skip_cell: 3\n",
        "slicing_early_termination_above_one": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  early_termination: 1.5\n",
        "slicing_exact_pow_not_bool": "method: slicing\nvolume: {generate: {kind: constant, size: 4}}\n" + cam + "slicing:\n  transfer_functions: [{points: [[0, 1, 1, 1, 0.5]]}]\n  exact_pow: sometimes\n",
    }
    for n, t in scenes.items():
        cases.append(Case(f"volume/{n}", ["volume", "render", "--scene", "{f}", "--out", "{out}"],
                          {"s.yaml": t, "bg.png": png_claiming(30000, 30000)},
                          names=["bg.png"] if n == "scene_background_claims_30000" else None))
    o = ["volume", "generate"]
    cases += [
        Case("volume/generate_kind", o + ["--kind", "smoke", "--out", "{out}.json"], names=["--kind"]),
        Case("volume/generate_size_zero", o + ["--size", "0", "--out", "{out}.json"], names=["--size"]),
        Case("volume/generate_extension", o + ["--out", "{out}.png"], names=["--out"]),
        Case("volume/generate_box_negative", o + ["--box", "0,0,0,1,-1,1", "--out", "{out}.json"], names=["--box"]),
        Case("volume/generate_out_is_a_folder", o + ["--out", "{d}"], {"full/keep.txt": "mine"}, names=["--out"]),
        Case("volume/render_no_scene", ["volume", "render", "--scene", "nowhere.yaml", "--out", "{out}"],
             names=["nowhere.yaml"]),
    ]
    return cases


def clv_header(dims, order=1, side=0, cell=(1.0, 1.0, 1.0)):
    return struct.pack("<3I3fBB", *dims, *cell, order, side)


def clv_cases():
    """Seed 001's .clv volume files (26-byte header, then 8-bit samples) and transfer-function
    scenes: short files, lying headers, wrong order bytes, zero and overflowing dimensions; each
    refused from the header and the file's size before anything is mapped or allocated."""
    cam = "camera: {type: pinhole, width: 8, height: 8, fov_deg: 40, eye: [40, -30, 20], target: [2, 2, 2]}\n"
    files = {
        "clv_empty": b"",
        "clv_header_cut": clv_header((4, 4, 4))[:20],
        "clv_samples_short": clv_header((4, 4, 4)) + b"\1" * 63,
        "clv_samples_long": clv_header((4, 4, 4)) + b"\1" * 65,
        "clv_order_byte_3": clv_header((4, 4, 4), order=3) + b"\1" * 64,
        "clv_order_byte_0": clv_header((4, 4, 4), order=0) + b"\1" * 64,
        "clv_linear_with_side": clv_header((4, 4, 4), order=1, side=16) + b"\1" * 64,
        "clv_blocked_side_1": clv_header((4, 4, 4), order=2, side=1) + b"\1" * 64,
        "clv_blocked_short": clv_header((4, 4, 4), order=2, side=3) + b"\1" * 64,  # needs 2^3 blocks of 3^3
        "clv_dims_zero": clv_header((0, 4, 4)),
        "clv_dims_one": clv_header((1, 4, 4)) + b"\1" * 16,
        "clv_dims_overflow": clv_header((0xFFFFFFFF, 0xFFFFFFFF, 0xFFFFFFFF)) + b"\1" * 64,
        "clv_dims_product_overflows_int64": clv_header((2147483647, 2147483647, 2147483647)) + b"\1" * 64,
        "clv_dims_claim_terabytes": clv_header((65535, 65535, 65535)) + b"\1" * 64,
        "clv_cell_nan": clv_header((2, 2, 2), cell=(1.0, float("nan"), 1.0)) + b"\1" * 8,
        "clv_cell_negative": clv_header((2, 2, 2), cell=(1.0, -1.0, 1.0)) + b"\1" * 8,
        "clv_text": b"this is not a volume, just some text pretending to be one\n",
    }
    cases = []
    for n, data in files.items():
        cases.append(Case(f"volume/{n}/info", ["volume", "info", "{f}"], {"v.clv": data}, names=["v.clv"]))
        for memory in ("mmap", "ram"):
            scene = ("model: transfer_function\nvolume: {file: v.clv, memory: %s}\n" % memory + cam +
                     "sampling: {ds_rule: fixed_step, step: 0.2}\n")
            cases.append(Case(f"volume/{n}/render_{memory}", ["volume", "render", "--scene", "{f}", "--out", "{out}"],
                              {"s.yaml": scene, "v.clv": data}, names=["v.clv"]))
    good = clv_header((4, 4, 4)) + bytes(range(64))
    tf = "model: transfer_function\nvolume: {file: v.clv}\n" + cam
    scenes = {
        "tf_table_unknown": tf + "transfer_function: {table: bones}\n",
        "tf_range_unclosed": tf + 'transfer_function: {table: [{range: "(85, 95", rgb: [1, 2, 3], alpha: 0.5}]}\n',
        "tf_range_reversed": tf + 'transfer_function: {table: [{range: "(95, 85]", rgb: [1, 2, 3], alpha: 0.5}]}\n',
        "tf_alpha_two": tf + 'transfer_function: {table: [{range: "(85, 95]", rgb: [1, 2, 3], alpha: 2}]}\n',
        "tf_for_hg": "model: hg\nvolume: {file: v.clv}\n" + cam + "transfer_function: {table: shapes}\n",
        "tf_exponent_unknown": tf + "transfer_function: {opacity_exponent: s_times_s0}\n",
        "tf_light_zero": tf + "transfer_function: {shading: {light_dir: [0, 0, 0]}}\n",
        "tf_fixed_step_zero": tf + "sampling: {ds_rule: fixed_step, step: 0}\n",
        "tf_tile_zero": tf + "traversal: {method: object_order, tile: 0}\n",
        "object_order_for_hg": "model: hg\nvolume: {file: v.clv}\n" + cam + "traversal: {method: object_order}\n",
        "tf_block_side_one": tf.replace("{file: v.clv}", "{file: v.clv, layout: blocked, block_side: 1}"),
        "tf_memory_unknown": tf.replace("{file: v.clv}", "{file: v.clv, memory: swap}"),
    }
    for n, t in scenes.items():
        cases.append(Case(f"volume/{n}", ["volume", "render", "--scene", "{f}", "--out", "{out}"],
                          {"s.yaml": t, "v.clv": good}, names=["s.yaml"]))
    o = ["volume", "generate", "--kind", "shapes"]
    cases += [
        Case("volume/generate_shapes_dims_zero", o + ["--dims", "0,4,4", "--out", "{out}.clv"], names=["--dims"]),
        Case("volume/generate_shapes_dims_two", o + ["--dims", "4,4", "--out", "{out}.clv"], names=["--dims"]),
        Case("volume/generate_shapes_block_side_1", o + ["--size", "8", "--layout", "blocked", "--block-side", "1",
                                                         "--out", "{out}.clv"], names=["--block-side"]),
        Case("volume/generate_shapes_layout", o + ["--size", "8", "--layout", "zigzag", "--out", "{out}.clv"],
             names=["--layout"]),
        Case("volume/generate_shapes_sample_300", o + ["--size", "8", "--sample", "300", "--out", "{out}.clv"],
             names=["--sample"]),
        Case("volume/generate_shapes_size_one", o + ["--size", "1", "--object-size", "1", "--out", "{out}.clv"], names=["out.clv"]),
        Case("volume/generate_shapes_huge_json", o + ["--size", "2000", "--out", "{out}.json"], names=["--out"]),
        Case("volume/bench_unknown_study", ["volume", "bench", "--study", "seed001-everything", "--out", "{out}"],
             names=["--study"]),
    ]
    # Seed 003's studies: no scenes, a scene that is not method: slicing, a bad key in one, bad --sizes.
    sl = ("method: slicing\nvolume: {generate: {kind: constant, size: 4}}\ncamera: {type: pinhole, width: 8, "
          "height: 8, fov_deg: 30, eye: [400, 0, 0], target: [0, 0, 0]}\nslicing:\n  transfer_functions: "
          "[{a: [[0, 1]]}]\n")
    b = ["volume", "bench", "--warmup", "0", "--repeats", "1"]
    cases += [
        Case("volume/bench_seed003_no_scenes", b + ["--study", "seed003-table3", "--out", "{out}"],
             names=["--slicing-scenes"]),
        Case("volume/bench_seed003_not_slicing", b + ["--study", "seed003-table3", "--slicing-scenes", "{f}", "--out",
                                                      "{out}"], {"s.yaml": sl.replace("method: slicing\n", "")},
             names=["s.yaml", "method: slicing"]),
        Case("volume/bench_seed003_bad_key", b + ["--study", "seed003-figures", "--slicing-scenes", "{f}", "--out",
                                                  "{out}"], {"s.yaml": sl + "  quality: 2\n"}, names=["s.yaml:6"]),
        Case("volume/bench_seed003_sizes_one", b + ["--study", "seed003-table4", "--slicing-scenes", "{f}", "--sizes",
                                                    "1x1x1", "--out", "{out}"], {"s.yaml": sl}, names=["--sizes"]),
        Case("volume/bench_seed003_sizes_text", b + ["--study", "seed003-table4", "--slicing-scenes", "{f}", "--sizes",
                                                     "4x4", "--out", "{out}"], {"s.yaml": sl}, names=["--sizes"]),
        Case("volume/bench_seed003_qcs_range", b + ["--study", "seed003-table3", "--slicing-scenes", "{f}", "--qcs",
                                                    "1,0", "--out", "{out}"], {"s.yaml": sl}, names=["--qcs"]),
        Case("volume/bench_seed003_qcs_twice", b + ["--study", "seed003-table3", "--slicing-scenes", "{f}", "--qcs",
                                                    "2,1,2", "--out", "{out}"], {"s.yaml": sl}, names=["--qcs"]),
    ]
    return cases


def vlb_header(dims="2 2 2", typ="int16", endian="little", spacing="1. 1. 2.", rng="-1117 2248", window="0 1",
               version="VLB.1"):
    return f"{version}\n{dims}\n{typ}\n{endian}\n{spacing}\n{rng}\n{window}\n".encode()


def medical_cases():
    """Seed 003's medical volume files (.vlb, .nrrd, .nhdr): lying sample counts, unknown types,
    zero, negative and overflowing dimensions, truncated headers, unsupported encodings, corrupt
    gzip; each refused with FILE:LINE (or the data file) before anything is allocated."""
    cam = "camera: {type: pinhole, width: 8, height: 8, fov_deg: 30, eye: [40, -30, 20], target: [1, 1, 1]}\n"
    nrrd = b"NRRD0004\ntype: int16\ndimension: 3\nsizes: 2 2 2\nendian: little\n"
    files = {
        "vlb_samples_short": ("v.vlb", vlb_header() + b"\1" * 15),
        "vlb_samples_long": ("v.vlb", vlb_header() + b"\1" * 17),
        "vlb_type_unknown": ("v.vlb", vlb_header(typ="int24") + b"\1" * 24),
        "vlb_type_int64": ("v.vlb", vlb_header(typ="int64") + b"\1" * 64),
        "vlb_dims_zero": ("v.vlb", vlb_header(dims="0 2 2")),
        "vlb_dims_negative": ("v.vlb", vlb_header(dims="-2 2 2") + b"\1" * 16),
        "vlb_dims_two": ("v.vlb", vlb_header(dims="2 2") + b"\1" * 8),
        "vlb_dims_overflow": ("v.vlb", vlb_header(dims="2147483647 2147483647 2147483647") + b"\1" * 16),
        "vlb_dims_over_the_limit": ("v.vlb", vlb_header(dims="65535 65535 65535") + b"\1" * 16),
        "vlb_dims_claim_terabytes_double": ("v.vlb", vlb_header(dims="2147483647 2147483647 2", typ="double")),
        "vlb_header_cut": ("v.vlb", vlb_header()[:20]),
        "vlb_empty": ("v.vlb", b""),
        "vlb_version_2": ("v.vlb", vlb_header(version="VLB.2") + b"\1" * 16),
        "vlb_endian_middle": ("v.vlb", vlb_header(endian="middle") + b"\1" * 16),
        "vlb_spacing_zero": ("v.vlb", vlb_header(spacing="1 0 1") + b"\1" * 16),
        "vlb_range_reversed": ("v.vlb", vlb_header(rng="5 -5") + b"\1" * 16),
        "vlb_window_empty": ("v.vlb", vlb_header(window="1 1") + b"\1" * 16),
        "vlb_float_nan": ("v.vlb", vlb_header(dims="2 1 1", typ="float") + b"\0\0\x80\x3f\0\0\xc0\x7f"),
        "vlb_binary": ("v.vlb", bytes((i * 97 + 13) % 256 for i in range(4096))),
        "nrrd_samples_short": ("v.nrrd", nrrd + b"encoding: raw\n\n" + b"\1" * 15),
        "nrrd_encoding_ascii": ("v.nrrd", nrrd + b"encoding: ascii\n\n1 2 3 4 5 6 7 8\n"),
        "nrrd_gzip_corrupt": ("v.nrrd", nrrd + b"encoding: gzip\n\n" + b"\x1f\x8b" + b"\1" * 30),
        "nrrd_gzip_bomb_claim": ("v.nrrd", nrrd.replace(b"2 2 2", b"4096 4096 1024") + b"encoding: gzip\n\n\x1f\x8b\1"),
        "nrrd_dimension_4": ("v.nrrd", b"NRRD0004\ntype: int16\ndimension: 4\n"),
        "nrrd_sizes_zero": ("v.nrrd", b"NRRD0004\ntype: int16\ndimension: 3\nsizes: 0 2 2\n"),
        "nrrd_oblique": ("v.nrrd", nrrd + b"encoding: raw\nspace directions: (1,1,0) (0,1,0) (0,0,1)\n\n" + b"\1" * 16),
        "nrrd_no_data": ("v.nrrd", nrrd + b"encoding: raw\n"),
        "nrrd_text": ("v.nrrd", b"this is not a volume\n"),
        "nhdr_data_missing": ("v.nhdr", nrrd + b"encoding: raw\ndata file: w.raw\n"),
    }
    named = {"nhdr_data_missing": "w.raw"}
    cases = []
    for n, (name, data) in files.items():
        names = [named.get(n, name)]
        cases.append(Case(f"volume/{n}/info", ["volume", "info", "{f}"], {name: data}, names=names))
        scene = "model: transfer_function\nvolume: {file: %s}\n" % name + cam
        cases.append(Case(f"volume/{n}/render", ["volume", "render", "--scene", "{f}", "--out", "{out}"],
                          {"s.yaml": scene, name: data}, names=names))
    good = vlb_header(dims="4 4 4") + bytes(range(128))
    tf = "model: transfer_function\nvolume: {file: v.vlb, %s}\n" + cam
    scenes = {
        "vlb_normalise_unknown": tf % "normalise: minmax",
        "vlb_window_units_unknown": tf % "window_units: percent",
        "normalise_for_generated": "model: transfer_function\nvolume: {generate: {kind: ct_phantom, dims: [8, 8, 8]}, "
                                   "normalise: header}\n" + cam,
        "ct_phantom_noise_negative": "model: transfer_function\nvolume: {generate: {kind: ct_phantom, dims: [8, 8, 8], "
                                     "noise_hu: -1}}\n" + cam,
    }
    for n, t in scenes.items():
        cases.append(Case(f"volume/{n}", ["volume", "render", "--scene", "{f}", "--out", "{out}"],
                          {"s.yaml": t, "v.vlb": good}, names=["s.yaml"]))
    o = ["volume", "generate", "--kind", "ct_phantom"]
    cases += [
        Case("volume/generate_ct_phantom_dims_one", o + ["--dims", "1,4,4", "--out", "{out}.vlb"], names=["ct_phantom"]),
        Case("volume/generate_ct_phantom_spacing_zero", o + ["--spacing", "1,0,2", "--out", "{out}.vlb"],
             names=["--spacing"]),
        Case("volume/generate_ct_phantom_noise_negative", o + ["--noise-hu", "-3", "--out", "{out}.vlb"],
             names=["--noise-hu"]),
        Case("volume/generate_noise_hu_for_turbulence", ["volume", "generate", "--noise-hu", "3", "--out", "{out}.vlb"],
             names=["--noise-hu"]),
        Case("volume/generate_ct_phantom_box", o + ["--box", "0,0,0,1,1,1", "--out", "{out}.vlb"], names=["--box"]),
        Case("volume/generate_shapes_vlb", ["volume", "generate", "--kind", "shapes", "--size", "8", "--out", "{out}.vlb"],
             names=["--out"]),
    ]
    return cases


def run_case(meltlab, case, root, fixtures, asan):
    work = tempfile.mkdtemp(prefix="case-", dir=root)
    first = None
    for rel, data in case.files.items():
        path = os.path.join(work, rel)
        os.makedirs(os.path.dirname(path), exist_ok=True)
        with open(path, "wb") as out:
            out.write(data.encode() if isinstance(data, str) else data)
        first = first or path
    os.makedirs(os.path.join(work, "meshdir"), exist_ok=True)
    if case.name.startswith(("manifest/", "series/", "option/predict_photos")):  # a real photo where manifests expect one
        os.makedirs(os.path.join(work, "seq", "frames"), exist_ok=True)
        shutil.copy(os.path.join(fixtures["seq"], "frames", "frame_0001.jpg"),
                    os.path.join(work, "seq", "frames", "frame_0001.jpg"))
    subs = {"{f}": first or "", "{out}": os.path.join(work, "out"), "{run}": fixtures["run"], "{seq}": fixtures["seq"],
            "{d}": os.path.join(work, "meshdir") if case.name == "mesh/is_a_folder" else
                   os.path.join(work, "cfg") if case.name.startswith("reproduce/") else os.path.join(work, "full"),
            "{file}": os.path.join(work, "afile"), "{mesh}": fixtures["mesh"]}
    args = []
    for a in case.args:
        for k, v in subs.items():
            a = a.replace(k, v)
        args.append(a)
    env = dict(os.environ)
    env.pop("MELTLAB_LIMITS", None)
    if asan:
        env["ASAN_OPTIONS"] = f"detect_leaks=0:hard_rss_limit_mb={ASAN_RSS_LIMIT_MB}:allocator_may_return_null=1"

    def cap():
        if not asan:
            resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP_BYTES, MEMORY_CAP_BYTES))

    t0 = time.monotonic()
    try:
        p = subprocess.run([meltlab] + args, cwd=work, env=env, capture_output=True, preexec_fn=cap,
                           timeout=ASAN_TIME_CAP_S if asan else TIME_CAP_S)
    except subprocess.TimeoutExpired:
        return [f"did not finish within {ASAN_TIME_CAP_S if asan else TIME_CAP_S} s"]
    elapsed = time.monotonic() - t0
    problems = []
    err = p.stderr.decode(errors="replace")
    lines = [l for l in err.splitlines() if l.strip()]
    if p.returncode != case.code:
        problems.append(f"exit {p.returncode}, want {case.code}")
    if case.code == 2:
        if len(lines) != 1:
            problems.append(f"{len(lines)} lines on stderr, want 1")
        names = case.names if case.names is not None else [os.path.basename(first)] if first else []
        for n in names:
            if not lines or n not in lines[-1]:
                problems.append(f"stderr does not name '{n}'")
        if "internal error" in err:
            problems.append("reported as an internal error")
    out = os.path.join(work, "out")
    if os.path.exists(out):
        problems.append("--out was left behind")
    leftovers = [n for n in os.listdir(work) if n.startswith(".") and "partial" in n]
    if leftovers:
        problems.append(f"staging folders left: {leftovers}")
    if problems:
        problems.append(f"stderr: {err.strip()[:300]!r} ({elapsed:.1f} s)")
    shutil.rmtree(work, ignore_errors=True)
    return problems


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("meltlab")
    ap.add_argument("--asan", action="store_true")
    ap.add_argument("--only", default="")
    ap.add_argument("--list", action="store_true")
    a = ap.parse_args()
    cases = (mesh_cases() + manifest_cases() + kl_cases() + scene_cases() + reproduce_cases() + sweep_cases() +
             option_cases() + volume_cases() + clv_cases() + medical_cases())
    cases = [c for c in cases if a.only in c.name]
    if a.list:
        for c in cases:
            print(c.name)
        print(f"{len(cases)} cases")
        return 0
    root = tempfile.mkdtemp(prefix="meltlab-hostile-")
    try:
        # Fixtures: a finished run and a tiny photo sequence, for the commands that need one.
        fixtures = {"run": os.path.join(root, "run"), "seq": os.path.join(root, "seq"), "mesh": os.path.join(root, "t.off")}
        with open(fixtures["mesh"], "w") as out:
            out.write(off_text())
        subprocess.run([a.meltlab, "simulate", "--mesh", "benchmark_a", "--cycles", "4", "--out", fixtures["run"]],
                       check=True, capture_output=True)
        subprocess.run([a.meltlab, "synth-sequence", "--mesh", "benchmark_a", "--photos", "2", "--width", "64",
                        "--height", "48", "--out", fixtures["seq"]], check=True, capture_output=True)
        failed = 0
        for c in cases:
            problems = run_case(a.meltlab, c, root, fixtures, a.asan)
            if problems:
                failed += 1
                print(f"FAIL {c.name}: " + "; ".join(problems))
        print(f"{len(cases) - failed}/{len(cases)} hostile inputs refused cleanly")
        return 1 if failed else 0
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
