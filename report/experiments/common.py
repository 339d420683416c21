"""Shared by the report modules of report/experiments/: CSV and report.json writing, run folders,
the monograph's hardware lines, montages."""
import csv
import json
import os
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


def read(path):
    """The rows of a CSV file as dicts."""
    with open(path) as f:
        return list(csv.DictReader(f))


def linfit(xs, ys):
    """Least-squares y = a + b x: (a, b, R²)."""
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    b = sxy / sxx if sxx > 0 else 0.0
    a = my - b * mx
    ss_res = sum((y - a - b * x) ** 2 for x, y in zip(xs, ys))
    ss_tot = sum((y - my) ** 2 for y in ys)
    return a, b, 1 - ss_res / ss_tot if ss_tot > 0 else 1.0


def yes(b):
    """A verdict word: "yes", or a shouted "NO" that stands out in a verdict line."""
    return "yes" if b else "NO"


def load_text(loads):
    """A bench record's load averages ([1, 5, 15 min]) as "1.23 0.98 0.75" ("?" if absent)."""
    if not loads:
        return "?"
    return " ".join(f"{x:.2f}" for x in loads)


def cache_text(hardware):
    """A provenance's cache sizes as "L1d 48K, L2 1024K, ..." with where they came from: Linux sysfs,
    or CPUID where the machine has no sysfs entries (a VM's CPUID L3 is the whole package's, of which
    the guest shares a part)."""
    caches = hardware.get("caches", {})
    if not caches:
        return "unknown"
    text = ", ".join(f"{k} {v}" for k, v in caches.items())
    if hardware.get("caches_source") == "cpuid":
        text += " (as CPUID reports them: under a VM the L3 is the package's, shared with other guests)"
    return text


def fmt_bool(b):
    return "yes" if b else "no"


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
