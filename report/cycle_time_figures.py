#!/usr/bin/python3
"""The monograph's Fig. 5.6 (time per cycle over a run, object B) and Fig. 5.7 (time per
cycle against the remaining triangles, object C), from `meltlab simulate` run folders.

Usage: report/cycle_time_figures.py RUN_B RUN_C OUT_DIR
Writes OUT_DIR/fig_5_6.png, fig_5_7.png and cycle_time.csv (per-run medians, the linear
fit of time against triangles, and the monograph's Tab. 5.1 CPU/GPU means for comparison).
"""
import csv
import json
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TAB_5_1 = {"B": (16000, 5.8, 4.6), "C": (32000, 20.0, 6.0)}  # initial triangles, CPU ms, GPU ms (2009)


def load(run_dir):
    run = json.loads((Path(run_dir) / "run.json").read_text())
    rows = list(csv.DictReader(open(Path(run_dir) / "stats.csv")))[1:]  # cycle 0 has no time
    return run, [int(r["cycle"]) for r in rows], [int(r["triangles"]) for r in rows], [float(r["ms"]) for r in rows]


def linear_fit(x, y):
    mx, my = statistics.fmean(x), statistics.fmean(y)
    sxx = sum((a - mx) ** 2 for a in x)
    slope = sum((a - mx) * (b - my) for a, b in zip(x, y)) / sxx if sxx else 0.0
    return slope, my - slope * mx


def main(argv):
    if len(argv) != 4:
        print(__doc__, file=sys.stderr)
        return 2
    out = Path(argv[3])
    out.mkdir(parents=True, exist_ok=True)
    run_b, cyc_b, tri_b, ms_b = load(argv[1])
    run_c, cyc_c, tri_c, ms_c = load(argv[2])

    fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    ax.plot(cyc_b, ms_b, linewidth=0.5, label=f"meltlab, {run_b['threads']} thread(s), {run_b['precision']}")
    ax.axhline(TAB_5_1["B"][1], color="C3", linestyle="--", label="monograph CPU mean (P8400, 2009)")
    ax.axhline(TAB_5_1["B"][2], color="C2", linestyle=":", label="monograph GPU mean (9600M GT)")
    ax.set_yscale("log")
    ax.set_xlabel("cycle")
    ax.set_ylabel("time per cycle, ms")
    ax.set_title("Fig. 5.6: object B (16000 triangles), time per cycle over the run")
    ax.legend(fontsize=8)
    fig.savefig(out / "fig_5_6.png", dpi=110)
    plt.close(fig)

    slope, icept = linear_fit(tri_c, ms_c)
    fig, ax = plt.subplots(figsize=(7, 4), constrained_layout=True)
    ax.plot(tri_c, ms_c, ".", markersize=1.5, alpha=0.5, label="meltlab, per cycle")
    xs = [min(tri_c), max(tri_c)]
    ax.plot(xs, [icept + slope * x for x in xs], "k-", linewidth=1,
            label=f"fit: {slope * 1000:.4f} ms per 1000 triangles + {icept:.3f} ms")
    # A few cycles (the first, with the poles' collapse and the first touch of the arrays; a
    # compaction; the host's hiccups) take tens of times the rest; an axis up to them would
    # flatten the line the figure is about, so they are counted above the axis instead.
    top = 1.5 * sorted(ms_c)[min(len(ms_c) - 1, int(0.995 * len(ms_c)))]
    above = [m for m in ms_c if m > top]
    ax.set_ylim(0, top)
    if above:
        ax.text(0.99, 0.97, f"{len(above)} cycle(s) above the axis, up to {max(above):.2f} ms",
                transform=ax.transAxes, ha="right", va="top", fontsize=8)
    ax.set_xlabel("remaining triangles")
    ax.set_ylabel("time per cycle, ms")
    ax.set_title("Fig. 5.7: object C (32000 triangles), time against remaining triangles")
    ax.legend(fontsize=8)
    fig.savefig(out / "fig_5_7.png", dpi=110)
    plt.close(fig)

    with open(out / "cycle_time.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["object", "initial_triangles", "cycles", "median_ms", "mean_ms", "max_ms",
                    "monograph_cpu_ms", "monograph_gpu_ms", "cpu_ratio_monograph_over_meltlab"])
        for name, run, ms in (("B", run_b, ms_b), ("C", run_c, ms_c)):
            tri0, cpu, gpu = TAB_5_1[name]
            med = statistics.median(ms)
            w.writerow([name, run["mesh"]["triangles"], len(ms), f"{med:.4f}", f"{statistics.fmean(ms):.4f}",
                        f"{max(ms):.4f}", cpu, gpu, f"{cpu / statistics.fmean(ms):.1f}"])
        w.writerow(["C_fit", "", "", f"slope_ms_per_1000_triangles={slope * 1000:.5f}", f"intercept_ms={icept:.4f}"])
    print((out / "cycle_time.csv").read_text())
    print(f"figures: {out / 'fig_5_6.png'}, {out / 'fig_5_7.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
