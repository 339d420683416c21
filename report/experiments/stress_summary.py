"""Report of the `stress_summary` experiments (see report/experiment_report.py)."""
import statistics
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .common import write_csv, write_fragment, load_run, MONOGRAPH_NONE


def stress_summary(exp: Path, _args):
    """Every mesh melted away in float and in double (folders <mesh>_float, <mesh>_double):
    cycles survived, checks passed, self-intersections, float-vs-double drift and time."""
    pairs = {}
    for d in sorted(p for p in exp.iterdir() if (p / "run.json").is_file()):
        mesh, _, prec = d.name.rpartition("_")
        if prec in ("float", "double"):
            pairs.setdefault(mesh, {})[prec] = load_run(d)
    meshes = [m for m in pairs if len(pairs[m]) == 2]
    if not meshes:
        raise SystemExit(f"experiment_report.py: {exp}: no <mesh>_float / <mesh>_double simulate runs")
    rows, drift_curves = [], {}
    for mesh in meshes:
        (rf, sf), (rd, sd) = pairs[mesh]["float"], pairs[mesh]["double"]
        v0 = float(sd[0]["volume"])
        vol_f = {int(r["cycle"]): float(r["volume"]) for r in sf}
        vol_d = {int(r["cycle"]): float(r["volume"]) for r in sd}
        tri_f = {int(r["cycle"]): int(r["triangles"]) for r in sf}
        tri_d = {int(r["cycle"]): int(r["triangles"]) for r in sd}
        common = sorted(c for c in vol_f if c in vol_d)
        # Drift while the double run still has a tenth of its volume: near the end both are a
        # few triangles and the difference of two small numbers says little.
        alive = [c for c in common if vol_d[c] >= 0.1 * v0]
        drift = [abs(vol_f[c] - vol_d[c]) / v0 for c in alive]
        drift_curves[mesh] = (alive, drift)
        first_diff = next((c for c in common if tri_f[c] != tri_d[c]), None)
        for prec, run in (("float", rf), ("double", rd)):
            ch = run["checks"]
            inter = ch.get("intersections", [])
            input_pairs = next((i["intersecting_pairs"] for i in inter if i["cycle"] == 0), 0)
            rows.append([mesh, prec, run["mesh"]["triangles"], run["status"], run["cycles_run"],
                         ch.get("topology_checks", 0), len(inter), input_pairs,
                         max((i["intersecting_pairs"] for i in inter if i["cycle"] > 0), default=0),
                         run["timing"]["cycle_ms_median"], max(drift) if drift else None,
                         (first_diff if first_diff is not None else "never") if prec == "float" else None])
    write_csv(exp / "stress_summary.csv",
              ["mesh", "precision", "triangles", "status", "cycles survived", "topology checks passed",
               "self-intersection checks", "intersecting pairs in the input", "max intersecting pairs after",
               "median ms/cycle",
               "max |V_float - V_double| / V0 (while V >= 0.1 V0)", "first cycle with different triangle counts"],
              rows)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.4))
    for mesh, (cycles, drift) in drift_curves.items():
        ax1.plot(cycles, [max(x, 1e-12) for x in drift], label=mesh, linewidth=1)
    ax1.set_yscale("log")
    ax1.set_xlabel("cycle")
    ax1.set_ylabel("|V_float - V_double| / V0")
    ax1.set_title("Float against double: volume drift (while V >= 0.1 V0)", fontsize=10)
    ax1.legend(fontsize=7)
    by = {(r[0], r[1]): r for r in rows}
    for mesh in meshes:
        t_f, t_d = by[(mesh, "float")][9], by[(mesh, "double")][9]
        err = by[(mesh, "float")][10] or 1e-12
        ax2.scatter([t_f / t_d], [err], s=18)
        ax2.annotate(mesh, (t_f / t_d, err), fontsize=7)
    ax2.set_yscale("log")
    ax2.set_xlabel("float time / double time per cycle (median)")
    ax2.set_ylabel("max volume drift of float")
    ax2.set_title("Time against error of the precision knob", fontsize=10)
    fig.tight_layout()
    fig.savefig(exp / "stress_summary.png", dpi=100)
    plt.close(fig)
    melted = sum(1 for r in rows if r[3] == "melted")
    checks = sum(r[5] for r in rows)
    worst = max((r[10] for r in rows if r[10] is not None), default=0.0)
    speed = statistics.median(by[(m, "double")][9] / by[(m, "float")][9] for m in meshes)
    any_inter = [r for r in rows if r[8] > 0]
    input_inter = sorted({r[0] for r in rows if r[7] > 0})
    write_fragment(exp, {
        "tables": [{"caption": "Meshes melted until empty in float and double (one core)", "csv": "stress_summary.csv"}],
        "figures": [{"caption": "Float-vs-double volume drift per cycle, and drift against the time ratio",
                     "png": "stress_summary.png", "data": "stress_summary.csv"}],
        "matches": melted == len(rows),
        "verdict": (f"{melted} of {len(rows)} runs ({len(meshes)} meshes x float/double) melted away completely; "
                    f"{checks} full topology checks passed (a failed check would have failed the run); "
                    + (f"meshes already self-intersecting as input: {', '.join(input_inter)}; " if input_inter else "")
                    + (f"self-intersections on sampled cycles after the start in {len(any_inter)} run(s) "
                       f"({', '.join(sorted({r[0] for r in any_inter}))}; max {max(r[8] for r in any_inter)} pairs); "
                       if any_inter else "no self-intersection on any sampled cycle after the start; ")
                    + f"float drifts from double by at most {worst:.2g} of the initial volume while a tenth of it "
                    f"remains, and is {speed:.2f}x as fast per cycle (median over the meshes)."),
        "source_hardware": MONOGRAPH_NONE,
    })
