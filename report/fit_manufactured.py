#!/usr/bin/python3
"""Fits the empirical model to the manufactured physics-based sequences (issue 5): for each
sequence of scripts/manufacture-set, `meltlab fit` of kg, the time scale (cycles per photo),
the registration and optionally kl parameters on the first N photos (the rest are held out
and predicted), then a table of the fitted values with standard errors, P over the fitted
photos and over the held-out ones, and one figure of the P curves.

Usage: report/fit_manufactured.py MELTLAB SET_DIR OUT_DIR [--fit-photos N] [--kl FILE] [--fit-extra kn,kl.NAME,...] [--bound NAME=LO:HI]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time

MESHES = ["giraffe", "airplane", "ship", "warship", "bunny00"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("meltlab")
    ap.add_argument("set_dir")
    ap.add_argument("out_dir")
    ap.add_argument("--fit-photos", type=int, default=100)
    ap.add_argument("--kl", default=None)
    ap.add_argument("--fit-extra", "--fit-kl", dest="fit_extra", default="",
                    help="more parameters to fit besides kg, K and the registration: kn, kl.<path in --kl>")
    ap.add_argument("--bound", action="append", default=[], help="passed to meltlab fit: name=lower:upper (repeatable)")
    ap.add_argument("--cycles-per-photo", type=float, default=8.0, help="start value of the time scale")
    ap.add_argument("--meshes", default=",".join(MESHES))
    a = ap.parse_args()
    os.makedirs(a.out_dir, exist_ok=True)
    rows = []
    curves = {}
    for mesh in a.meshes.split(","):
        seq = os.path.join(a.set_dir, mesh)
        manifest = os.path.join(seq, "manifest.yaml")
        if not os.path.exists(manifest):
            print(f"fit_manufactured: {manifest}: missing (run scripts/manufacture-set)", file=sys.stderr)
            return 1
        n_photos = sum(1 for _ in os.scandir(os.path.join(seq, "frames")))
        holdout = max(0.0, 1.0 - a.fit_photos / n_photos)
        fit_dir = os.path.join(a.out_dir, mesh)
        free = "kg,cycles_per_photo,reg" + ("," + a.fit_extra if a.fit_extra else "")
        cmd = [a.meltlab, "fit", "--mesh", os.path.join(seq, "truth", "initial_mesh.ply"), "--observations", manifest,
               "--fit", free, "--cycles-per-photo", str(a.cycles_per_photo), "--holdout", f"{holdout:.6f}",
               "--overlay-every", "25", "--out", fit_dir, "--overwrite"]
        if a.kl:
            cmd += ["--kl", a.kl]
        for b in a.bound:
            cmd += ["--bound", b]
        print(f"== fit {mesh}: {' '.join(cmd[1:])}", flush=True)
        t0 = time.time()
        with open(os.path.join(a.out_dir, mesh + ".log"), "w") as log:
            r = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT)
        if r.returncode != 0:
            print(f"fit_manufactured: fit of {mesh} failed (exit {r.returncode}), see {mesh}.log", file=sys.stderr)
            rows.append({"mesh": mesh, "error": f"exit {r.returncode}"})
            continue
        j = json.load(open(os.path.join(fit_dir, "fit.json")))
        p_rows = list(csv.DictReader(open(os.path.join(fit_dir, "comparison", "per_frame.csv"))))
        p_key = "P" if "P" in p_rows[0] else [k for k in p_rows[0] if k.lower().startswith("p")][0]
        ps = [float(x[p_key]) for x in p_rows if x[p_key] not in ("", "nan")]
        fitted = ps[: a.fit_photos]
        held = ps[a.fit_photos:]
        curves[mesh] = ps
        e = j["estimates"]
        row = {"mesh": mesh, "photos": len(ps), "wall_s": round(time.time() - t0, 1),
               "simulations": j.get("simulations"), "iterations": j.get("iterations")}
        for name in free.split(","):
            if name == "reg":
                continue
            row[name] = e[name]["value"]
            row[name + "_se"] = e[name]["standard_error"]
        row["corr_kg_K"] = j["correlation"][j["free"].index("kg")][j["free"].index("cycles_per_photo")]
        row["P1"] = ps[0]
        row["P100"] = ps[min(99, len(ps) - 1)]
        row["P_fit_mean"] = sum(fitted) / len(fitted)
        row["P_fit_max"] = max(fitted)
        row["P_held_mean"] = sum(held) / len(held) if held else None
        row["P_held_max"] = max(held) if held else None
        rows.append(row)
        print(f"   {row}", flush=True)
    keys = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    with open(os.path.join(a.out_dir, "fit_manufactured.csv"), "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(rows)
    print()
    print(f"Empirical model fitted to the physics-based sequences (first {a.fit_photos} photos; the rest held out)")
    print(f"{'mesh':>9} {'kg':>15} {'K [cyc/photo]':>15} {'P1':>6} {'P100':>6} {'P fit max':>9} {'P held max':>10} {'sims':>5} {'s':>6}")
    for r in rows:
        if "error" in r:
            print(f"{r['mesh']:>9} failed: {r['error']}")
            continue
        hm = r["P_held_max"]
        print(f"{r['mesh']:>9} {r['kg']:7.4f}±{r['kg_se'] or 0:6.4f} {r['cycles_per_photo']:7.3f}±{r['cycles_per_photo_se'] or 0:6.3f} "
              f"{r['P1']:6.3f} {r['P100']:6.3f} {r['P_fit_max']:9.3f} {hm if hm is not None else float('nan'):10.3f} "
              f"{r['simulations']:5d} {r['wall_s']:6.0f}")
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return 0
    fig, ax = plt.subplots(figsize=(7, 4))
    for mesh, ps in curves.items():
        ax.plot(range(1, len(ps) + 1), ps, label=mesh)
    ax.axvline(a.fit_photos + 0.5, color="gray", ls=":", lw=1)
    ax.axhline(0.2, color="red", ls="--", lw=1, label="acceptance P = 0.2")
    ax.set_xlabel("photo")
    ax.set_ylabel("P")
    ax.set_title("Fitted empirical model against the physics-based sequences")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(os.path.join(a.out_dir, "fit_manufactured_p.png"), dpi=120)
    return 0 if all("error" not in r for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
