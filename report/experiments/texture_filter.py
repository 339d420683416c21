"""Report of the `texture_filter` experiments (see report/experiment_report.py)."""
import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .common import write_csv, write_fragment, MONOGRAPH_NONE


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
