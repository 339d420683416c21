"""Report of the `deform_variants` experiments (see report/experiment_report.py)."""
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .common import write_csv, write_fragment, load_run, MONOGRAPH_NONE


def deform_variants(exp: Path, _args):
    table, series = [], {}
    for name in ("normal_only", "combined"):
        run, rows = load_run(exp / name)
        ch = run["checks"]
        inter = ch["intersections"]
        series[name] = ([i["cycle"] for i in inter], [i["intersecting_pairs"] for i in inter])
        last = rows[-1]
        table.append([name, run["parameters"]["deform"], run["status"], run["cycles_run"],
                      ch["first_self_intersection_cycle"], max(series[name][1]) if inter else None,
                      float(last["Qd"]), float(last["max_d"]), float(last["volume"]) / float(rows[0]["volume"])])
    write_csv(exp / "deform_variants.csv",
              ["run", "deform", "status", "cycles", "first self-intersection cycle", "max intersecting pairs",
               "Qd at end (deg)", "max d at end (deg)", "volume left"], table)
    write_csv(exp / "intersections.csv", ["run", "cycle", "intersecting_pairs"],
              [[n, c, p] for n, (cs, ps) in series.items() for c, p in zip(cs, ps)])
    fig, ax = plt.subplots(figsize=(7, 3.6), constrained_layout=True)
    for n, (cs, ps) in series.items():
        ax.plot(cs, ps, marker="o", label=n)
    ax.axvline(1500, color="k", ls=":", label="monograph: escaping triangles by cycle 1500")
    ax.set_xlabel("cycle")
    ax.set_ylabel("self-intersecting triangle pairs")
    ax.set_yscale("symlog")
    ax.legend(fontsize=8)
    fig.savefig(exp / "intersections.png", dpi=110)
    plt.close(fig)
    n_first, c_first = table[0][4], table[1][4]
    every = load_run(exp / "normal_only")[0]["checks"]["intersections_every"]
    normal_fails = n_first is not None and n_first >= 0
    combined_clean = c_first is None or c_first < 0
    write_fragment(exp, {
        "tables": [{"caption": "M_N only (Fig. 3.1) against Eq. 3.6 (Fig. 3.5), 1600 cycles", "csv": "deform_variants.csv"}],
        "figures": [{"caption": "Self-intersecting pairs (CGAL) over the run", "png": "intersections.png",
                     "data": "intersections.csv"},
                    {"caption": "Fig. 3.1 analogue: M_N only, top views of cycles 0/800/1600",
                     "png": "normal_only/snapshots.png", "data": "normal_only/stats.csv"},
                    {"caption": "Fig. 3.5 analogue: combined vector, top views of cycles 0/800/1600",
                     "png": "combined/snapshots.png", "data": "combined/stats.csv"}],
        "matches": normal_fails and combined_clean,
        "verdict": (f"Self-intersections (CGAL) checked every {every} cycles. "
                    f"M_N only: first found at cycle {n_first}, up to {table[0][5]} intersecting pairs "
                    f"(monograph: escaping triangles by cycle 1500); combined (Eq. 3.6): "
                    + ("none. Matches the monograph's claim." if combined_clean else
                       f"first at cycle {c_first}, up to {table[1][5]} pairs. The M_N-only failure is reproduced "
                       "(earlier and larger), but the combined vector is not free of self-intersections on this "
                       "mesh, against the monograph's claim that M_E causes no mesh errors.")),
        "source_hardware": MONOGRAPH_NONE,
    })
