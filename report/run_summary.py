#!/usr/bin/python3
"""Summarise `meltlab simulate` run folders: a text table on stdout and, per run, a PNG
with volume, triangle count, components and cycle time against the cycle number.

Usage: report/run_summary.py RUN_DIR [RUN_DIR ...]
"""
import csv
import json
import struct
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def load(run_dir: Path):
    with open(run_dir / "run.json") as f:
        run = json.load(f)
    with open(run_dir / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    return run, rows


def column(rows, name, kind=float):
    return [kind(r[name]) for r in rows]


def plot(run_dir: Path, run, rows):
    cycle = column(rows, "cycle", int)
    volume = column(rows, "volume")
    tris = column(rows, "triangles", int)
    comps = column(rows, "components", int)
    ms = column(rows, "ms")
    v0 = volume[0] if volume and volume[0] != 0 else 1.0
    fig, axes = plt.subplots(2, 2, figsize=(10, 6.5), constrained_layout=True)
    axes[0][0].plot(cycle, [v / v0 for v in volume])
    axes[0][0].set_ylabel("volume / initial volume")
    axes[0][1].plot(cycle, tris)
    axes[0][1].set_ylabel("live triangles")
    axes[1][0].step(cycle, comps, where="post")
    axes[1][0].set_ylabel("components S")
    axes[1][1].plot(cycle[1:], ms[1:], linewidth=0.6)
    axes[1][1].set_ylabel("cycle time, ms")
    for ax in axes.flat:
        ax.set_xlabel("cycle")
        ax.grid(alpha=0.3)
    mesh = Path(run["mesh"]["argument"]).name
    fig.suptitle(f"{mesh}: {run['status']} after {run['cycles_run']} cycles "
                 f"({run['precision']}, {run['execution']}, {run['threads']} thread(s))")
    out = run_dir / "summary.png"
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


PLY_TYPES = {"float": "f", "float32": "f", "double": "d", "float64": "d", "uchar": "B", "uint8": "B",
             "int": "i", "int32": "i", "uint": "I", "uint32": "I", "short": "h", "ushort": "H"}


def read_mesh(path: Path):
    """Vertices [(x, y, z)] and triangles [(a, b, c)] of an OFF or (ASCII/binary LE) PLY file."""
    data = path.read_bytes()
    if path.suffix.lower() == ".off":
        tok = data.decode().split()
        assert tok[0] == "OFF"
        nv, nf = int(tok[1]), int(tok[2])
        i = 4
        verts = [tuple(map(float, tok[i + 3 * k:i + 3 * k + 3])) for k in range(nv)]
        i += 3 * nv
        faces = []
        for _ in range(nf):
            n = int(tok[i])
            faces.append(tuple(int(x) for x in tok[i + 1:i + 1 + n]))
            i += 1 + n
        return verts, faces
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode().splitlines()
    binary = any(l.startswith("format binary_little_endian") for l in header)
    elements, current = [], None
    for line in header:
        w = line.split()
        if w and w[0] == "element":
            current = {"name": w[1], "count": int(w[2]), "props": []}
            elements.append(current)
        elif w and w[0] == "property":
            current["props"].append(w[1:])
    verts, faces = [], []
    if binary:
        off = end
        for el in elements:
            for _ in range(el["count"]):
                row = []
                for prop in el["props"]:
                    if prop[0] == "list":
                        cf, vf = PLY_TYPES[prop[1]], PLY_TYPES[prop[2]]
                        (n,) = struct.unpack_from("<" + cf, data, off)
                        off += struct.calcsize(cf)
                        row.append(struct.unpack_from(f"<{n}{vf}", data, off))
                        off += n * struct.calcsize(vf)
                    else:
                        f = PLY_TYPES[prop[0]]
                        row.append(struct.unpack_from("<" + f, data, off)[0])
                        off += struct.calcsize(f)
                (verts if el["name"] == "vertex" else faces).append(row)
    else:
        lines = data[end:].decode().split("\n")
        li = 0
        for el in elements:
            for _ in range(el["count"]):
                w = lines[li].split()
                li += 1
                if el["name"] == "vertex":
                    verts.append([float(x) for x in w])
                else:
                    faces.append([tuple(int(x) for x in w[1:1 + int(w[0])])])
    return [tuple(v[:3]) for v in verts], [f[0] for f in faces]


def plot_snapshots(run_dir: Path, run, max_panels=8):
    """Top views (orthographic, looking down -z) of the snapshots: the silhouette a camera
    above the ice would see, as in the monograph's verification set-up."""
    from matplotlib.collections import PolyCollection
    snaps = run["outputs"]["snapshots"]
    if len(snaps) > max_panels:
        step = (len(snaps) - 1) / (max_panels - 1)
        snaps = [snaps[round(k * step)] for k in range(max_panels)]
    cols = min(4, len(snaps))
    rows_n = (len(snaps) + cols - 1) // cols
    fig, axes = plt.subplots(rows_n, cols, figsize=(3.2 * cols, 3.0 * rows_n), squeeze=False, constrained_layout=True)
    first = None
    for ax, rel in zip(axes.flat, snaps):
        verts, faces = read_mesh(run_dir / rel)
        polys = [[verts[i][:2] for i in f] for f in faces]
        ax.add_collection(PolyCollection(polys, facecolors="0.35", edgecolors="none"))
        if first is None and verts:
            xs, ys = [v[0] for v in verts], [v[1] for v in verts]
            pad = 0.05 * max(max(xs) - min(xs), max(ys) - min(ys))
            first = (min(xs) - pad, max(xs) + pad, min(ys) - pad, max(ys) + pad)
        if first:
            ax.set_xlim(first[0], first[1])
            ax.set_ylim(first[2], first[3])
        ax.set_aspect("equal")
        ax.set_title(Path(rel).stem.replace("cycle_", "cycle ").lstrip("0"), fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    for ax in list(axes.flat)[len(snaps):]:
        ax.axis("off")
    out = run_dir / "snapshots.png"
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out


def main(argv):
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    header = f"{'mesh':<14}{'status':>12}{'cycles':>8}{'tris0':>8}{'tris':>8}{'S max':>7}{'vol left':>10}{'median ms':>11}{'p95 ms':>9}"
    print(header)
    print("-" * len(header))
    for arg in argv[1:]:
        run_dir = Path(arg)
        try:
            run, rows = load(run_dir)
        except (OSError, json.JSONDecodeError, KeyError) as e:
            print(f"run_summary: {run_dir}: cannot read run: {e}", file=sys.stderr)
            return 2
        volume = column(rows, "volume")
        comps = column(rows, "components", int)
        t = run["timing"]
        left = volume[-1] / volume[0] if volume and volume[0] else 0.0
        print(f"{Path(run['mesh']['argument']).name:<14}{run['status']:>12}{run['cycles_run']:>8}"
              f"{run['mesh']['triangles']:>8}{run['final']['triangles']:>8}{max(comps):>7}{left:>10.3f}"
              f"{t['cycle_ms_median']:>11.3f}{t['cycle_ms_p95']:>9.3f}")
        png = plot(run_dir, run, rows)
        top = plot_snapshots(run_dir, run)
        print(f"{'':<14}figures: {png}, {top}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
