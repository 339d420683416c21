"""Report of the `physics_fit` experiments (see report/experiment_report.py)."""
import csv
import json
from pathlib import Path

from .common import write_csv, write_fragment, fmt_bool, MONOGRAPH_PHOTO
from .chapter8 import P_MONOGRAPH


def physics_fit(exp: Path, args):
    """The empirical model fitted to a physically based melt (meltlab manufacture + fit)."""
    mold = args[0]
    j = json.loads((exp / "fit" / "fit.json").read_text())
    rows = [[name, e.get("value"), e.get("standard_error"), e.get("initial"), fmt_bool(e.get("at_bound", False))]
            for name, e in j["estimates"].items() if not e.get("fixed")]
    write_csv(exp / "fit.csv", ["parameter", "estimate", "standard error", "start", "at a bound"], rows)
    per = list(csv.DictReader(open(exp / "fit" / "comparison" / "per_frame.csv")))
    p_key = "P" if "P" in per[0] else [k for k in per[0] if k.lower().startswith("p")][0]
    # P per photo number (photos whose silhouette is empty have no P: the ice has vanished).
    p_of = {int(r["frame"]): float(r[p_key]) for r in per if r[p_key] not in ("", "nan")}
    ps = [p_of[k] for k in sorted(p_of)]
    first = [p for k, p in sorted(p_of.items()) if k <= 100]
    p1_ref, p100_ref = P_MONOGRAPH[mold]
    p100 = p_of.get(100, ps[min(99, len(ps) - 1)])
    held = j.get("P_held_out_frames") or {}
    # Held-out prediction (full mode): how far past the fitted photos P stays within 0.2.
    later = sorted(k for k in p_of if k > 100)
    first_over = next((k for k in later if p_of[k] > 0.2), None)
    last_within = (first_over - 1) if first_over else (later[-1] if later else None)
    empty = sorted(int(r["frame"]) for r in per if r.get("status", "ok") != "ok")
    rows = [["P1", ps[0], p1_ref], ["P100", p100, p100_ref], ["P max, photos 1-100", max(first), None],
            ["P mean, photos 1-100", sum(first) / len(first), None],
            ["P mean, held-out photos", held.get("P_mean"), None], ["P max, held-out photos", held.get("P_max"), None]]
    if later:
        rows.append(["last photo with P <= 0.2 (before the first above)", last_within, None])
    if empty:
        rows.append(["first photo with no ice left (empty silhouette)", empty[0], None])
    write_csv(exp / "p1_p100.csv",
              ["quantity", "meltlab (fitted model vs physics photos)", "monograph (model vs real ice)"], rows)
    held_note = ""
    if later:
        held_note = (f" Held-out photos {later[0]}-{later[-1]} (predicted, not fitted): P ≤ 0.2 up to photo {last_within}"
                     + (f", then rising as the last ice vanishes (no ice from photo {empty[0]})"
                        if first_over and empty else "") + ".")
    figs = []
    if (exp / "fit" / "comparison" / "p_curve.png").is_file():
        figs.append({"caption": f"P per photo of the fitted model against the physics-based photos ({mold})",
                     "png": "fit/comparison/p_curve.png", "data": "fit/comparison/per_frame.csv"})
    for k in (1, 34, 67, 100):
        png = exp / "fit" / "comparison" / "overlays" / f"frame_{k:04d}.png"
        if png.is_file():
            figs.append({"caption": f"Fig. 8.12 analogue, photo {k} (dark grey photo only, black render only, light grey common)",
                         "png": str(png.relative_to(exp)), "data": "fit/comparison/per_frame.csv"})
    est = j["estimates"]
    ok = max(first) <= 0.2
    write_fragment(exp, {
        "tables": [{"caption": "Ceres fit of the empirical model to the physics-based photos (standard errors from "
                               "ceres::Covariance; kn in units of the mean edge length L0)", "csv": "fit.csv"},
                   {"caption": f"P1 and P100 ({mold}); monograph values from spec §9.5", "csv": "p1_p100.csv"}],
        "figures": figs,
        "matches": ok,
        "verdict": (f"kg {est['kg']['value']:.3f} ± {est['kg']['standard_error']:.3f}, "
                    + (f"K {est['cycles_per_photo']['value']:.2f} ± {est['cycles_per_photo']['standard_error']:.2f}, "
                       if "cycles_per_photo" in est else "")
                    + (f"kN/L0 {est['kn']['value']:.5f} ± {est['kn']['standard_error']:.5f} "
                       f"(the monograph's kE/100 = 0.0005), " if "kn" in est else "")
                    + f"P1 {ps[0]:.3f}, P100 {p100:.3f}, P max over photos 1-100 {max(first):.3f}: "
                    + ("within" if ok else "NOT within")
                    + f" the acceptance P ≤ 0.2 (monograph, real ice, hand-chosen kg: P1 {p1_ref}, P100 {p100_ref})."
                    + held_note),
        "source_hardware": MONOGRAPH_PHOTO,
        "extra": {"physics_mold": mold, "P1": ps[0], "P100": p100, "P_max_first_100": max(first)},
    })
