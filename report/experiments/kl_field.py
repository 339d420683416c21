"""Report of the `kl_field` experiments (see report/experiment_report.py)."""
from pathlib import Path

from .common import write_csv, write_fragment, load_run, MONOGRAPH_NONE


def kl_field(exp: Path, _args):
    table = []
    for name in ("kl_field", "uniform"):
        run, rows = load_run(exp / name)
        v0 = float(rows[0]["volume"])
        table.append([name, run["status"], run["cycles_run"], float(rows[-1]["volume"]) / v0,
                      int(rows[0]["triangles"]), int(rows[-1]["triangles"]), max(int(r["components"]) for r in rows)])
    write_csv(exp / "kl_field.csv", ["run", "status", "cycles", "volume left", "triangles at start", "triangles at end",
                                     "max components"], table)
    write_fragment(exp, {
        "tables": [{"caption": "Giraffe mold with kl = max(point source, ground pressure) against kl = 1",
                    "csv": "kl_field.csv"}],
        "figures": [{"caption": "Fig. 3.10 analogue: kl field (heat source near the head + ground pressure), top views",
                     "png": "kl_field/snapshots.png", "data": "kl_field/stats.csv"},
                    {"caption": "The same block with kl = 1", "png": "uniform/snapshots.png", "data": "uniform/stats.csv"},
                    {"caption": "kl field run: volume, triangles, components, cycle time", "png": "kl_field/summary.png",
                     "data": "kl_field/stats.csv"}],
        "matches": None,
        "verdict": (f"Qualitative figure (the monograph gives no falloff or magnitudes): with kl ≤ 1 the block keeps "
                    f"{table[0][3]:.2f} of its volume against {table[1][3]:.2f} with kl = 1; compare the top views."),
        "source_hardware": MONOGRAPH_NONE,
    })
