"""Report of the `fit` experiments (see report/experiment_report.py)."""
import json
import math
from pathlib import Path

from .common import write_csv, write_fragment, MONOGRAPH_NONE


def fit(exp: Path, _args):
    j = json.loads((exp / "fit" / "fit.json").read_text())
    rows = []
    for name, e in j["estimates"].items():
        rows.append([name, e.get("value"), e.get("standard_error"), e.get("standard_error_clustered"),
                     e.get("segmentation_bias"), e.get("standard_error_total"), (j.get("truth") or {}).get(name)])
    reg = j.get("registration", {})
    for k in ("tx_px", "ty_px", "angle_deg", "scale"):
        if k in reg:
            rows.append([f"registration {k}", reg[k], None, None, None, None,
                         {"tx_px": 5, "ty_px": -3, "angle_deg": 0.8, "scale": 1}[k]])
    write_csv(exp / "fit.csv", ["parameter", "estimate", "standard error (Ceres)", "standard error (per photo)",
                                "segmentation bias", "standard error (total)", "truth"], rows)
    kg = j["estimates"]["kg"]
    rel = abs(kg["value"] - 0.8) / 0.8
    comp = j.get("comparison", {})
    figs = []
    if (exp / "fit" / "comparison" / "p_curve.png").is_file():
        figs.append({"caption": "P per photo of the fitted run", "png": "fit/comparison/p_curve.png",
                     "data": "fit/comparison/per_frame.csv"})
    write_fragment(exp, {
        "tables": [{"caption": "Ceres fit of kg and the registration (truth: kg = 0.8, 5/-3 px, 0.8°); reg.* are parameters about the first photo's centroid, the registration rows the resulting camera shift", "csv": "fit.csv"}],
        "figures": figs,
        "matches": rel < 0.01,
        "verdict": (f"kg = {kg['value']:.4f} ± {kg.get('standard_error_total') or math.nan:.4f} (the total error, "
                    f"per photo and segmentation; Ceres' ± {kg['standard_error']:.4f}) (truth 0.8, error "
                    f"{100 * rel:.2f} %), "
                    f"{j.get('simulations')} simulations in {j.get('time_s', 0):.0f} s, P max of the fitted run "
                    f"{comp.get('P_max', math.nan):.4f}. No source value: the monograph chose kg by hand."),
        "source_hardware": MONOGRAPH_NONE,
    })
