"""Report of the `runs` experiments (see report/experiment_report.py)."""
from pathlib import Path

from .common import write_csv, write_fragment, load_run, MONOGRAPH_NONE


def runs(exp: Path, _args):
    rows, figs = [], []
    for d in sorted(p for p in exp.iterdir() if (p / "run.json").is_file()):
        run, st = load_run(d)
        rows.append([d.name, run["status"], run["cycles_run"], run["mesh"]["triangles"], run["final"]["triangles"],
                     run["timing"]["cycle_ms_median"]])
        for png in ("summary.png", "snapshots.png"):
            if (d / png).is_file():
                figs.append({"caption": f"{d.name}: {png}", "png": f"{d.name}/{png}", "data": f"{d.name}/stats.csv"})
    if not rows:
        raise SystemExit(f"experiment_report.py: {exp}: no simulate run folders")
    write_csv(exp / "runs.csv", ["run", "status", "cycles", "triangles at start", "triangles at end", "median ms"], rows)
    write_fragment(exp, {"tables": [{"caption": "Simulate runs", "csv": "runs.csv"}], "figures": figs, "matches": None,
                         "verdict": f"{len(rows)} run(s): " + ", ".join(f"{r[0]} {r[1]}" for r in rows),
                         "source_hardware": MONOGRAPH_NONE})
