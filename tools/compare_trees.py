#!/usr/bin/env python3
"""Compares two meltlab output trees file by file, bitwise (the check of a behaviour-preserving
change: `meltlab reproduce --quick --out A` with one build, `--out B` with another).

    tools/compare_trees.py A B [--ignore GLOB ...] [--sources SRC_A SRC_B]

Files that record when, where and how long something ran are not compared bitwise: logs/,
done.json, summary.json, provenance records, timing CSVs. JSON files that differ bitwise are
compared as parsed values, with the provenance-like keys left out (time stamps, durations,
hardware, command lines, content-hash identifiers) and the two tree roots made equal; CSV
files likewise without their timing columns (`ms`, `*_ms`, `* ms`, `*_seconds`). Run records present
in one tree only (a Slurm run's slurm/ folders) are not reported either. Both are reported as
"same values" when nothing else differs. Exit 0 when nothing else differs.
"""
import argparse
import fnmatch
import filecmp
import json
import csv
import os
import re
import sys

# Records of the run itself (time stamps, durations, host, command line): expected to differ.
RUN_RECORDS = ["*/logs/*", "logs/*", "*done.json", "summary.json", "*provenance*.json", "*.err", "*.out",
               "*timing*", "*timings*", "*bench*.json", "*bench*.csv",
               # the Slurm executor's plan, batch scripts, job logs and step records (docs/cluster.md)
               "slurm/*", "*/slurm/*"]
# Keys of a JSON file that describe the run rather than its result.
RUN_KEYS = {"meltlab", "meltlab_version", "provenance", "hardware", "command", "command_line", "timing", "timings",
            "seconds", "finished", "started", "started_utc", "finished_utc", "wall_seconds", "elapsed_seconds", "host",
            "git_revision", "version", "created", "time_utc", "timestamp"}
# A content hash names an input; meltlab's hash function itself may change (issue 14 made it one).
HASH_KEY = re.compile(r"(^|_)hash$")
# Dataset files carry a content hash in their name (giraffe-95f6a320.off).
HASHED_NAME = re.compile(r"-[0-9a-f]{8}\.(off|ply|obj|stl)")
TIMING_COLUMN = re.compile(r"(^ms$|_ms$| ms$|_seconds$|^seconds$)")


def strip(value, roots):
    if isinstance(value, dict):
        return {k: strip(v, roots) for k, v in value.items()
                if k not in RUN_KEYS and not HASH_KEY.search(k) and not TIMING_COLUMN.search(k)}
    if isinstance(value, list):
        return [strip(v, roots) for v in value]
    if isinstance(value, str):
        for root in roots:
            value = value.replace(root, "<out>")
        return HASHED_NAME.sub(r".\1", value)
    return value


def csv_values(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return rows
    keep = [i for i, name in enumerate(rows[0]) if not TIMING_COLUMN.search(name)]
    return [[r[i] for i in keep if i < len(r)] for r in rows]


def files(root):
    for folder, _, names in os.walk(root):
        for name in names:
            yield os.path.relpath(os.path.join(folder, name), root)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--ignore", action="append", default=[], help="glob of relative paths not compared")
    ap.add_argument("--sources", nargs=2, default=[], metavar=("SRC_A", "SRC_B"),
                    help="the repositories the two runs read configs from (paths to them are made equal)")
    args = ap.parse_args()
    ignore = RUN_RECORDS + args.ignore
    a_files, b_files = set(files(args.a)), set(files(args.b))
    counts = {"identical": 0, "same values": 0, "ignored": 0}
    roots = [os.path.abspath(args.a), os.path.abspath(args.b)] + [os.path.abspath(p) for p in args.sources]
    def ignored(rel):
        return any(fnmatch.fnmatch(rel, g) for g in ignore)

    differ = []
    only_a = sorted(r for r in a_files - b_files if not ignored(r))
    only_b = sorted(r for r in b_files - a_files if not ignored(r))
    for rel in sorted(a_files & b_files):
        if ignored(rel):
            counts["ignored"] += 1
            continue
        pa, pb = os.path.join(args.a, rel), os.path.join(args.b, rel)
        if filecmp.cmp(pa, pb, shallow=False):
            counts["identical"] += 1
            continue
        try:
            if rel.endswith(".json"):
                with open(pa) as fa, open(pb) as fb:
                    if strip(json.load(fa), roots) == strip(json.load(fb), roots):
                        counts["same values"] += 1
                        continue
            if rel.endswith(".csv") and csv_values(pa) == csv_values(pb):
                counts["same values"] += 1
                continue
        except (ValueError, OSError):
            pass
        differ.append(rel)
    for rel in differ:
        print(f"DIFFERS  {rel}")
    for rel in only_a:
        print(f"ONLY A   {rel}")
    for rel in only_b:
        print(f"ONLY B   {rel}")
    print(f"{counts['identical']} identical, {counts['same values']} JSON/CSV with the same values, "
          f"{len(differ)} differ, {len(only_a)} only in A, {len(only_b)} only in B, {counts['ignored']} run records ignored")
    return 1 if differ or only_a or only_b else 0


if __name__ == "__main__":
    sys.exit(main())
