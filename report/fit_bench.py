#!/usr/bin/python3
"""Benchmark of `meltlab fit` (issue 5): a full fit of one 100-photo sequence, its wall time
and simulations, and the time against the accuracy of the fitted kg when the photos' resolution
or the model's cycle count is reduced.

The sequence is an inverse crime with known truth (the giraffe mold melted with kg = 0.8,
a photo every 7 cycles as in the monograph, noise, blur, JPEG, a misaligned camera). Each row
fits kg and the registration:
  * resolution rows: the same melt photographed at 2048x1536 ... 320x240;
  * cycle rows: fewer simulated cycles per evaluation, by fitting only the first 50 or 25
    photos (350 or 175 of the 700 cycles; the rest is not simulated).
Writes DIR/fit_bench.csv and DIR/fit_bench.png and prints the table.

Usage: report/fit_bench.py MELTLAB_BINARY DIR [--quick | --full]   (--full: the default)
"""
import csv
import json
import os
import sys
import time

from script_args import meltlab_out_quick, run

TRUE_KG = 0.8
K = 7.0


def main(argv):
    args = meltlab_out_quick(argv, __doc__)
    if args is None:
        return 2
    meltlab, out, quick = args
    photos = 30 if quick else 100
    os.makedirs(out, exist_ok=True)
    sizes = [(2048, 1536), (1024, 768), (640, 480), (320, 240)]
    if quick:
        sizes = [(640, 480), (320, 240)]
    rows = []
    for (w, h) in sizes:
        seq = os.path.join(out, f"seq_{w}")
        if not os.path.exists(os.path.join(seq, "manifest.yaml")):
            run([meltlab, "synth-sequence", "--mesh", "giraffe", "--kg", str(TRUE_KG), "--photos", str(photos),
                 "--cycles-per-photo", str(K), "--width", str(w), "--height", str(h),
                 "--misalign", "5,-3,0.8,1", "--seed", "5", "--out", seq, "--overwrite"],
                os.path.join(out, f"synth_{w}.log"))
        fractions = [1.0] if (w, h) != (1024, 768) and not (quick and w == 640) else [1.0, 0.5, 0.25]
        for f in fractions:
            n_fit = max(2, round(photos * f))
            name = f"fit_{w}_n{n_fit}"
            fit_dir = os.path.join(out, name)
            t0 = time.time()
            run([meltlab, "fit", "--mesh", "giraffe", "--observations", os.path.join(seq, "manifest.yaml"),
                 "--cycles-per-photo", str(K), "--fit", "kg,reg", "--kg", "0.5",
                 "--holdout", f"{1.0 - n_fit / photos:.6f}", "--overlay-every", "0",
                 "--out", fit_dir, "--overwrite"], os.path.join(out, name + ".log"))
            wall = time.time() - t0
            j = json.load(open(os.path.join(fit_dir, "fit.json")))
            kg = j["estimates"]["kg"]["value"]
            melt_per_photo = kg  # the truth is kg at the photos' own time scale
            rows.append({
                "photos": n_fit, "width": w, "height": h, "cycles": round(n_fit * K),
                "wall_s": round(wall, 2), "fit_time_s": round(j.get("time_s", wall), 2),
                "simulations": j.get("simulations"), "iterations": j.get("iterations"),
                "kg": kg, "kg_se": j["estimates"]["kg"].get("standard_error"),
                "rel_error": abs(melt_per_photo - TRUE_KG) / TRUE_KG,
                "P_mean": j.get("comparison", {}).get("P_mean"),
            })
            print(f"{name}: {rows[-1]}", flush=True)
    with open(os.path.join(out, "fit_bench.csv"), "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=list(rows[0].keys()))
        wr.writeheader()
        wr.writerows(rows)
    print()
    print(f"Fit of kg + registration, giraffe mold (true kg {TRUE_KG}, {K:g} cycles per photo)")
    print(f"{'image':>10} {'photos':>6} {'cycles':>6} {'wall s':>7} {'sims':>5} {'iter':>4} {'kg':>8} {'± se':>8} {'rel.err':>8} {'P mean':>7}")
    for r in rows:
        pm = r["P_mean"]
        print(f"{r['width']}x{r['height']:<4} {r['photos']:6d} {r['cycles']:6d} {r['wall_s']:7.1f} {r['simulations'] or 0:5d} "
              f"{r['iterations'] or 0:4d} {r['kg']:8.4f} {r['kg_se'] or 0:8.5f} {r['rel_error']:8.2%} {pm if pm is not None else float('nan'):7.4f}")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return 0
    fig, ax = plt.subplots(figsize=(6, 4))
    res = [r for r in rows if r["photos"] == photos]
    cyc = [r for r in rows if r["width"] == (640 if quick else 1024)]
    ax.loglog([r["wall_s"] for r in res], [max(r["rel_error"], 1e-5) for r in res], "o-", label="image resolution")
    for r in res:
        ax.annotate(f"{r['width']}", (r["wall_s"], max(r["rel_error"], 1e-5)), fontsize=7)
    ax.loglog([r["wall_s"] for r in cyc], [max(r["rel_error"], 1e-5) for r in cyc], "s--", label="simulated cycles")
    for r in cyc:
        ax.annotate(f"{r['cycles']} cycles", (r["wall_s"], max(r["rel_error"], 1e-5)), fontsize=7)
    ax.set_xlabel("fit wall time [s]")
    ax.set_ylabel("relative error of the melt rate")
    ax.set_title(f"meltlab fit: time against accuracy ({photos} photos)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(os.path.join(out, "fit_bench.png"), dpi=120)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
