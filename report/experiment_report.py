#!/usr/bin/python3
"""The report step of each `meltlab reproduce` experiment: reads the experiment's result
files, writes the numbers as CSV (the harness's beside the source's), draws what the
earlier steps did not, and writes EXP_DIR/report.json, the fragment that
report/build_report.py puts into the HTML report.

usage: experiment_report.py KIND EXP_DIR [ARGS...]
KIND: tab_2_3 | cycle_time CYCLES | deform_variants | split | kl_field | chapter8 MOLD | fit | physics_fit MOLD |
      melt_away | liquid_figure | melt_scene | texture_filter FACTOR | stress_summary |
      module_studies | runs (generic: every simulate run folder in EXP_DIR)

report.json: {"tables": [{"caption", "csv"}], "figures": [{"caption", "png", "data"}],
"verdict": str, "matches": bool|null, "notes": [str], "source_hardware": str, "extra": {...}}
(paths relative to EXP_DIR). The numbers the monograph reports are quoted from the spec
(spec/melting-monograph.md), section given in each table's caption.
"""
import csv
import json
import math
import os
import statistics
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

MONOGRAPH_CPU = "Intel Core 2 Duo P8400 (2.26 GHz), nVidia GeForce 9600M GT (spec §6.5)"
MONOGRAPH_PHOTO = ("Nikon Coolpix 995, 2048x1536, photo every 40 s, ice ~250 g at -10 °C, air 25-35 °C; "
                   "contours traced in Adobe Photoshop (spec §9.2)")
MONOGRAPH_NONE = "not stated (qualitative figure)"


def write_csv(path: Path, header, rows):
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(path.name + ".partial")
    with open(tmp, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in rows:
            w.writerow(["" if v is None else (f"{v:.6g}" if isinstance(v, float) else v) for v in r])
    os.replace(tmp, path)


def write_fragment(exp: Path, fragment):
    for t in fragment.get("tables", []):
        assert (exp / t["csv"]).is_file(), t["csv"]
    for fg in fragment.get("figures", []):
        assert (exp / fg["png"]).is_file(), fg["png"]
    tmp = exp / "report.json.partial"
    tmp.write_text(json.dumps(fragment, indent=2) + "\n")
    os.replace(tmp, exp / "report.json")
    print(f"{exp / 'report.json'}: {fragment['verdict']}")


def load_run(run_dir: Path):
    run = json.loads((run_dir / "run.json").read_text())
    with open(run_dir / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    return run, rows


def fmt_bool(b):
    return "yes" if b else "no"


# ------------------------------------------------------------------ Tab. 2.3
TAB_2_3 = [  # name, label, V, E, F, H, S, G, chi (spec §2.2)
    ("cube_quads", "cube of quads", 8, 12, 6, 0, 1, 0, 0),
    ("cube_triangles", "cube of triangles", 8, 18, 12, 0, 1, 0, 0),
    ("double_cube_quads", "double cube of quads", 16, 24, 12, 0, 2, 0, 0),
    ("cube_with_face_hole", "cube with a hole in a face", 16, 24, 11, 1, 1, 0, 0),
    ("cube_with_tunnel", "cube with a tunnel", 16, 24, 10, 2, 1, 1, 0),
    ("cube_with_tunnel_front_triangulated", "cube with a tunnel, front triangulated", 16, 32, 17, 1, 1, 1, 0),
]


def tab_2_3(exp: Path, _args):
    rows, exact, chi_ok = [], 0, 0
    keys = ["V", "E", "F", "H", "S", "G", "chi"]
    # Counts of the polygon forms (faces with hole loops; `meltlab dataset euler`), validity of
    # the stored meshes (`meltlab mesh-info`).
    polygon_forms = json.loads((exp / "mesh_info" / "polygon_forms.json").read_text())
    for name, label, *ref in TAB_2_3:
        info = json.loads((exp / "mesh_info" / f"{name}.json").read_text())
        ours = [polygon_forms[name][k] for k in keys]
        same = ours == ref
        exact += same
        chi_ok += polygon_forms[name]["chi"] == 0 and info["valid"]
        rows.append([label] + ours + ref + [fmt_bool(same), fmt_bool(info["valid"])])
    header = (["mesh"] + [f"{k} meltlab" for k in keys] + [f"{k} monograph" for k in keys]
              + ["identical", "valid (closed, manifold, oriented)"])
    write_csv(exp / "tab_2_3.csv", header, rows)
    n = len(TAB_2_3)
    write_fragment(exp, {
        "tables": [{"caption": "Tab. 2.3: V E F H S G and χ (Eq. 2.3) of the example meshes; monograph values from spec §2.2",
                    "csv": "tab_2_3.csv"}],
        "figures": [],
        "matches": chi_ok == n and exact == n,
        "verdict": (f"χ = 0 and valid for {chi_ok}/{n} meshes; all counts identical for {exact}/{n}. "
                    "Counts are those of the polygon forms (faces with hole loops, `meltlab dataset euler`); the "
                    "catalog stores the meshes with a face hole or a tunnel triangulated for melting (no file "
                    "format keeps polygons with holes), and mesh-info checks those stored meshes' validity."),
        "source_hardware": MONOGRAPH_NONE,
    })


# ------------------------------------------------------------------ Tab. 5.1
def cycle_time(exp: Path, args):
    cycles = int(args[0]) if args else 0
    rows = list(csv.DictReader(open(exp / "figures" / "cycle_time.csv")))
    by = {r["object"]: r for r in rows}
    out, ratio = [], {}
    for obj, tri0, cpu, gpu in (("A", 192, "< 1", 4.0), ("B", 16000, 5.8, 4.6), ("C", 32000, 20.0, 6.0)):
        r = by.get(obj)
        if r is None and (exp / f"object_{obj.lower()}" / "run.json").is_file():
            run, st = load_run(exp / f"object_{obj.lower()}")
            ms = [float(x["ms"]) for x in st[1:]]  # cycle 0 has no time
            r = {"mean_ms": statistics.fmean(ms), "median_ms": statistics.median(ms),
                 "initial_triangles": run["mesh"]["triangles"]}
        if r is None:
            out.append([obj, tri0, None, None, None, cpu, gpu, None, "not run"])
            continue
        run, _ = load_run(exp / f"object_{obj.lower()}")
        mean = float(r["mean_ms"])
        ratio[obj] = cpu / mean if isinstance(cpu, float) else math.nan
        out.append([obj, tri0, int(r["initial_triangles"]), run["cycles_run"], mean, cpu, gpu, ratio[obj],
                    f"{run['status']}, median {float(r['median_ms']):.3f} ms"])
    write_csv(exp / "tab_5_1.csv",
              ["object", "monograph initial triangles", "meltlab initial triangles", "meltlab cycles", "meltlab mean ms",
               "monograph CPU ms", "monograph GPU ms", "monograph CPU / meltlab", "note"], out)
    # Target 13 of the spec: time per cycle proportional to the live triangles (Fig. 5.7).
    # Per-cycle times are noisy on a shared machine, so the test uses the medians of bins of
    # 1000 triangles: R^2 of their linear fit and a positive slope.
    _, rows_c = load_run(exp / "object_c")
    bins = {}
    for r in rows_c[1:]:
        bins.setdefault(int(r["triangles"]) // 1000, []).append(float(r["ms"]))
    xs = [k * 1000 + 500 for k in sorted(bins)]
    ys = [statistics.median(bins[k]) for k in sorted(bins)]
    r2, slope = math.nan, math.nan
    if len(xs) >= 3:
        mx, my = statistics.fmean(xs), statistics.fmean(ys)
        sxx = sum((x - mx) ** 2 for x in xs)
        slope = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx
        icept = my - slope * mx
        ss_res = sum((y - icept - slope * x) ** 2 for x, y in zip(xs, ys))
        ss_tot = sum((y - my) ** 2 for y in ys)
        r2 = 1 - ss_res / ss_tot if ss_tot > 0 else math.nan
    write_csv(exp / "fig_5_7_bins.csv", ["triangles (bin centre)", "median ms"], list(zip(xs, ys)))
    linear = slope > 0 and r2 >= 0.9
    mean_b = float(by["B"]["mean_ms"]) if "B" in by else math.nan
    mean_c = float(by["C"]["mean_ms"]) if "C" in by else math.nan
    write_fragment(exp, {
        "tables": [{"caption": "Tab. 5.1: mean time per cycle, one core, float (monograph: spec §6.5)", "csv": "tab_5_1.csv"},
                   {"caption": "Per-run statistics and the linear fit of Fig. 5.7", "csv": "figures/cycle_time.csv"},
                   {"caption": "Fig. 5.7 in bins of 1000 remaining triangles (median ms)", "csv": "fig_5_7_bins.csv"}],
        "figures": [{"caption": "Fig. 5.6: object B, time per cycle over the run", "png": "figures/fig_5_6.png",
                     "data": "object_b/stats.csv"},
                    {"caption": "Fig. 5.7: object C, time per cycle against remaining triangles", "png": "figures/fig_5_7.png",
                     "data": "object_c/stats.csv"}],
        "matches": linear,
        "verdict": (f"Cost linear in the remaining triangles (spec target 13): "
                    f"{'yes' if linear else 'no'} (binned R² {r2:.3f}, {slope * 1000:.4f} ms per 1000 triangles). "
                    f"Absolute times differ with the hardware: this CPU is {ratio.get('B', math.nan):.0f}x (B) and "
                    f"{ratio.get('C', math.nan):.0f}x (C) faster than the 2009 P8400; C/B mean ratio "
                    f"{mean_c / mean_b:.2f} here against 3.45 in Tab. 5.1 (2x the triangles). "
                    + (f"Quick mode: only the first {cycles} cycles, so the means weigh the larger early meshes."
                       if cycles and cycles < 20000 else "")),
        "source_hardware": MONOGRAPH_CPU,
    })


# ------------------------------------------------------------------ Figs. 3.1 / 3.5
def deform_variants(exp: Path, _args):
    table, series = [], {}
    for name in ("normal_only", "combined"):
        run, rows = load_run(exp / name)
        ch = run["checks"]
        inter = ch["intersections"]
        series[name] = ([i["cycle"] for i in inter], [i["intersecting_pairs"] for i in inter])
        last = rows[-1]
        table.append([name, run["parameters"]["deform"], run["status"], run["cycles_run"],
                      ch["first_self_intersection_cycle"], max(series[name][1]) if inter else None,
                      float(last["Qd"]), float(last["max_d"]), float(last["volume"]) / float(rows[0]["volume"])])
    write_csv(exp / "deform_variants.csv",
              ["run", "deform", "status", "cycles", "first self-intersection cycle", "max intersecting pairs",
               "Qd at end (deg)", "max d at end (deg)", "volume left"], table)
    write_csv(exp / "intersections.csv", ["run", "cycle", "intersecting_pairs"],
              [[n, c, p] for n, (cs, ps) in series.items() for c, p in zip(cs, ps)])
    fig, ax = plt.subplots(figsize=(7, 3.6), constrained_layout=True)
    for n, (cs, ps) in series.items():
        ax.plot(cs, ps, marker="o", label=n)
    ax.axvline(1500, color="k", ls=":", label="monograph: escaping triangles by cycle 1500")
    ax.set_xlabel("cycle")
    ax.set_ylabel("self-intersecting triangle pairs")
    ax.set_yscale("symlog")
    ax.legend(fontsize=8)
    fig.savefig(exp / "intersections.png", dpi=110)
    plt.close(fig)
    n_first, c_first = table[0][4], table[1][4]
    every = load_run(exp / "normal_only")[0]["checks"]["intersections_every"]
    normal_fails = n_first is not None and n_first >= 0
    combined_clean = c_first is None or c_first < 0
    write_fragment(exp, {
        "tables": [{"caption": "M_N only (Fig. 3.1) against Eq. 3.6 (Fig. 3.5), 1600 cycles", "csv": "deform_variants.csv"}],
        "figures": [{"caption": "Self-intersecting pairs (CGAL) over the run", "png": "intersections.png",
                     "data": "intersections.csv"},
                    {"caption": "Fig. 3.1 analogue: M_N only, top views of cycles 0/800/1600",
                     "png": "normal_only/snapshots.png", "data": "normal_only/stats.csv"},
                    {"caption": "Fig. 3.5 analogue: combined vector, top views of cycles 0/800/1600",
                     "png": "combined/snapshots.png", "data": "combined/stats.csv"}],
        "matches": normal_fails and combined_clean,
        "verdict": (f"Self-intersections (CGAL) checked every {every} cycles. "
                    f"M_N only: first found at cycle {n_first}, up to {table[0][5]} intersecting pairs "
                    f"(monograph: escaping triangles by cycle 1500); combined (Eq. 3.6): "
                    + ("none. Matches the monograph's claim." if combined_clean else
                       f"first at cycle {c_first}, up to {table[1][5]} pairs. The M_N-only failure is reproduced "
                       "(earlier and larger), but the combined vector is not free of self-intersections on this "
                       "mesh, against the monograph's claim that M_E causes no mesh errors.")),
        "source_hardware": MONOGRAPH_NONE,
    })


# ------------------------------------------------------------------ split
def split(exp: Path, _args):
    run, rows = load_run(exp / "dumbbell")
    comps = [(int(r["cycle"]), int(r["components"])) for r in rows]
    first_two = next((c for c, s in comps if s >= 2), None)
    before = max((c for c, s in comps if s < 2 and (first_two is None or c < first_two)), default=None)
    chi_bad = sum(1 for r in rows if int(r["euler"]) != 0) if "euler" in rows[0] else None
    ch = run["checks"]
    table = [[run["status"], run["cycles_run"], first_two, before, max(s for _, s in comps), ch["topology_every"],
              ch["topology_checks"], chi_bad]]
    write_csv(exp / "split.csv", ["status", "cycles", "first cycle with S >= 2", "last cycle with S = 1 before it",
                                  "max components", "topology check every", "topology checks passed",
                                  "rows with chi != 0"], table)
    ok = first_two is not None and run["status"] in ("ok", "melted", "completed") and chi_bad in (0, None)
    write_fragment(exp, {
        "tables": [{"caption": "The split (Fig. 3.8): components S per cycle, χ = 0 kept per part", "csv": "split.csv"}],
        "figures": [{"caption": "Volume, triangles, components and cycle time", "png": "dumbbell/summary.png",
                     "data": "dumbbell/stats.csv"},
                    {"caption": "Top views of the snapshots", "png": "dumbbell/snapshots.png", "data": "dumbbell/stats.csv"}],
        "matches": ok,
        "verdict": (f"The dumbbell splits at cycle {first_two} (S = 1 at cycle {before}); run status {run['status']}, "
                    f"{ch['topology_checks']} full topology checks passed, χ ≠ 0 in {chi_bad} rows. "
                    "The monograph shows the split over three consecutive cycles (Fig. 3.8) without numbers."),
        "source_hardware": MONOGRAPH_NONE,
    })


# ------------------------------------------------------------------ Fig. 3.10
def kl_field(exp: Path, _args):
    table = []
    for name in ("kl_field", "uniform"):
        run, rows = load_run(exp / name)
        v0 = float(rows[0]["volume"])
        table.append([name, run["status"], run["cycles_run"], float(rows[-1]["volume"]) / v0,
                      int(rows[0]["triangles"]), int(rows[-1]["triangles"]), max(int(r["components"]) for r in rows)])
    write_csv(exp / "kl_field.csv", ["run", "status", "cycles", "volume left", "triangles at start", "triangles at end",
                                     "max components"], table)
    write_fragment(exp, {
        "tables": [{"caption": "Giraffe mold with kl = max(point source, ground pressure) against kl = 1",
                    "csv": "kl_field.csv"}],
        "figures": [{"caption": "Fig. 3.10 analogue: kl field (heat source near the head + ground pressure), top views",
                     "png": "kl_field/snapshots.png", "data": "kl_field/stats.csv"},
                    {"caption": "The same block with kl = 1", "png": "uniform/snapshots.png", "data": "uniform/stats.csv"},
                    {"caption": "kl field run: volume, triangles, components, cycle time", "png": "kl_field/summary.png",
                     "data": "kl_field/stats.csv"}],
        "matches": None,
        "verdict": (f"Qualitative figure (the monograph gives no falloff or magnitudes): with kl ≤ 1 the block keeps "
                    f"{table[0][3]:.2f} of its volume against {table[1][3]:.2f} with kl = 1; compare the top views."),
        "source_hardware": MONOGRAPH_NONE,
    })


# ------------------------------------------------------------------ chapter 8
P_MONOGRAPH = {"giraffe": (0.068818, 0.137467), "airplane": (0.027969, 0.10399),
               "ship": (0.044926, 0.120915), "warship": (0.07131, 0.178187)}


def chapter8(exp: Path, args):
    mold = args[0]
    rows = list(csv.DictReader(open(exp / "p_curves.csv")))
    p1_ref, p100_ref = P_MONOGRAPH[mold]
    table, extra = [], {}
    for r in rows:
        p1, p100, pmax = float(r["P1"]), float(r["P100"]), float(r["P_max"])
        table.append([r["comparison"], p1, p1_ref, p100, p100_ref, pmax, float(r["P_mean"]), float(r["frac<=0.2"]),
                      r["skipped"], fmt_bool(pmax <= 0.2)])
        extra[r["comparison"]] = {"P1": p1, "P100": p100, "P_max": pmax}
    write_csv(exp / "p1_p100.csv", ["comparison", "P1 meltlab", "P1 monograph", "P100 meltlab", "P100 monograph",
                                    "P max", "P mean", "fraction P <= 0.2", "photos skipped", "P <= 0.2 throughout"],
              table)
    figures = [{"caption": f"Figs. 8.7-8.10 analogue ({mold}): P per photo; circles: the monograph's P1/P100",
                "png": "p_curves.png", "data": "p_curves.csv"}]
    for cmp_dir in ("compare_kg1", "compare_kg085"):
        for k in (1, 34, 67, 100):
            png = exp / cmp_dir / "overlays" / f"frame_{k:04d}.png"
            if png.is_file():
                figures.append({"caption": f"Fig. 8.12 analogue: {cmp_dir.replace('compare_', '')}, photo {k} "
                                           "(dark grey photo only, black render only, light grey common)",
                                "png": str(png.relative_to(exp)), "data": f"{cmp_dir}/per_frame.csv"})
    right, wrong = table[0], table[1]
    match = right[9] == "yes"
    write_fragment(exp, {
        "tables": [{"caption": f"P1 and P100 ({mold}); monograph values from spec §9.5", "csv": "p1_p100.csv"}],
        "figures": figures,
        "matches": match,
        "verdict": (f"Right kg: P1 {right[1]:.4f}, P100 {right[3]:.4f} (monograph {p1_ref} / {p100_ref}); "
                    f"P ≤ 0.2 throughout: {right[9]}. kg = 0.85: P100 {wrong[3]:.4f}. "
                    "Inverse-crime photos: P1 here measures camera misalignment + segmentation only, not the "
                    "mold/scan/optics errors behind the monograph's P1, so P is expected lower than the monograph's; "
                    "the wrong kg shows how P grows with cycles as in Figs. 8.7-8.10."),
        "source_hardware": MONOGRAPH_PHOTO,
        "extra": {"mold": mold, "p": extra},
    })


# ------------------------------------------------------------------ fit
def fit(exp: Path, _args):
    j = json.loads((exp / "fit" / "fit.json").read_text())
    rows = []
    for name, e in j["estimates"].items():
        rows.append([name, e.get("value"), e.get("standard_error"), (j.get("truth") or {}).get(name)])
    reg = j.get("registration", {})
    for k in ("tx_px", "ty_px", "angle_deg", "scale"):
        if k in reg:
            rows.append([f"registration {k}", reg[k], None, {"tx_px": 5, "ty_px": -3, "angle_deg": 0.8, "scale": 1}[k]])
    write_csv(exp / "fit.csv", ["parameter", "estimate", "standard error", "truth"], rows)
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
        "verdict": (f"kg = {kg['value']:.4f} ± {kg['standard_error']:.4f} (truth 0.8, error {100 * rel:.2f} %), "
                    f"{j.get('simulations')} simulations in {j.get('time_s', 0):.0f} s, P max of the fitted run "
                    f"{comp.get('P_max', math.nan):.4f}. No source value: the monograph chose kg by hand."),
        "source_hardware": MONOGRAPH_NONE,
    })


# ------------------------------------------------------------------ physics fit
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


# ------------------------------------------------------------------ melt away
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


# ------------------------------------------------------------------ chapter 7 (rendering)
def _montage(pngs, labels, out_png, title, cols):
    import matplotlib.image as mpimg
    rows_n = (len(pngs) + cols - 1) // cols
    fig, axes = plt.subplots(rows_n, cols, figsize=(3 * cols, 3 * rows_n * 0.8), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, png, label in zip(axes.flat, pngs, labels):
        ax.imshow(mpimg.imread(png), cmap="gray" if "mask" in png.name else None)
        ax.set_title(label, fontsize=9)
    fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    plt.close(fig)


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


def texture_filter(exp: Path, args):
    """The texture-lookup study: 1-ray frames (bilinear, mipmap) against the reference frame
    args[0] times larger, box-filtered down in linear radiance (display PNGs, gamma 2.2)."""
    import matplotlib.image as mpimg
    import numpy as np
    k = int(args[0]) if args else 8

    def last_frame(step):
        with open(exp / step / "frames.csv") as f:
            rows = list(csv.DictReader(f))
        pngs = sorted((exp / step / "frames").glob("frame_*.png"))
        if not rows or not pngs:
            raise SystemExit(f"experiment_report.py: {exp / step}: no frames")
        return np.asarray(mpimg.imread(pngs[-1]), dtype=np.float64)[..., :3], rows[-1], pngs[-1]

    ref_big, ref_row, _ = last_frame("reference")
    h, w = ref_big.shape[0] // k, ref_big.shape[1] // k
    ref_lin = (ref_big[:h * k, :w * k] ** 2.2).reshape(h, k, w, k, 3).mean(axis=(1, 3))
    ref = ref_lin ** (1 / 2.2)
    table, images = [], {}
    base_ms = None
    for step, label in (("bilinear", "bilinear, 1 ray/pixel"), ("mipmap", "MIP-mapped (OIIO TextureSystem), 1 ray/pixel")):
        img, row, png = last_frame(step)
        if img.shape != ref.shape:
            raise SystemExit(f"experiment_report.py: {png}: {img.shape} does not match the reference {ref.shape}")
        err = np.abs(img - ref)
        ms = float(row["trace_ms"])
        base_ms = base_ms or ms
        table.append([label, int(row["cycle"]), ms, ms / base_ms, float(np.sqrt((err ** 2).mean())),
                      float(np.percentile(err.max(axis=2), 99))])
        images[step] = (img, err)
    table.append([f"reference: {k}x{k} rays/pixel, bilinear", int(ref_row["cycle"]), float(ref_row["trace_ms"]),
                  float(ref_row["trace_ms"]) / base_ms, 0.0, 0.0])
    write_csv(exp / "texture_filter.csv", ["lookups", "cycle", "frame ms", "time / bilinear", "RMSE vs reference",
                                           "99th percentile |error|"], table)
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.4))
    for ax in axes.flat:
        ax.axis("off")
    axes[0, 0].imshow(np.clip(ref, 0, 1))
    axes[0, 0].set_title(f"reference ({k}x{k} rays/pixel)", fontsize=9)
    for col, step in ((1, "bilinear"), (2, "mipmap")):
        img, err = images[step]
        axes[0, col].imshow(np.clip(img, 0, 1))
        axes[0, col].set_title(f"{step}, 1 ray/pixel", fontsize=9)
        axes[1, col].imshow(np.clip(4 * err.max(axis=2), 0, 1), cmap="magma")
        axes[1, col].set_title(f"|{step} - reference| x 4", fontsize=9)
    fig.suptitle("Texture lookups: time against error")
    fig.tight_layout()
    fig.savefig(exp / "texture_filter.png", dpi=100)
    plt.close(fig)
    e_bi, e_mip = table[0][4], table[1][4]
    write_fragment(exp, {
        "tables": [{"caption": "Frame time and error against the supersampled reference (display values in [0, 1])",
                    "csv": "texture_filter.csv"}],
        "figures": [{"caption": "Reference, bilinear and MIP-mapped frames and their errors",
                     "png": "texture_filter.png", "data": "texture_filter.csv"}],
        "matches": e_mip < e_bi,
        "verdict": (f"MIP-mapped lookups bring the 1-ray frame to RMSE {e_mip:.4f} of the {k}x{k} reference "
                    f"against {e_bi:.4f} for bilinear lookups ({e_bi / max(e_mip, 1e-12):.2f}x closer) "
                    f"for {table[1][3]:.1f}x the frame time ({table[0][2]:.0f} -> {table[1][2]:.0f} ms). "
                    "An own study: the monograph reports no texture filtering."),
        "source_hardware": MONOGRAPH_NONE,
    })


# ------------------------------------------------------------------ stress summary
def stress_summary(exp: Path, _args):
    """Every mesh melted away in float and in double (folders <mesh>_float, <mesh>_double):
    cycles survived, checks passed, self-intersections, float-vs-double drift and time."""
    pairs = {}
    for d in sorted(p for p in exp.iterdir() if (p / "run.json").is_file()):
        mesh, _, prec = d.name.rpartition("_")
        if prec in ("float", "double"):
            pairs.setdefault(mesh, {})[prec] = load_run(d)
    meshes = [m for m in pairs if len(pairs[m]) == 2]
    if not meshes:
        raise SystemExit(f"experiment_report.py: {exp}: no <mesh>_float / <mesh>_double simulate runs")
    rows, drift_curves = [], {}
    for mesh in meshes:
        (rf, sf), (rd, sd) = pairs[mesh]["float"], pairs[mesh]["double"]
        v0 = float(sd[0]["volume"])
        vol_f = {int(r["cycle"]): float(r["volume"]) for r in sf}
        vol_d = {int(r["cycle"]): float(r["volume"]) for r in sd}
        tri_f = {int(r["cycle"]): int(r["triangles"]) for r in sf}
        tri_d = {int(r["cycle"]): int(r["triangles"]) for r in sd}
        common = sorted(c for c in vol_f if c in vol_d)
        # Drift while the double run still has a tenth of its volume: near the end both are a
        # few triangles and the difference of two small numbers says little.
        alive = [c for c in common if vol_d[c] >= 0.1 * v0]
        drift = [abs(vol_f[c] - vol_d[c]) / v0 for c in alive]
        drift_curves[mesh] = (alive, drift)
        first_diff = next((c for c in common if tri_f[c] != tri_d[c]), None)
        for prec, run in (("float", rf), ("double", rd)):
            ch = run["checks"]
            inter = ch.get("intersections", [])
            input_pairs = next((i["intersecting_pairs"] for i in inter if i["cycle"] == 0), 0)
            rows.append([mesh, prec, run["mesh"]["triangles"], run["status"], run["cycles_run"],
                         ch.get("topology_checks", 0), len(inter), input_pairs,
                         max((i["intersecting_pairs"] for i in inter if i["cycle"] > 0), default=0),
                         run["timing"]["cycle_ms_median"], max(drift) if drift else None,
                         (first_diff if first_diff is not None else "never") if prec == "float" else None])
    write_csv(exp / "stress_summary.csv",
              ["mesh", "precision", "triangles", "status", "cycles survived", "topology checks passed",
               "self-intersection checks", "intersecting pairs in the input", "max intersecting pairs after",
               "median ms/cycle",
               "max |V_float - V_double| / V0 (while V >= 0.1 V0)", "first cycle with different triangle counts"],
              rows)
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.4))
    for mesh, (cycles, drift) in drift_curves.items():
        ax1.plot(cycles, [max(x, 1e-12) for x in drift], label=mesh, linewidth=1)
    ax1.set_yscale("log")
    ax1.set_xlabel("cycle")
    ax1.set_ylabel("|V_float - V_double| / V0")
    ax1.set_title("Float against double: volume drift (while V >= 0.1 V0)", fontsize=10)
    ax1.legend(fontsize=7)
    by = {(r[0], r[1]): r for r in rows}
    for mesh in meshes:
        t_f, t_d = by[(mesh, "float")][9], by[(mesh, "double")][9]
        err = by[(mesh, "float")][10] or 1e-12
        ax2.scatter([t_f / t_d], [err], s=18)
        ax2.annotate(mesh, (t_f / t_d, err), fontsize=7)
    ax2.set_yscale("log")
    ax2.set_xlabel("float time / double time per cycle (median)")
    ax2.set_ylabel("max volume drift of float")
    ax2.set_title("Time against error of the precision knob", fontsize=10)
    fig.tight_layout()
    fig.savefig(exp / "stress_summary.png", dpi=100)
    plt.close(fig)
    melted = sum(1 for r in rows if r[3] == "melted")
    checks = sum(r[5] for r in rows)
    worst = max((r[10] for r in rows if r[10] is not None), default=0.0)
    speed = statistics.median(by[(m, "double")][9] / by[(m, "float")][9] for m in meshes)
    any_inter = [r for r in rows if r[8] > 0]
    input_inter = sorted({r[0] for r in rows if r[7] > 0})
    write_fragment(exp, {
        "tables": [{"caption": "Meshes melted until empty in float and double (one core)", "csv": "stress_summary.csv"}],
        "figures": [{"caption": "Float-vs-double volume drift per cycle, and drift against the time ratio",
                     "png": "stress_summary.png", "data": "stress_summary.csv"}],
        "matches": melted == len(rows),
        "verdict": (f"{melted} of {len(rows)} runs ({len(meshes)} meshes x float/double) melted away completely; "
                    f"{checks} full topology checks passed (a failed check would have failed the run); "
                    + (f"meshes already self-intersecting as input: {', '.join(input_inter)}; " if input_inter else "")
                    + (f"self-intersections on sampled cycles after the start in {len(any_inter)} run(s) "
                       f"({', '.join(sorted({r[0] for r in any_inter}))}; max {max(r[8] for r in any_inter)} pairs); "
                       if any_inter else "no self-intersection on any sampled cycle after the start; ")
                    + f"float drifts from double by at most {worst:.2g} of the initial volume while a tenth of it "
                    f"remains, and is {speed:.2f}x as fast per cycle (median over the meshes)."),
        "source_hardware": MONOGRAPH_NONE,
    })


# ------------------------------------------------------------------ module studies
def module_studies(exp: Path, _args):
    """Time against error of the verification loop (P measure, silhouettes), of the
    reference solver and of the fit, from what the earlier steps wrote (benchmark JSONs,
    fit/fit_bench.csv)."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
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


# ------------------------------------------------------------------ generic
def runs(exp: Path, _args):
    rows, figs = [], []
    for d in sorted(p for p in exp.iterdir() if (p / "run.json").is_file()):
        run, st = load_run(d)
        rows.append([d.name, run["status"], run["cycles_run"], run["mesh"]["triangles"], run["final"]["triangles"],
                     run["timing"]["cycle_ms_median"]])
        for png in ("summary.png", "snapshots.png"):
            if (d / png).is_file():
                figs.append({"caption": f"{d.name}: {png}", "png": f"{d.name}/{png}", "data": f"{d.name}/stats.csv"})
    if not rows:
        raise SystemExit(f"experiment_report.py: {exp}: no simulate run folders")
    write_csv(exp / "runs.csv", ["run", "status", "cycles", "triangles at start", "triangles at end", "median ms"], rows)
    write_fragment(exp, {"tables": [{"caption": "Simulate runs", "csv": "runs.csv"}], "figures": figs, "matches": None,
                         "verdict": f"{len(rows)} run(s): " + ", ".join(f"{r[0]} {r[1]}" for r in rows),
                         "source_hardware": MONOGRAPH_NONE})


KINDS = {"tab_2_3": tab_2_3, "cycle_time": cycle_time, "deform_variants": deform_variants, "split": split,
         "kl_field": kl_field, "chapter8": chapter8, "fit": fit, "physics_fit": physics_fit, "melt_away": melt_away, "runs": runs,
         "liquid_figure": liquid_figure, "melt_scene": melt_scene, "texture_filter": texture_filter,
         "stress_summary": stress_summary, "module_studies": module_studies}


def main(argv):
    if len(argv) < 3 or argv[1] not in KINDS:
        print(__doc__, file=sys.stderr)
        return 2
    KINDS[argv[1]](Path(argv[2]), argv[3:])
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
