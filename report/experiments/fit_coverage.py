"""Report of the `fit_coverage` experiment (see report/experiment_report.py and
report/fit_coverage.py): the coverage table, the errors against their error bars, a verdict."""
import json
from pathlib import Path

from .common import MONOGRAPH_NONE, plt, write_csv, write_fragment

GOAL = (0.90, 0.98)


def fit_coverage(exp: Path, _args):
    seq = exp / "sequences"
    s = json.loads((seq / "coverage.json").read_text())
    import csv
    rows = list(csv.DictReader(open(seq / "coverage.csv")))
    n = s["sequences"]
    kinds = [("ceres", "Ceres covariance (independent residuals)"),
             ("clustered", "clustered, one cluster per photo (statistical)"),
             ("total", "total: clustered and segmentation bias")]
    table = []
    for key, label in kinds:
        f = s[f"coverage_{key}"]
        table.append([label, f"{s[f'counted_{key}']}/{n}", f, s[f"rms_z_{key}"]])
    write_csv(exp / "coverage.csv", ["standard error", "sequences", "coverage (truth within ±1.96 s.e.)",
                                     "RMS of error / s.e. (1 if honest)"], table)
    per = []
    for r in rows:
        f = lambda k: float(r[k]) if r[k] not in ("", "None") else None  # noqa: E731
        per.append([r["sequence"], r["mesh"], f"{r['width']}x{r['height']}", int(r["photos"]), r["registration"],
                    f("kg_true"), f("kg"), f("error"), f("se_ceres"), f("se_clustered"), f("segmentation_bias"),
                    f("se_total"), r["covered_total"]])
    write_csv(exp / "sequences.csv", ["sequence", "mesh", "image", "photos", "registration fitted", "true kg",
                                      "fitted kg", "error", "s.e. Ceres", "s.e. clustered", "segmentation bias",
                                      "s.e. total", "truth within ±1.96 total"], per)
    bias = [["mean error of kg (all sequences)", s["mean_error"]],
            ["mean error / clustered s.e.", s["mean_z_clustered"]],
            ["mean |error|", s["mean_abs_error"]],
            ["mean |estimated segmentation bias|", s["mean_abs_segmentation_bias"]],
            ["mean |error - estimated segmentation bias|", s["mean_abs_error_corrected"]]]
    write_csv(exp / "bias.csv", ["quantity", "value"], bias)

    # Errors against their error bars, per kind.
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.8), sharey=False)
    for ax, (key, label) in zip(axes, kinds):
        col = {"ceres": "se_ceres", "clustered": "se_clustered", "total": "se_total"}[key]
        pts = [(float(r[col]), abs(float(r["error"]))) for r in rows if r[col] not in ("", "None")]
        if pts:
            lo = min(min(p[0] for p in pts), min(p[1] for p in pts if p[1] > 0) if any(p[1] > 0 for p in pts) else 1)
            hi = max(max(p[0] for p in pts), max(p[1] for p in pts))
            ax.loglog([p[0] for p in pts], [max(p[1], lo / 10) for p in pts], "o", ms=4)
            ax.plot([lo / 2, hi * 2], [1.96 * lo / 2, 1.96 * hi * 2], "r--", lw=1, label="|error| = 1.96 s.e.")
        ax.set_title(label, fontsize=9)
        ax.set_xlabel("standard error of kg")
        ax.set_ylabel("|error of kg|")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(exp / "coverage.png", dpi=110)
    plt.close(fig)

    total = s["coverage_total"]
    ok = total is not None and GOAL[0] <= total <= GOAL[1]
    quick = n < 20
    verdict = (f"{n} sequences: the truth lies within ±1.96 s.e. for {s['coverage_ceres']:.0%} with Ceres' covariance, "
               f"{s['coverage_clustered']:.0%} with the per-photo clustered (statistical) error alone and "
               f"{total:.0%} with the total error (goal {GOAL[0]:.0%}-{GOAL[1]:.0%}). RMS of error / s.e.: "
               f"{s['rms_z_ceres']:.2f} Ceres, {s['rms_z_clustered']:.2f} clustered, {s['rms_z_total']:.2f} total (1 if "
               f"honest). What the statistical error leaves out is the segmentation's systematic error, of either sign "
               f"(mean error {s['mean_z_clustered']:+.2f} clustered s.e.); the estimated segmentation bias (mean |b| "
               f"{s['mean_abs_segmentation_bias']:.2g}) sizes it"
               + (" and would correct it" if s["mean_abs_error_corrected"] < s["mean_abs_error"] else
                  " but is no correction")
               + f" (mean |error| {s['mean_abs_error']:.2g}, {s['mean_abs_error_corrected']:.2g} after subtracting it).")
    if quick:
        verdict += " Quick mode: too few sequences for a coverage fraction; the full mode fits 24."
    write_fragment(exp, {
        "tables": [{"caption": "Coverage of the fit's standard errors of kg over independent noisy synthetic "
                               "sequences (goal for an honest error: 90-98 %)", "csv": "coverage.csv"},
                   {"caption": "The bias beside the statistical error", "csv": "bias.csv"},
                   {"caption": "Per sequence: truth, estimate and the errors of fit.json", "csv": "sequences.csv"}],
        "figures": [{"caption": "|error| of kg against each standard error (below the dashed line: covered)",
                     "png": "coverage.png", "data": "sequences/coverage.csv"}],
        "matches": None if quick else ok,
        "verdict": verdict,
        "source_hardware": MONOGRAPH_NONE,
    })
