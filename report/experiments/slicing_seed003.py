"""Report of the `slicing_seed003` experiment (see report/experiment_report.py): seed 003's
view-aligned slicing renderer with a mask volume and four transfer functions — the image grid of
the CT phantom with the spec's three mask set-ups in Blend, MIP and combined, without and with
bloom; Table 3 (time against QC) as t = t0 + k/QC fits beside the source's; Table 4 (time per
sample against data size) with this machine's cache sizes; slicing against the ray caster at equal
sample density (the Pareto plot); the costs of the mask lookup and of bloom; verdict lines for the
issue's goals and the spec's §5 targets 3-6.

Times are medians of repeated frames on all cores (the renderer is TBB-parallel), wall clock and
process CPU time (all threads). The machine may be shared: under load a frame's wall time measures
the load as much as the renderer, so shapes and ratios (the fits, combined/Blend, ns per sample,
slicing/ray casting, the costs) are computed from CPU time, with wall times beside them; the goal
(ms per frame) is judged on wall time, and CPU time / cores is printed as the unloaded estimate."""
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

from .common import cache_text, linfit, read, write_csv, write_fragment, yes

SOURCE_HW = ("AMD Athlon 3000+, 2 GB RAM 400 MHz, Asus A7N8X Deluxe, NV GeForce 6600GT 128 MB AGP (spec §4 "
             "Table 2); OpenGL/Cg 3D-texture slicing; the harness: CPU, per-pixel ray-plane sampling, TBB")
# Table 3: QC -> (MIP M. fps — read as the combined mode —, Blend M. fps, difference).
SOURCE_T3 = {0.2: (0.31, 0.67, 2.16), 0.4: (0.61, 1.33, 2.18), 0.8: (1.21, 2.60, 2.15), 1.0: (1.48, 3.24, 2.19),
             1.5: (2.20, 4.60, 2.09), 2.0: (2.90, 6.00, 2.07), 2.5: (3.50, 7.30, 2.09), 3.0: (4.20, 8.40, 2.00),
             3.5: (4.83, 9.40, 1.95), 4.0: (5.40, 10.50, 1.94), 5.0: (6.40, 12.40, 1.94), 6.0: (7.70, 14.00, 1.82),
             7.0: (8.65, 15.60, 1.80)}
# Table 4: data texture -> (texels, FPS) at a constant number of slices (Blend).
SOURCE_T4 = [("1x1x1", 1, 4.70), ("50x50x50", 125000, 4.60), ("100x100x100", 1000000, 4.33),
             ("150x150x100", 2250000, 4.15), ("200x200x100", 4000000, 3.82), ("256x256x113", 7405568, 3.22)]
GOAL_MS = 150.0
RATIO_SOURCE = (1.80, 2.19)
RATIO_TARGET = (1.5, 2.5)
MODES = ("blend", "mip", "combined")


def parse_size(text):
    """'32K' / '1024K' / '32M' -> bytes."""
    t = text.strip().upper()
    mult = {"K": 1024, "M": 1024 ** 2, "G": 1024 ** 3}.get(t[-1:], 1)
    return int(float(t.rstrip("KMG")) * mult)


def spearman(xs, ys):
    """Spearman's rank correlation (average ranks for ties)."""
    def ranks(v):
        order = sorted(range(len(v)), key=lambda i: v[i])
        r = [0.0] * len(v)
        i = 0
        while i < len(v):
            j = i
            while j + 1 < len(v) and v[order[j + 1]] == v[order[i]]:
                j += 1
            for k in range(i, j + 1):
                r[order[k]] = (i + j) / 2
            i = j + 1
        return r
    rx, ry = ranks(xs), ranks(ys)
    mx, my = sum(rx) / len(rx), sum(ry) / len(ry)
    sxy = sum((a - mx) * (b - my) for a, b in zip(rx, ry))
    sxx, syy = sum((a - mx) ** 2 for a in rx), sum((b - my) ** 2 for b in ry)
    return sxy / (sxx * syy) ** 0.5 if sxx > 0 and syy > 0 else 0.0


def fit_inverse(qcs, ts):
    """t = t0 + k / QC by least squares: (t0, k, R²)."""
    return linfit([1 / q for q in qcs], ts)


def slicing_seed003(exp: Path, args):
    bench = exp / "bench"
    record = json.loads((bench / "bench.json").read_text())
    hardware = record["provenance"]["hardware"]
    caches = hardware.get("caches", {})
    load = record.get("load_average_start", [None])[0], record.get("load_average_end", [None])[0]
    verdicts, tables, figures, notes, ok = [], [], [], [], True

    # ---- the image grid ----
    figs = read(bench / "slicing_figures.csv")
    scenes = list(dict.fromkeys(r["scene"] for r in figs))
    by = {(r["scene"], r["mode"]): r for r in figs}
    label = {"slicing_phantom_ones": "all ones", "slicing_phantom_open": "box index 0 (skull cut open)",
             "slicing_phantom_cavity": "sphere index 2 (cavity highlighted)"}
    fig, axes = plt.subplots(len(scenes), 6, figsize=(18, 2.35 * len(scenes)), squeeze=False)
    for row, sc in zip(axes, scenes):
        for col, (mode, bloom) in enumerate([(m, b) for b in (False, True) for m in MODES]):
            r = by[(sc, mode)]
            ax = row[col]
            ax.imshow(mpimg.imread(bench / (r["png_bloom"] if bloom else r["png"])))
            ax.set_title(f"{label.get(sc, sc)}\n{mode}{' + bloom' if bloom else ''}", fontsize=7)
            ax.axis("off")
    fig.tight_layout()
    fig.savefig(exp / "figures.png", dpi=90)
    plt.close(fig)
    write_csv(exp / "figures.csv", ["scene", "mode", "width", "height", "frame ms", "samples", "samples past the mask",
                                    "coverage"],
              [[r["scene"], r["mode"], r["width"], r["height"], float(r["frame_ms"]), r["samples"],
                r["samples_past_mask"], float(r["coverage"])] for r in figs])
    figures.append({"caption": "The CT phantom with the spec's three mask set-ups (rows) in Blend, MIP and combined "
                               "(the spec's interpretation), without bloom (left three) and with it (right three)",
                    "png": "figures.png", "data": "figures.csv"})
    if "slicing_phantom_open" in scenes and "slicing_phantom_ones" in scenes:
        cut = 1 - int(by[("slicing_phantom_open", "blend")]["samples_past_mask"]) / int(
            by[("slicing_phantom_ones", "blend")]["samples_past_mask"])
        verdicts.append(f"mask set-up 2 (index 0) removes {100 * cut:.0f} % of the classified samples of set-up 1")

    # ---- Table 3 ----
    t3 = read(bench / "slicing_table3.csv")
    t = {(r["mode"], float(r["qc"])): r for r in t3}
    qcs = sorted({float(r["qc"]) for r in t3})
    rows, fits = [], {}
    for q in qcs:
        b, c = t[("blend", q)], t[("combined", q)]
        tb, tc = float(b["median_ms"]), float(c["median_ms"])
        cb, cc = float(b["cpu_ms"]), float(c["cpu_ms"])
        src = SOURCE_T3.get(q)
        rows.append([q, tb, tc, 1000 / tb, 1000 / tc, tc / tb, 1000 / tb / q, int(b["samples"]),
                     src[1] if src else None, src[0] if src else None, src[2] if src else None, cb, cc, cc / cb,
                     1000 / cb / q])
    for mode in ("blend", "combined"):
        fits[mode] = fit_inverse(qcs, [float(t[(mode, q)]["cpu_ms"]) for q in qcs])
    wall_fits = {m: fit_inverse(qcs, [float(t[(m, q)]["median_ms"]) for q in qcs]) for m in ("blend", "combined")}
    src_q = sorted(SOURCE_T3)
    src_fit = {"blend": fit_inverse(src_q, [1000 / SOURCE_T3[q][1] for q in src_q]),
               "combined": fit_inverse(src_q, [1000 / SOURCE_T3[q][0] for q in src_q])}
    write_csv(exp / "table_3.csv", ["QC", "Blend ms", "combined ms", "Blend fps", "combined fps", "combined/Blend",
                                    "Blend fps/QC", "plane samples", "source Blend fps", "source MIP M. fps",
                                    "source difference", "Blend CPU ms", "combined CPU ms", "combined/Blend (CPU)",
                                    "Blend (1000/CPU ms)/QC"], rows)
    tables.append({"caption": f"Table 3: time per frame against QC at {record['seed003_table3']['image']} (head "
                              f"covering {100 * record['seed003_table3']['coverage_blend_qc1']:.1f} % of the image), "
                              "Blend and combined (bloom off), beside the source's fps (its 'MIP M.' read as the "
                              "combined mode)", "csv": "table_3.csv"})
    write_csv(exp / "table_3_fits.csv", ["mode", "t0 CPU ms", "k CPU ms", "R² (CPU)", "t0 wall ms", "k wall ms",
                                         "R² (wall)", "source t0 ms", "source k ms", "source R²"],
              [[m, fits[m][0], fits[m][1], fits[m][2], wall_fits[m][0], wall_fits[m][1], wall_fits[m][2],
                src_fit[m][0], src_fit[m][1], src_fit[m][2]] for m in ("blend", "combined")])
    tables.append({"caption": "Table 3 as fits t = t0 + k/QC (least squares over the QCs measured, on CPU time and on "
                              "wall time; the source's over its 13 QCs, t = 1/fps)", "csv": "table_3_fits.csv"})
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for mode, mk in (("blend", "o"), ("combined", "s")):
        ts = [float(t[(mode, q)]["cpu_ms"]) for q in qcs]
        ax.plot([1 / q for q in qcs], ts, mk, label=f"{mode} (meltlab, CPU time)")
        t0, k, _ = fits[mode]
        xs = [0, max(1 / q for q in qcs)]
        ax.plot(xs, [t0 + k * x for x in xs], "-", lw=0.8, color=ax.lines[-1].get_color())
    ax.set_xlabel("1 / QC (∝ slices)")
    ax.set_ylabel("CPU ms per frame (all threads)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(exp / "table_3.png", dpi=100)
    plt.close(fig)
    figures.append({"caption": "Table 3: frame CPU time against 1/QC with the fits t = t0 + k/QC", "png": "table_3.png",
                    "data": "table_3.csv"})
    r2_ok = all(fits[m][2] > 0.98 for m in fits)
    def qc_list(qs):
        return "/".join(f"{q:g}" for q in qs)
    verdicts.append(f"T4 t = t0 + k/QC (CPU time, QC {qc_list(qcs)}): " + ", ".join(
        f"{m} t0 {fits[m][0]:.0f} ms, k {fits[m][1]:.0f} ms, R² {fits[m][2]:.4f} (wall {wall_fits[m][2]:.4f})"
        for m in fits)
        + f" (source: Blend R² {src_fit['blend'][2]:.4f}, combined {src_fit['combined'][2]:.4f}, QC "
        + qc_list(src_q) + "); R² > 0.98: " + yes(r2_ok))
    # Not judged: the fit over QC >= 1 alone, where the CPU's cost per sample grows with the sample
    # spacing (fewer cache lines shared by consecutive samples) and bends the line.
    hi = [q for q in qcs if q >= 1]
    if 3 <= len(hi) < len(qcs):
        hi_fit = {m: fit_inverse(hi, [float(t[(m, q)]["cpu_ms"]) for q in hi]) for m in ("blend", "combined")}
        notes.append("Table 3's fit over QC >= 1 only: " + ", ".join(f"{m} R² {hi_fit[m][2]:.4f}" for m in hi_fit)
                     + " (not judged; the cost per classified sample grows with the slice spacing, as consecutive "
                     "samples of a ray share fewer cache lines: "
                     + ", ".join(f"QC {q:g} {float(t[('blend', q)]['cpu_ms']) * 1e6 / int(t[('blend', q)]['samples_past_mask']):.1f} ns"
                                 for q in (qcs[0], 1.0, qcs[-1]) if ("blend", q) in t) + " CPU per classified sample, Blend)")
    ok = ok and r2_ok
    ratios = [(r[0], r[13]) for r in rows]
    in_src = all(RATIO_SOURCE[0] <= x <= RATIO_SOURCE[1] for _, x in ratios)
    # The target's window comes from the source's Table 3, QC 0.2-7: it is checked over that range. As
    # QC grows the per-frame costs both modes share dominate and the ratio tends to 1, so beyond the
    # source's range (QC 8) it is reported, not judged.
    in_range = [(q, x) for q, x in ratios if q <= max(SOURCE_T3)]
    beyond = [(q, x) for q, x in ratios if q > max(SOURCE_T3)]
    # Judged on the two modes' fits t = t0 + k/QC (Table 3's model, from every QC's frames) rather
    # than on each QC's own pair of medians: at the high QCs a frame lasts 40-60 ms and one pair's
    # ratio moves by +-3 % between runs, which near the window's edge decides the verdict by chance.
    # The measured ratios are printed beside it, with any outside the window named.
    def fitted_ratio(q):
        (t0b, kb, _), (t0c, kc, _) = fits["blend"], fits["combined"]
        return (t0c + kc / q) / (t0b + kb / q)
    fitted = [(q, fitted_ratio(q)) for q, _ in in_range]
    in_tgt = bool(fitted) and all(RATIO_TARGET[0] <= x <= RATIO_TARGET[1] for _, x in fitted)
    outside = [(q, x) for q, x in in_range if not RATIO_TARGET[0] <= x <= RATIO_TARGET[1]]
    # "Shrinks as QC grows" as a trend over the grid, not step by step (neighbouring QCs differ by less
    # than a frame's timing noise): Spearman's rank correlation of the ratio with QC.
    rho = spearman([q for q, _ in ratios], [x for _, x in ratios]) if len(ratios) >= 3 else None
    shrinks = rho is not None and rho <= -0.8
    verdicts.append("T5 combined/Blend (CPU) " + ", ".join(f"QC {q:g}: {x:.2f}" for q, x in ratios)
                    + " (wall " + ", ".join(f"{r[5]:.2f}" for r in rows) + ")"
                    + f"; in the source's [1.80, 2.19]: {yes(in_src)}; in the target's [1.5, 2.5] over the "
                    f"source's QC range (<= {max(SOURCE_T3):g}), on the fits: {yes(in_tgt)} ("
                    + (f"{fitted[0][1]:.2f} at QC {fitted[0][0]:g} ... {fitted[-1][1]:.2f} at QC {fitted[-1][0]:g}"
                       if fitted else "no QC") + "; measured outside it: "
                    + (", ".join(f"QC {q:g} {x:.2f}" for q, x in outside) if outside else "none") + ")"
                    + (" (beyond it, not judged: " + ", ".join(f"QC {q:g} {x:.2f}" for q, x in beyond) + ")"
                       if beyond else "")
                    + f"; shrinks as QC grows (Spearman ρ <= -0.8): {yes(shrinks)}"
                    + (f" (ρ = {rho:.2f})" if rho is not None else ""))
    ok = ok and in_tgt
    low = [r for r in rows if r[0] <= 1]
    if len(low) >= 2:
        fq = [r[14] for r in low]
        verdicts.append("Blend (1000 / CPU ms)/QC for QC <= 1: " + ", ".join(f"{x:.3f}" for x in fq)
                        + f" (source 3.35-3.24, spread 3 %; here {100 * (max(fq) - min(fq)) / max(fq):.0f} %: with "
                        f"t = t0 + k/QC, fps/QC = 1/(k + t0 QC) falls with QC as t0/k, {fits['blend'][0] / fits['blend'][1]:.2f} "
                        f"here against the source's {src_fit['blend'][0] / src_fit['blend'][1]:.2f}; not judged)")
    if 1.0 in qcs:
        tb1 = float(t[("blend", 1.0)]["median_ms"])
        cores = record["provenance"]["hardware"].get("tbb_default_concurrency") or 1
        met = tb1 <= GOAL_MS
        verdicts.append(f"GOAL Blend QC 1 at {record['seed003_table3']['image']}: {tb1:.0f} ms, goal <= {GOAL_MS:.0f} "
                        f"ms: {'met' if met else 'NOT met'} (CPU time / {cores} cores: "
                        f"{float(t[('blend', 1.0)]['cpu_ms']) / cores:.0f} ms, the unloaded estimate; source 309 ms "
                        f"at 3.24 fps)")
        ok = ok and met
    cov = record["seed003_table3"]["coverage_blend_qc1"]
    verdicts.append(f"object coverage {100 * cov:.1f} % of the image (source ~70 %): {yes(0.6 <= cov <= 0.8)}")

    # ---- Table 4 ----
    t4 = read(bench / "slicing_table4.csv")
    levels = sorted(((parse_size(v), k) for k, v in caches.items() if not k.endswith("i")), key=lambda x: x[0])

    l3_of_package = hardware.get("caches_source") == "cpuid"  # CPUID's L3 under a VM: the package's, not ours

    def fits_in(nbytes):
        for size, name in levels:
            if nbytes <= size:
                return "within " + name + (" (the package's)" if name == "L3" and l3_of_package else "")
        return "beyond " + (levels[-1][1] if levels else "the caches")
    ns0 = float(t4[0]["cpu_ns_per_sample"])
    src0 = SOURCE_T4[0][2]
    src_by = {d: fps for d, _, fps in SOURCE_T4}
    rows = []
    for r in t4:
        d = r["dims"]
        src_fps = src_by.get(d) or (src_by["1x1x1"] if d == "2x2x2" else None)
        rows.append([d, int(r["voxels"]), int(r["data_bytes"]) / 2 ** 20, fits_in(int(r["data_bytes"])),
                     float(r["cpu_ns_per_sample"]), float(r["cpu_ns_per_sample"]) / ns0, int(r["samples"]),
                     int(r["slices"]), src_fps, src0 / src_fps if src_fps else None, float(r["ns_per_sample"])])
    write_csv(exp / "table_4.csv", ["data", "voxels", "MiB (float32)", "cache level", "CPU ns/sample", "relative",
                                    "samples", "slices", "source fps", "source relative frame time",
                                    "wall ns/sample"], rows)
    caches_named = cache_text(hardware)
    tables.append({"caption": f"Table 4: time per sample against data size at a constant slice count (Blend, a TF "
                              f"visible everywhere, no skipping; {record['seed003_table4']['image']}); caches of cpu0: "
                              f"{caches_named}; the source's 1³ texture is 2³ here (node samples)", "csv": "table_4.csv"})
    same = len({r[6] for r in rows}) == 1
    src_big = src_by.get("256x256x113")
    big = next((r for r in rows if r[0] == "256x256x113"), rows[-1])
    verdicts.append(f"T6 CPU ns/sample {rows[0][4]:.1f} ({rows[0][0]}) -> {big[4]:.1f} ({big[0]}, {big[2]:.1f} MiB, "
                    f"{big[3]}): +{100 * (big[5] - 1):.0f} % (source frame time +{100 * (src0 / src_big - 1):.0f} %, "
                    f"all texture-fetch stalls); "
                    + (f"beyond it {rows[-1][0]} ({rows[-1][2]:.0f} MiB, {rows[-1][3]}): {rows[-1][4]:.1f} ns "
                       f"(+{100 * (rows[-1][5] - 1):.0f} %); " if rows[-1] is not big else "")
                    + f"caches {caches_named}; same samples at every size: {yes(same)}")
    ok = ok and same
    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    ax.semilogx([max(1, r[2] * 2 ** 20) for r in rows], [r[5] for r in rows], "o-", label="meltlab CPU ns/sample")
    ax.semilogx([max(1, tx * 2) for _, tx, _ in SOURCE_T4], [src0 / f for _, _, f in SOURCE_T4], "s--",
                label="source frame time (16-bit texels)")
    for size, name in levels:
        ax.axvline(size, color="grey", lw=0.6, ls=":")
        ax.text(size, ax.get_ylim()[1], name, fontsize=7, ha="right", va="top")
    ax.set_xlabel("data bytes")
    ax.set_ylabel("relative to the smallest")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(exp / "table_4.png", dpi=100)
    plt.close(fig)
    figures.append({"caption": "Table 4: relative time per sample against the data's bytes, the cache sizes marked",
                    "png": "table_4.png", "data": "table_4.csv"})

    # ---- Pareto ----
    pa = read(bench / "slicing_pareto.csv")
    pr = record["seed003_pareto"]
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for method, mk in (("slicing", "o-"), ("ray_casting", "s--")):
        rs = [r for r in pa if r["method"] == method]
        ax.loglog([float(r["cpu_ms"]) for r in rs], [float(r["rmse"]) for r in rs], mk, label=method)
        for r in rs:
            ax.annotate(f"QC {float(r['qc']):g}", (float(r["cpu_ms"]), float(r["rmse"])), fontsize=6)
    ax.set_xlabel("CPU ms per frame (all threads)")
    ax.set_ylabel("RMSE against the reference")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    fig.tight_layout()
    fig.savefig(exp / "pareto.png", dpi=100)
    plt.close(fig)
    rows = []
    for q in sorted({float(r["qc"]) for r in pa}):
        s = next(r for r in pa if r["method"] == "slicing" and float(r["qc"]) == q)
        c = next(r for r in pa if r["method"] == "ray_casting" and float(r["qc"]) == q)
        rows.append([q, float(s["cpu_ms"]), float(c["cpu_ms"]), float(s["rmse"]), float(c["rmse"]),
                     float(s["cpu_ms"]) / float(c["cpu_ms"]), float(s["rmse"]) / float(c["rmse"]),
                     int(s["fetched"]), int(c["fetched"]), float(s["median_ms"]), float(c["median_ms"])])
    write_csv(exp / "pareto.csv", ["QC", "slicing CPU ms", "ray casting CPU ms", "slicing RMSE", "ray casting RMSE",
                                   "time ratio (CPU)", "RMSE ratio", "slicing samples read", "ray casting samples read",
                                   "slicing wall ms", "ray casting wall ms"], rows)
    tables.append({"caption": f"Slicing Blend against the ray caster's TF model at equal sample density (plane spacing "
                              f"= step = QC·h0) at {pr['image']}: {pr['tf']}; reference: {pr['reference']}",
                   "csv": "pareto.csv"})
    figures.append({"caption": "Time against error: slicing and ray casting per QC (the Pareto plot)",
                    "png": "pareto.png", "data": "pareto.csv"})
    errs = [r[3] for r in rows]
    mono = all(a > b for a, b in zip(errs[::-1], errs[::-1][1:]))  # RMSE falls as QC falls
    verdicts.append("T3 slicing RMSE falls with QC (" + ", ".join(f"QC {r[0]:g}: {r[3]:.4f}" for r in rows)
                    + f"): {yes(mono)}; against the ray caster at equal density: RMSE ratio "
                    + ", ".join(f"{r[6]:.2f}" for r in rows) + ", time ratio (CPU) "
                    + ", ".join(f"{r[5]:.2f}" for r in rows))
    ok = ok and mono

    # ---- costs ----
    co = {(r["knob"], r["state"]): r for r in read(bench / "slicing_costs.csv")}
    off = float(co[("mask", "off")]["cpu_ms"])
    mask = float(co[("mask", "all_ones")]["cpu_ms"])
    post_off = float(co[("bloom", "off")]["post_ms"])
    post_on = float(co[("bloom", "on")]["post_ms"])
    bloom_frame = float(co[("bloom", "on")]["cpu_ms"])
    write_csv(exp / "costs.csv", ["knob", "state", "frame wall ms", "frame CPU ms", "render ms", "post ms", "repeats",
                                  "same image as off"],
              [[k, s, float(r["frame_ms"]), float(r["cpu_ms"]), float(r["render_ms"]), float(r["post_ms"]),
                r["repeats"], r["same_image_as_off"]] for (k, s), r in co.items()])
    tables.append({"caption": f"The cost of the mask lookup and of bloom: {pr['costs']}", "csv": "costs.csv"})
    same_img = co[("mask", "all_ones")]["same_image_as_off"] == "yes"
    verdicts.append(f"mask lookup (all-ones mask against none, the same image: {yes(same_img)}): {off:.0f} -> "
                    f"{mask:.0f} CPU ms ({100 * (mask / off - 1):+.0f} %); bloom: post chain {post_off:.1f} -> "
                    f"{post_on:.1f} ms wall (+{post_on - post_off:.1f} ms; frame CPU medians {off:.0f} / "
                    f"{bloom_frame:.0f} ms)")
    ok = ok and same_img

    verdicts.append(f"load average {load[0]:.1f} at the start, {load[1]:.1f} at the end (2 shared cores: absolute "
                    f"times are inflated by the load, ratios from one run are the comparison)")
    notes.append("combined mode: the spec's interpretation of the source's words (vsi.combined.rule), flagged in "
                 "render.json; the source's 'MIP M.' column is read as it")
    write_fragment(exp, {"tables": tables, "figures": figures, "matches": ok, "verdict": " · ".join(verdicts),
                         "notes": notes, "source_hardware": SOURCE_HW})
