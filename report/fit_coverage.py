#!/usr/bin/python3
"""Coverage of the fit's standard errors (issue 19).

Independent noisy photo sequences of the empirical model with a known kg (`meltlab
synth-sequence`: anti-aliased silhouettes as bright ice on a textured ground, uneven light,
blur, sensor noise, JPEG), differing in mesh, image size, seed, true kg, number of photos and
camera misalignment, each fitted with `meltlab fit` (kg, and the registration where the camera
is misaligned). Per sequence: the error of kg against the truth, and how many of each kind of
standard error it is (fit.json: Ceres' covariance; the per-photo clustered one; the total, the
clustered one and the estimated segmentation bias together). Coverage = the fraction of
sequences whose truth lies within +-1.96 standard errors; the goal for an honest error is
90-98 %.

Usage: report/fit_coverage.py MELTLAB DIR [--quick | --full]
  --quick: 4 sequences (the quick report); --full (default): 24.
Writes DIR/coverage.csv (one row per sequence), DIR/coverage.json (the fractions) and prints
the table. A sequence folder that already holds a finished fit is reused.
"""
import csv
import json
import math
import os
import sys
import time

from script_args import meltlab_out_quick, run

# mesh, cycles simulated over the photos at kg = 0.8 (about half of its melt: icosphere_3
# melts in 1057 cycles at kg 0.8, torus 466, benchmark_a 146, dumbbell 1368, airplane 2216,
# giraffe 1984), whether the camera is misaligned (then the registration is fitted too).
MESHES = [
    ("icosphere_3", 560, False),
    ("torus", 240, False),
    ("airplane", 640, True),
    ("benchmark_a", 80, False),
    ("dumbbell", 700, False),
    ("giraffe", 700, True),
]
# The dumbbell splits in two halfway through: its photos keep every component (the default
# keeps the largest one only, half of the ice once it has split).
SEGMENTATION = {"dumbbell": "segmentation: {largest_component: false}\n"}
SIZES = [(320, 240), (480, 360), (640, 480)]
TRUE_KG = [0.8, 0.6, 0.9, 0.7]
PHOTOS = [8, 12]


def cases(n):
    """n sequences cycling through meshes, sizes, true kg and photo counts (deterministic)."""
    out = []
    for i in range(n):
        mesh, span, misalign = MESHES[i % len(MESHES)]
        w, h = SIZES[(i // len(MESHES) + i) % len(SIZES)]
        kg = TRUE_KG[(i // 2) % len(TRUE_KG)]
        photos = PHOTOS[(i // 3) % len(PHOTOS)]
        # The same share of the melt whatever the true kg: cycles scale with 0.8 / kg.
        k = round(span / photos * 0.8 / kg, 3)
        out.append({"name": f"seq{i:02d}_{mesh}_{w}", "mesh": mesh, "width": w, "height": h, "kg": kg,
                    "photos": photos, "cycles_per_photo": k, "seed": 101 + i, "misalign": misalign})
    return out


def covered(err, se):
    return None if se is None or not se > 0 else abs(err) <= 1.96 * se


def main(argv):
    args = meltlab_out_quick(argv, __doc__)
    if args is None:
        return 2
    meltlab, out, quick = args
    n = 4 if quick else 24
    os.makedirs(out, exist_ok=True)
    rows = []
    for c in cases(n):
        seq = os.path.join(out, c["name"], "photos")
        fit = os.path.join(out, c["name"], "fit")
        t0 = time.time()
        os.makedirs(os.path.join(out, c["name"]), exist_ok=True)
        if not os.path.exists(os.path.join(seq, "manifest.yaml")):
            cmd = [meltlab, "synth-sequence", "--mesh", c["mesh"], "--kg", str(c["kg"]), "--photos", str(c["photos"]),
                   "--cycles-per-photo", str(c["cycles_per_photo"]), "--width", str(c["width"]),
                   "--height", str(c["height"]), "--seed", str(c["seed"]), "--out", seq, "--overwrite"]
            if c["misalign"]:
                cmd += ["--misalign", "4,-3,0.6,1"]
            run(cmd, os.path.join(out, c["name"], "synth.log"))
            if c["mesh"] in SEGMENTATION:
                with open(os.path.join(seq, "manifest.yaml"), "a") as fh:
                    fh.write(SEGMENTATION[c["mesh"]])
        if not os.path.exists(os.path.join(fit, "fit.json")):
            run([meltlab, "fit", "--mesh", c["mesh"], "--observations", os.path.join(seq, "manifest.yaml"),
                 "--cycles-per-photo", str(c["cycles_per_photo"]), "--fit", "kg,reg" if c["misalign"] else "kg",
                 "--kg", "0.5", "--overlay-every", "0", "--out", fit, "--overwrite"],
                os.path.join(out, c["name"], "fit.log"))
        wall = time.time() - t0
        j = json.load(open(os.path.join(fit, "fit.json")))
        e = j["estimates"]["kg"]
        err = e["value"] - c["kg"]
        se, sc, bias = e.get("standard_error"), e.get("standard_error_clustered"), e.get("segmentation_bias")
        total = e.get("standard_error_total")
        rows.append({
            "sequence": c["name"], "mesh": c["mesh"], "width": c["width"], "height": c["height"],
            "photos": c["photos"], "registration": c["misalign"], "kg_true": c["kg"], "kg": e["value"],
            "error": err, "se_ceres": se, "se_clustered": sc, "segmentation_bias": bias, "se_total": total,
            "z_ceres": err / se if se else None, "z_clustered": err / sc if sc else None,
            "z_total": err / total if total else None,
            "covered_ceres": covered(err, se), "covered_clustered": covered(err, sc),
            "covered_total": covered(err, total),
            "simulations": j.get("simulations"), "wall_s": round(wall, 1),
        })
        r = rows[-1]
        print(f"{r['sequence']:28s} kg {r['kg']:.5f} (truth {r['kg_true']}) error {err:+.5f}  se {se or 0:.5f} "
              f"clustered {sc or 0:.5f} bias {bias if bias is not None else float('nan'):+.5f} "
              f"total {total or 0:.5f}  {wall:.0f} s", flush=True)
    with open(os.path.join(out, "coverage.csv"), "w", newline="") as fh:
        wr = csv.DictWriter(fh, fieldnames=list(rows[0].keys()))
        wr.writeheader()
        wr.writerows(rows)

    def frac(key):
        vals = [r[key] for r in rows if r[key] is not None]
        return (sum(vals) / len(vals), len(vals)) if vals else (None, 0)

    summary = {"sequences": len(rows)}
    for kind in ("ceres", "clustered", "total"):
        f, m = frac(f"covered_{kind}")
        summary[f"coverage_{kind}"] = f
        summary[f"counted_{kind}"] = m
    errs = [r["error"] for r in rows]
    summary["mean_error"] = sum(errs) / len(errs)
    summary["rms_error"] = math.sqrt(sum(x * x for x in errs) / len(errs))
    summary["mean_relative_error"] = sum(r["error"] / r["kg_true"] for r in rows) / len(rows)
    # The bias: the mean error in units of the statistical (clustered) error, and whether the
    # estimated segmentation bias would have corrected it (the mean |error| with and without).
    zc = [r["z_clustered"] for r in rows if r["z_clustered"] is not None]
    summary["mean_z_clustered"] = sum(zc) / len(zc) if zc else None
    corr = [r for r in rows if r["segmentation_bias"] is not None]
    summary["mean_abs_error"] = sum(abs(r["error"]) for r in rows) / len(rows)
    summary["mean_abs_error_corrected"] = (sum(abs(r["error"] - r["segmentation_bias"]) for r in corr) / len(corr)
                                           if corr else None)
    summary["mean_abs_segmentation_bias"] = (sum(abs(r["segmentation_bias"]) for r in corr) / len(corr)
                                             if corr else None)
    summary["wall_s"] = sum(r["wall_s"] for r in rows)
    for kind in ("ceres", "clustered", "total"):
        z = [r[f"z_{kind}"] for r in rows if r[f"z_{kind}"] is not None]
        summary[f"rms_z_{kind}"] = math.sqrt(sum(x * x for x in z) / len(z)) if z else None
    with open(os.path.join(out, "coverage.json"), "w") as fh:
        json.dump(summary, fh, indent=2)
    print(json.dumps(summary, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
