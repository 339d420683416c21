#!/usr/bin/python3
"""The verification loop's time-against-error table from the two Google Benchmark JSON
files: silhouette rendering of a 10.8k-triangle mold (ours serial/parallel, the
cv::fillConvexPoly peer measured in the same run) and the P measure of two discs against
the analytic value (raster pixels, 4x4 coverage, exact CGAL polygons), per resolution.
Also the per-frame cost of a comparison: silhouette + raster P, and silhouette at k = 4 +
marching squares + exact P.

Usage: report/verify_bench_summary.py bench_silhouette.json bench_p_measure.json
"""
import json
import re
import sys


def medians(path):
    doc = json.load(open(path))
    return [b for b in doc["benchmarks"] if b.get("aggregate_name") == "median"]


def tables(sil_json, p_json):
    """(silhouette, p): silhouette[(width, k, parallel)] and peer[(width, k)] median ms;
    p[(kind, width)] = (median ms, |P error|) for kind RasterP, CoverageP, ContourExactP."""
    sil, peer = {}, {}
    for b in medians(sil_json):
        label = b.get("label", "")
        m = re.search(r"(\d+)x(\d+) k(\d+)", label)
        if not m:
            continue
        width, k = int(m.group(1)), int(m.group(3))
        if label.startswith("meltlab"):
            sil[(width, k, "parallel" in label)] = b["real_time"]
        else:
            peer[(width, k)] = b["real_time"]
    p = {}
    for b in medians(p_json):
        m = re.match(r"BM_(\w+)/width:(\d+)_median", b["name"])
        if m:
            p[(m.group(1), int(m.group(2)))] = (b["real_time"], b.get("abs_error"))
    return sil, peer, p


def main(argv):
    if len(argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    sil, peer, p = tables(argv[1], argv[2])
    widths = sorted({w for (w, _, _) in sil})
    print("Silhouette of the giraffe mold (10.8k triangles), median ms")
    print(f"{'image':>10} {'serial':>8} {'2 thr':>8} {'peer':>8} {'peer/ours':>9} {'k4 ser':>8} {'k4 2thr':>8} {'k4 peer':>8}")
    for w in widths:
        h = w * 3 // 4
        s, par, pe = sil.get((w, 1, False)), sil.get((w, 1, True)), peer.get((w, 1))
        s4, p4, pe4 = sil.get((w, 4, False)), sil.get((w, 4, True)), peer.get((w, 4))
        f = lambda v: f"{v:8.2f}" if v is not None else f"{'-':>8}"
        ratio = f"{pe / s:9.2f}" if (pe and s) else f"{'-':>9}"
        print(f"{w}x{h:<5} {f(s)} {f(par)} {f(pe)} {ratio} {f(s4)} {f(p4)} {f(pe4)}")
    print()
    print("P of two discs against the analytic value: median ms (|error|)")
    print(f"{'image':>10} {'raster P':>20} {'coverage 4x4 P':>20} {'exact (CGAL) P':>20} {'frame raster':>13} {'frame exact':>12}")
    for w in widths:
        h = w * 3 // 4
        cells = []
        for kind in ("RasterP", "CoverageP", "ContourExactP"):
            t, e = p.get((kind, w), (None, None))
            cells.append(f"{t:8.2f} ({e:8.1e})" if t is not None else f"{'-':>20}")
        frame_raster = (sil.get((w, 1, True)) or 0) + (p.get(("RasterP", w), (0, 0))[0] or 0)
        frame_exact = (sil.get((w, 4, True)) or 0) + (p.get(("ContourExactP", w), (0, 0))[0] or 0)
        print(f"{w}x{h:<5} " + " ".join(f"{c:>20}" for c in cells) + f" {frame_raster:13.2f} {frame_exact:12.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
