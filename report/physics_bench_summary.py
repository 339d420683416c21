#!/usr/bin/python3
"""The reference melt solver's time-against-error table (issue 4) from the Google Benchmark
JSON of meltlab_bench_physics: per grid spacing the run time, the error against the closed
form (Neumann similarity solution of the 1-D Stefan problem; quasi-steady shrinking sphere)
and the observed order of convergence between successive spacings; for the giraffe block the
cost of one simulated hour. Writes <json>.csv and <json>.png (time against error, log-log).

Usage: report/physics_bench_summary.py bench_physics.json
"""
import csv
import json
import math
import re
import sys


def rows(path):
    doc = json.load(open(path))
    out = []
    for b in doc["benchmarks"]:
        if b.get("run_type") == "aggregate" and b.get("aggregate_name") != "median":
            continue
        m = re.match(r"BM_(\w+)/(\d+)", b["name"])
        if not m:
            continue
        out.append({
            "case": m.group(1),
            "h_mm": b.get("h_mm"),
            "time_ms": b["real_time"] if b.get("time_unit") == "ms" else b["real_time"] / 1e6,
            "rel_error": b.get("rel_error"),
            "cells": b.get("cells"),
            "steps": b.get("steps"),
            "s_per_sim_hour": None,
        })
    return out


def add_orders(table):
    """Observed order of convergence between successive grid spacings, as r["order"]."""
    for case in ("NeumannStefan", "ShrinkingSphere"):
        sub = sorted((r for r in table if r["case"] == case), key=lambda r: -r["h_mm"])
        for a, b in zip(sub, sub[1:]):
            if a["rel_error"] and b["rel_error"] and a["rel_error"] > 0 and b["rel_error"] > 0:
                b["order"] = math.log(a["rel_error"] / b["rel_error"]) / math.log(a["h_mm"] / b["h_mm"])


def plot_time_error(ax, table):
    """Run time against relative error per case, log-log, points labelled with h."""
    for case, marker in (("NeumannStefan", "o-"), ("ShrinkingSphere", "s-")):
        sub = sorted((r for r in table if r["case"] == case and r["rel_error"]), key=lambda r: -r["h_mm"])
        if sub:
            ax.loglog([r["time_ms"] for r in sub], [r["rel_error"] for r in sub], marker, label=case)
            for r in sub:
                ax.annotate(f"{r['h_mm']:g} mm", (r["time_ms"], r["rel_error"]), fontsize=7)
    ax.set_xlabel("run time [ms]")
    ax.set_ylabel("relative interface error")
    ax.set_title("Reference melt solver: time against error")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()


def main(argv):
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    table = rows(argv[1])
    for r in table:
        if r["case"] == "GiraffeBlock":
            r["s_per_sim_hour"] = r["time_ms"] / 1e3 * 6.0  # 10 simulated minutes
    add_orders(table)
    print("Reference solver: grid spacing against run time and interface error")
    print(f"{'case':>16} {'h [mm]':>7} {'time [ms]':>10} {'rel. error':>11} {'order':>6} {'cells':>9} {'s/sim h':>8}")
    for r in table:
        f = lambda v, fmt: format(v, fmt) if v is not None else "-"
        print(f"{r['case']:>16} {f(r['h_mm'], '7.2f'):>7} {f(r['time_ms'], '10.1f'):>10} "
              f"{f(r['rel_error'], '11.2e'):>11} {f(r.get('order'), '6.2f'):>6} "
              f"{f(r['cells'], '9.0f'):>9} {f(r['s_per_sim_hour'], '8.1f'):>8}")
    base = re.sub(r"\.json$", "", argv[1])
    with open(base + ".csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=["case", "h_mm", "time_ms", "rel_error", "order", "cells", "steps", "s_per_sim_hour"])
        w.writeheader()
        for r in table:
            w.writerow({k: r.get(k) for k in w.fieldnames})
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return 0
    fig, ax = plt.subplots(figsize=(6, 4))
    plot_time_error(ax, table)
    fig.tight_layout()
    fig.savefig(base + ".png", dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
