"""Report of a `meltlab sweep` (see report/experiment_report.py): one figure per measure of
sweep.csv (written by `meltlab sweep --collect`, described by sweep.json) against the x option,
one line per combination of the other swept options."""
import csv
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .common import write_fragment, MONOGRAPH_NONE


def _number(text):
    try:
        return float(text)
    except ValueError:
        return None


def sweep(exp: Path, _args):
    meta = json.loads((exp / "sweep.json").read_text())
    with open(exp / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"experiment_report.py: {exp}: sweep.csv has no points")
    options, x = meta["options"], meta["x"]
    others = [o for o in options if o != x]
    figures = []
    for m in meta["measures"]:
        name = m["name"]
        values = [_number(r[name]) for r in rows]
        fig, ax = plt.subplots(figsize=(6.4, 4.2))
        if any(v is None for v in values):
            # a measure that is a text (a status): one column of labels per point
            ax.axis("off")
            ax.table(cellText=[[r["point"]] + [r[o] for o in options] + [r[name]] for r in rows],
                     colLabels=["point"] + options + [name], loc="center", fontsize=8)
        else:
            groups = {}
            for r, v in zip(rows, values):
                key = ", ".join(f"{o} {r[o]}" for o in others)
                xv = _number(r[x]) if x else None
                groups.setdefault(key, []).append((xv if xv is not None else r["point"], v))
            for key, pts in groups.items():
                if x:
                    pts.sort()
                    ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=key or None)
                else:
                    ax.bar([str(p[0]) for p in pts], [p[1] for p in pts], label=key or None)
            ax.set_xlabel(x if x else "point")
            ax.set_ylabel(name)
            if any(groups):
                ax.legend(fontsize=7)
        ax.set_title(f"{meta['title']}: {name}", fontsize=10)
        fig.tight_layout()
        png = f"sweep_{name}.png"
        fig.savefig(exp / png, dpi=100)
        plt.close(fig)
        figures.append({"caption": f"{name} ({m['file']}: {m['key']}) over {', '.join(options)}", "png": png,
                        "data": "sweep.csv"})
    write_fragment(exp, {"tables": [{"caption": f"Sweep of meltlab {meta['command']}: every point and its measures",
                                     "csv": "sweep.csv"}],
                         "figures": figures, "matches": None,
                         "verdict": f"{len(rows)} point(s) of meltlab {meta['command']} over {', '.join(options)}; "
                                    f"{len(meta['measures'])} measure(s)",
                         "source_hardware": MONOGRAPH_NONE})
