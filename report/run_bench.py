#!/usr/bin/python3
"""Runs one Google Benchmark binary for `meltlab reproduce` and keeps its JSON: the step of
an experiment that measures time against error with a benchmark (the binaries sit next to
meltlab; the config passes ${bin}/NAME). The JSON is written to OUT.json.partial and renamed
when the benchmark succeeds, so a failed run leaves no result behind.

usage: run_bench.py BENCH_BINARY OUT.json [BENCHMARK ARGS...]
"""
import os
import subprocess
import sys


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    binary, out = argv[1], argv[2]
    if not os.access(binary, os.X_OK):
        print(f"run_bench.py: {binary}: not an executable (build it: scripts/build release)", file=sys.stderr)
        return 2
    tmp = out + ".partial"
    cmd = [binary, *argv[3:], f"--benchmark_out={tmp}", "--benchmark_out_format=json"]
    rc = subprocess.call(cmd)
    if rc != 0:
        print(f"run_bench.py: {binary} exited with code {rc}", file=sys.stderr)
        return 1
    os.replace(tmp, out)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
