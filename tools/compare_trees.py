#!/usr/bin/env python3
"""Compares two meltlab output trees file by file, bitwise (the check of a behaviour-preserving
change: `meltlab reproduce --quick --out A` with one build, `--out B` with another).

    tools/compare_trees.py A B [--ignore GLOB ...]

Files that record when, where and how long something ran are not compared bitwise: logs/,
done.json, summary.json, provenance records, timing CSVs. JSON files that differ bitwise are
compared as parsed values, with the provenance-like keys left out, and reported as
"same numbers" when only formatting or those keys differ. Exit 0 when nothing else differs.
"""
import argparse
import fnmatch
import filecmp
import json
import os
import sys

# Records of the run itself (time stamps, durations, host, command line): expected to differ.
RUN_RECORDS = ["*/logs/*", "logs/*", "*done.json", "summary.json", "*provenance*.json", "*.err", "*.out",
               "*timing*", "*timings*", "*bench*.json", "*bench*.csv"]
# Keys of a JSON file that describe the run rather than its result.
RUN_KEYS = {"meltlab", "provenance", "hardware", "command_line", "timings", "seconds", "finished", "started",
            "wall_seconds", "elapsed_seconds", "host", "git_revision", "version", "created", "time_utc", "timestamp"}


def strip(value):
    if isinstance(value, dict):
        return {k: strip(v) for k, v in value.items() if k not in RUN_KEYS}
    if isinstance(value, list):
        return [strip(v) for v in value]
    return value


def files(root):
    for folder, _, names in os.walk(root):
        for name in names:
            yield os.path.relpath(os.path.join(folder, name), root)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--ignore", action="append", default=[], help="glob of relative paths not compared")
    args = ap.parse_args()
    ignore = RUN_RECORDS + args.ignore
    a_files, b_files = set(files(args.a)), set(files(args.b))
    counts = {"identical": 0, "same numbers": 0, "ignored": 0}
    differ, only_a, only_b = [], sorted(a_files - b_files), sorted(b_files - a_files)
    for rel in sorted(a_files & b_files):
        if any(fnmatch.fnmatch(rel, g) for g in ignore):
            counts["ignored"] += 1
            continue
        pa, pb = os.path.join(args.a, rel), os.path.join(args.b, rel)
        if filecmp.cmp(pa, pb, shallow=False):
            counts["identical"] += 1
            continue
        if rel.endswith(".json"):
            try:
                with open(pa) as fa, open(pb) as fb:
                    if strip(json.load(fa)) == strip(json.load(fb)):
                        counts["same numbers"] += 1
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
    print(f"{counts['identical']} identical, {counts['same numbers']} JSON with the same values, "
          f"{len(differ)} differ, {len(only_a)} only in A, {len(only_b)} only in B, {counts['ignored']} run records ignored")
    return 1 if differ or only_a or only_b else 0


if __name__ == "__main__":
    sys.exit(main())
