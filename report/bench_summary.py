#!/usr/bin/python3
"""Summarise meltlab_bench_cycle's JSON: median ms per cycle for every mesh, mode and
precision, the speed-up of the parallel cycle, the ratio to the OpenMesh peer measured
in the same run, the share of the serial cycle spent in Alg. 1 / Alg. 2, the parallel cycle's work on one
thread (its sweep in two parts, BM_MeltCycleInParts, ms), the two-thread
ceiling (two serial cycles at once on their own copies: BM_IndependentCopies' throughput
ratio, where measured) and the serial cost of one statistics row; the cycle after a gap
(BM_MeltCycleAfterGap: a statistics row, a busy wait or a sleep before each timed cycle, against
no gap); writes
bench_cycle.png (time per cycle against triangles) beside the JSON.

Usage: report/bench_summary.py bench_cycle.json
"""
import json
import re
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MONOGRAPH_MS = {"A_192": ("<1", "4"), "B_16k": ("5.8", "4.6"), "C_32k": ("20", "6")}  # Tab. 5.1 CPU, GPU


def share(row):
    """'deform/collapse' percentages of a cycle's time, from the simulator's own clocks."""
    ms, _, deform_ms, collapse_ms = row
    if deform_ms is None or collapse_ms is None or ms <= 0:
        return "-"
    return f"{100 * deform_ms / ms:.0f}/{100 * collapse_ms / ms:.0f}"


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    path = Path(argv[1])
    doc = json.loads(path.read_text())
    rows = {}
    gaps = []  # (mesh, gap, cycle ms, gap ms) of BM_MeltCycleAfterGap, in run order
    for b in doc["benchmarks"]:
        if b.get("aggregate_name", "median") != "median":
            continue
        label = b.get("label", "")
        if b.get("run_name", b["name"]).startswith("BM_MeltCycleAfterGap"):
            g = re.match(r"(\S+) parallel double after (.+)", label)
            if g:
                ms = b["real_time"] if b.get("time_unit") == "ms" else b["real_time"] / 1e6
                gaps.append((g.group(1), g.group(2), ms, b.get("gap_ms", 0.0)))
            continue
        m = re.match(r"(\S+) (\S+) (\S+) ?(\S+)?(?: (\S+))?", label)
        if not m:
            continue
        family = b.get("run_name", b["name"]).split("<")[0]
        mesh = m.group(1)
        ms = b["real_time"] if b.get("time_unit") == "ms" else b["real_time"] / 1e6
        if family == "BM_MeltCycle":
            mode, prec = m.group(2), m.group(3)
        elif family == "BM_OpenMeshPeer":
            mode, prec = "openmesh", m.group(4)
        elif family == "BM_MeshStatistics":  # one statistics row, not a cycle
            mode, prec = "stats-" + m.group(2), m.group(3)
        elif family == "BM_MeltCycleInParts":  # "<mesh> <n> parts serial <prec>": the parallel work on one thread
            mode, prec = "parts" + m.group(2), m.group(5)
        elif family == "BM_IndependentCopies":  # "<mesh> <n> copy|copies <prec>": 1 / summed throughput
            mode, prec = "copies" + m.group(2), m.group(4)
            ms = b.get("ms_per_cycle", ms)
        else:
            continue
        rows[(mesh, mode, prec)] = (ms, b.get("triangles", 0.0), b.get("deform_ms"), b.get("collapse_ms"))
    meshes = []
    for (mesh, _, _) in rows:
        if mesh not in meshes:
            meshes.append(mesh)
    ctx = doc.get("context", {})
    print(f"machine: {ctx.get('num_cpus')} CPUs at {ctx.get('mhz_per_cpu')} MHz; median ms per cycle")
    hdr = (f"{'mesh':<14}{'prec':<7}{'triangles':>10}{'serial':>9}{'parallel':>9}{'speed-up':>9}{'2 parts':>9}{'ceiling':>9}"
           f"{'OpenMesh':>10}{'peer/ours':>10}{'Alg.1/2 %':>10}{'stats row':>10}{'  monograph CPU/GPU (2009)'}")
    print(hdr)
    print("-" * len(hdr))
    for mesh in meshes:
        for prec in ("float", "double"):
            s = rows.get((mesh, "serial", prec))
            p = rows.get((mesh, "parallel", prec))
            o = rows.get((mesh, "openmesh", prec))
            c1, c2 = rows.get((mesh, "copies1", prec)), rows.get((mesh, "copies2", prec))
            st = rows.get((mesh, "stats-serial", prec))
            p2 = rows.get((mesh, "parts2", prec))
            if not s:
                continue
            mono = MONOGRAPH_MS.get(mesh, ("", ""))
            print(f"{mesh:<14}{prec:<7}{s[1]:>10.0f}{s[0]:>9.3f}"
                  f"{(p[0] if p else float('nan')):>9.3f}{(s[0] / p[0] if p else float('nan')):>9.2f}"
                  f"{(p2[0] if p2 else float('nan')):>9.3f}"
                  f"{(c1[0] / c2[0] if c1 and c2 else float('nan')):>9.2f}"
                  f"{(o[0] if o else float('nan')):>10.3f}{(o[0] / s[0] if o else float('nan')):>10.2f}"
                  f"{share(s):>10}{(st[0] if st else float('nan')):>10.3f}"
                  f"  {mono[0]:>5} / {mono[1]}")
    if gaps:
        print("\nthe parallel double cycle after a gap (median ms of the cycle alone; the gap's own length)")
        print(f"{'mesh':<14}{'gap':<16}{'gap ms':>8}{'cycle ms':>10}{'vs none':>9}")
        for mesh, gap, ms, gap_ms in gaps:
            none = next((x[2] for x in gaps if x[0] == mesh and x[1] == "no gap"), float("nan"))
            print(f"{mesh:<14}{gap:<16}{gap_ms:>8.2f}{ms:>10.3f}{ms / none:>9.2f}")
    fig, ax = plt.subplots(figsize=(7, 4.5), constrained_layout=True)
    for mode, style in (("serial", "o-"), ("parallel", "s-"), ("openmesh", "^--")):
        for prec in ("float", "double"):
            pts = sorted((v[1], v[0]) for (mesh, md, pr), v in rows.items() if md == mode and pr == prec)
            if pts:
                ax.loglog([t for t, _ in pts], [ms for _, ms in pts], style, label=f"{mode} {prec}",
                          alpha=1.0 if prec == "float" else 0.6)
    ax.set_xlabel("live triangles")
    ax.set_ylabel("time per cycle, ms (median)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    out = path.with_suffix(".png")
    fig.savefig(out, dpi=110)
    print(f"figure: {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
