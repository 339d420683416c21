"""Report of the `liquid_figure` experiments (see report/experiment_report.py)."""
import csv
from pathlib import Path

from .common import write_csv, write_fragment, MONOGRAPH_CPU, _montage


def liquid_figure(exp: Path, _args):
    d = exp / "mask" / "liquid"
    with open(d / "mask_sums.csv") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"experiment_report.py: {d}/mask_sums.csv: no rows")
    pngs = [d / f"mask_{int(r['cycle']):06d}.png" for r in rows]
    missing = [str(p) for p in pngs if not p.is_file()]
    if missing:
        raise SystemExit(f"experiment_report.py: missing masks: {missing}")
    _montage(pngs, [f"{r['cycle']} cycles" for r in rows], exp / "fig_7_6.png", "Liquid mask (Fig. 7.6)", 4)
    write_csv(exp / "fig_7_6.csv", ["cycle", "triangles", "mask sum", "wet texels", "mask max"],
              [[r["cycle"], r["triangles"], r["mask_sum"], r["wet_texels"], r["mask_max"]] for r in rows])
    sums = [float(r["mask_sum"]) for r in rows]
    wet = [int(r["wet_texels"]) for r in rows]
    grows = all(b >= a for a, b in zip(wet, wet[1:])) if all(int(r["triangles"]) > 0 for r in rows) else None
    write_fragment(exp, {
        "tables": [{"caption": "Liquid mask per cycle (sum of the mask, texels above the threshold)", "csv": "fig_7_6.csv"}],
        "figures": [{"caption": "The mask after each cycle count (white = wet)", "png": "fig_7_6.png", "data": "fig_7_6.csv"}],
        "matches": grows,
        "verdict": (f"The puddle spreads from {wet[0]} to {wet[-1]} wet texels (mask sum {sums[0]:.0f} -> {sums[-1]:.0f}) "
                    f"while the object melts ({rows[0]['triangles']} -> {rows[-1]['triangles']} triangles); "
                    "the monograph shows the same qualitative growth, no numbers."),
        "source_hardware": MONOGRAPH_CPU,
    })
