"""Report of the `module_studies` experiments (see report/experiment_report.py)."""
import csv
import statistics
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .common import write_csv, write_fragment, MONOGRAPH_NONE


def module_studies(exp: Path, _args):
    """Time against error of the verification loop (P measure, silhouettes), of the
    reference solver and of the fit, from what the earlier steps wrote (benchmark JSONs,
    fit/fit_bench.csv)."""
    import physics_bench_summary
    import verify_bench_summary
    sil, peer, p = verify_bench_summary.tables(str(exp / "silhouette.json"), str(exp / "p_measure.json"))
    if not p or not sil:
        raise SystemExit(f"experiment_report.py: {exp}: no medians in silhouette.json / p_measure.json")
    methods = (("RasterP", "raster pixels"), ("CoverageP", "4x4 coverage"), ("ContourExactP", "exact polygons (CGAL)"))
    widths = sorted({w for (_, w) in p})
    p_rows = [[f"{w}x{w * 3 // 4}", label, p[(kind, w)][0], p[(kind, w)][1]]
              for w in widths for kind, label in methods if (kind, w) in p]
    write_csv(exp / "p_measure.csv", ["image", "P computed from", "median ms", "|P - P exact (closed form)|"], p_rows)
    s_widths = sorted({w for (w, _, _) in sil})
    s_rows = []
    for w in s_widths:
        for k in (1, 4):
            ours, ours2, pe = sil.get((w, k, False)), sil.get((w, k, True)), peer.get((w, k))
            s_rows.append([f"{w}x{w * 3 // 4}", k, ours, ours2, pe, (pe / ours) if (pe and ours) else None])
    write_csv(exp / "silhouette.csv", ["image", "supersampling k (k x k)", "meltlab serial ms", "meltlab 2 threads ms",
                                       "cv::fillConvexPoly peer ms", "peer / meltlab serial"], s_rows)
    phys = physics_bench_summary.rows(str(exp / "physics.json"))
    physics_bench_summary.add_orders(phys)
    write_csv(exp / "physics.csv", ["case", "grid spacing h [mm]", "run time ms", "relative error", "observed order",
                                    "cells"],
              [[r["case"], r["h_mm"], r["time_ms"], r["rel_error"], r.get("order"), r["cells"]] for r in phys])
    with open(exp / "fit" / "fit_bench.csv") as f:
        fit = list(csv.DictReader(f))
    if not fit:
        raise SystemExit(f"experiment_report.py: {exp}: fit/fit_bench.csv has no rows")
    write_csv(exp / "fit.csv", ["image", "photos fitted", "cycles simulated", "wall s", "simulations", "kg",
                                "kg standard error", "relative error of kg (true 0.8)", "P mean"],
              [[f"{r['width']}x{r['height']}", int(r["photos"]), int(r["cycles"]), float(r["wall_s"]),
                r["simulations"], float(r["kg"]), r["kg_se"], float(r["rel_error"]), r["P_mean"]] for r in fit])
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.4))
    for kind, label in methods:
        pts = [(p[(kind, w)][0], p[(kind, w)][1], w) for w in widths if (kind, w) in p and p[(kind, w)][1]]
        if pts:
            ax1.loglog([t for t, _, _ in pts], [e for _, e, _ in pts], "o-", label=label)
            for t, e, w in pts:
                ax1.annotate(f"{w}", (t, e), fontsize=7)
    ax1.set_xlabel("median ms per P (image width annotated)")
    ax1.set_ylabel("|P - closed form|")
    ax1.set_title("P measure (Eq. 8.1): time against error", fontsize=10)
    ax1.grid(True, which="both", alpha=0.3)
    ax1.legend(fontsize=8)
    physics_bench_summary.plot_time_error(ax2, phys)
    fig.tight_layout()
    fig.savefig(exp / "module_studies.png", dpi=100)
    plt.close(fig)
    # Verdict: the cheapest method per target error, and the solver's convergence order.
    big = widths[-1]
    raster_t, raster_e = p.get(("RasterP", big), (None, None))
    exact_t, exact_e = p.get(("ContourExactP", big), (None, None))
    orders = {case: [r["order"] for r in phys if r["case"] == case and r.get("order") is not None]
              for case in ("NeumannStefan", "ShrinkingSphere")}
    order_txt = "; ".join(f"{case} observed order {statistics.median(o):.2f} (median over {len(o)} refinements)"
                          for case, o in orders.items() if o)
    ratios = [r[5] for r in s_rows if r[5] is not None and r[1] == 1]
    most_photos = max(int(r["photos"]) for r in fit)
    full_fits = [r for r in fit if int(r["photos"]) == most_photos]
    fit_txt = "fit of kg: " + ", ".join(
        f"{float(r['rel_error']):.2%} error in {float(r['wall_s']):.0f} s at {r['width']}x{r['height']}"
        for r in sorted(full_fits, key=lambda r: -int(r["width"])))
    write_fragment(exp, {
        "tables": [{"caption": "P of two discs against its closed form, per image size and method", "csv": "p_measure.csv"},
                   {"caption": "Silhouette of the giraffe mold (10.8k triangles): meltlab and the OpenCV peer",
                    "csv": "silhouette.csv"},
                   {"caption": "Reference solver: grid spacing, run time, error against the closed form",
                    "csv": "physics.csv"},
                   {"caption": "meltlab fit of kg + registration (giraffe mold, inverse crime, true kg 0.8): "
                               "photo resolution and simulated cycles against time and accuracy", "csv": "fit.csv"}],
        "figures": [{"caption": "Time against error: the P measure (left) and the reference solver (right)",
                     "png": "module_studies.png", "data": "p_measure.csv"},
                    {"caption": "meltlab fit: wall time against the relative error of kg",
                     "png": "fit/fit_bench.png", "data": "fit.csv"}],
        "matches": bool(orders["NeumannStefan"] or orders["ShrinkingSphere"]),
        "verdict": (f"At {big}x{big * 3 // 4}, P from raster pixels costs {raster_t:.2f} ms for an error of {raster_e:.1e}, "
                    f"from exact polygons {exact_t:.1f} ms for {exact_e:.1e}; "
                    + (f"silhouettes {min(ratios):.2f}-{max(ratios):.2f}x the speed of the OpenCV peer; " if ratios else "")
                    + order_txt + "; " + fit_txt + ". An own study: the sources give no error budget."),
        "source_hardware": MONOGRAPH_NONE,
    })
