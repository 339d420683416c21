"""Report of the `melt_scene` experiments (see report/experiment_report.py)."""
import csv
from pathlib import Path

from .common import write_csv, write_fragment, MONOGRAPH_CPU, _montage


def melt_scene(exp: Path, _args):
    d = exp / "scene"
    with open(d / "frames.csv") as f:
        rows = list(csv.DictReader(f))
    pngs = [d / "frames" / f"frame_{int(r['cycle']):06d}.png" for r in rows]
    missing = [str(p) for p in pngs if not p.is_file()]
    if missing:
        raise SystemExit(f"experiment_report.py: missing frames: {missing}")
    _montage(pngs, [f"cycle {r['cycle']}" for r in rows], exp / "fig_7_8.png", "Melting scene (Fig. 7.8)", 3)
    write_csv(exp / "fig_7_8.csv", ["cycle", "triangles", "BVH update", "BVH ms", "trace ms", "mask sum", "wet texels"],
              [[r["cycle"], r["triangles"], r["bvh_update"], r["bvh_ms"], r["trace_ms"], r["mask_sum"], r["wet_texels"]]
               for r in rows])
    trace = [float(r["trace_ms"]) for r in rows]
    write_fragment(exp, {
        "tables": [{"caption": "Frames: triangles, BVH and trace time (ms), liquid mask", "csv": "fig_7_8.csv"}],
        "figures": [{"caption": "The melting bunny, ice material on the wet ground", "png": "fig_7_8.png", "data": "fig_7_8.csv"}],
        "matches": None,
        "verdict": (f"{len(rows)} frames, trace {min(trace):.0f}-{max(trace):.0f} ms per frame on this CPU "
                    "(the monograph's GPU frame rates of 2010 compare only as ratios)."),
        "source_hardware": MONOGRAPH_CPU,
    })
