#!/usr/bin/env python3
"""Chapter 8 summary: P per photo for several `meltlab compare` folders, beside the
monograph's P1 / P100 (Fig. 8.12, spec §9.5).

usage: compare_summary.py OUT_PNG LABEL=COMPARE_DIR [LABEL=COMPARE_DIR ...]
Writes OUT_PNG (P against photo number, one line per comparison, Figs. 8.7-8.10 style),
OUT_PNG with .csv (label, P1, P33, P67, P100, max, mean, fraction <= 0.2, skipped) and
prints the same table.
"""
import csv
import json
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

# The monograph's values (Fig. 8.12 captions, spec §9.5).
MONOGRAPH = {
    "giraffe": (0.068818, 0.137467),
    "airplane": (0.027969, 0.10399),
    "ship": (0.044926, 0.120915),
    "warship": (0.07131, 0.178187),
}


def load(folder):
    rows = list(csv.DictReader(open(os.path.join(folder, "per_frame.csv"))))
    info = json.load(open(os.path.join(folder, "compare.json")))
    photo, p = [], []
    for r in rows:
        if r["status"] == "ok":
            photo.append(int(r["frame"]))
            p.append(float(r["P"]))
    return photo, p, rows, info


def at(photo, p, n):
    return p[photo.index(n)] if n in photo else math.nan


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    out_png = sys.argv[1]
    entries = []
    for arg in sys.argv[2:]:
        label, _, folder = arg.partition("=")
        entries.append((label, folder) + load(folder))

    fig, ax = plt.subplots(figsize=(9, 5))
    table = []
    for label, folder, photo, p, rows, info in entries:
        ax.plot(photo, p, label=label, lw=1.4)
        s = info["summary"]
        table.append(
            [label, at(photo, p, 1), at(photo, p, 33), at(photo, p, 67), at(photo, p, 100),
             s["P_max"] if s["P_max"] is not None else math.nan,
             s["P_mean"] if s["P_mean"] is not None else math.nan,
             s["fraction_P_le_0.2"] if s["fraction_P_le_0.2"] is not None else math.nan,
             s["frames_skipped"]])
    for name, (p1, p100) in MONOGRAPH.items():
        ax.plot([1, 100], [p1, p100], ls="none", marker="o", ms=5, color="black", alpha=0.6)
        for x, y in ((1, p1), (100, p100)):
            ax.annotate(name, (x, y), textcoords="offset points", xytext=(5, -3), fontsize=7, alpha=0.8)
    ax.axhline(0.2, color="tab:red", ls="--", lw=1, label="acceptance P = 0.2")
    ax.set_xlabel("photo number")
    ax.set_ylabel("P (Eq. 8.1, pixels)")
    ax.set_title("P per photo (circles: the monograph's P1 and P100 of its four molds)")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=2)
    fig.tight_layout()
    tmp = out_png + ".partial.png"
    fig.savefig(tmp, dpi=120)
    os.replace(tmp, out_png)

    header = ["comparison", "P1", "P33", "P67", "P100", "P_max", "P_mean", "frac<=0.2", "skipped"]
    csv_path = os.path.splitext(out_png)[0] + ".csv"
    with open(csv_path + ".partial", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(header)
        for r in table:
            w.writerow(r)
    os.replace(csv_path + ".partial", csv_path)
    print(" ".join(f"{h:>12}" for h in header))
    for r in table:
        print(f"{r[0]:>12} " + " ".join(f"{v:12.4f}" if isinstance(v, float) else f"{v:>12}" for v in r[1:]))
    print(" ".join(f"{h:>12}" for h in ["monograph", "P1", "", "", "P100"]))
    for name, (p1, p100) in MONOGRAPH.items():
        print(f"{name:>12} {p1:12.4f} {'':>12} {'':>12} {p100:12.4f}")
    print(f"wrote {out_png} and {csv_path}")


if __name__ == "__main__":
    main()
