#!/usr/bin/python3
"""A/B comparison of two builds of a Google Benchmark program on a shared, noisy machine.

Runs OLD and NEW alternately (the order swapped every round) for ROUNDS rounds on the same
filter, each run with repetitions shuffled (--benchmark_enable_random_interleaving), and
prints per benchmark: the median time of each build over all repetitions, the median of the
per-round ratios new/old (a slow spell of the host falls on both builds of a round), and the
median of the simulator's per-pass counters (deform_ms, collapse_ms) where present.
Benchmarks only one build has (e.g. a new mesh) are listed with that build's median.
--time cpu compares the process CPU time instead of wall time: under load the wall time of
a serial benchmark includes the time the scheduler gave the core to other processes, its
CPU time does not (it still includes the cost of caches shared with them). For a parallel
benchmark the CPU time is the work of all threads, not how long the cycle took.

--counter NAME compares a per-repetition counter of the benchmark instead of its time, e.g. steady_ms
(BM_MeltCycle's cycles that are neither a fresh simulator's first nor a remnant check: on two threads
the benchmark's restarts every 20 cycles add a wake-up-bound tail that is noisier than the cycle).

--side-by-side 0,1 runs OLD and NEW at the same time, each pinned to one of the two CPUs (swapped
every round): both then see the same spell of the host, at one thread each (TBB follows the
affinity mask), which makes the per-round ratios steadier than runs one after the other.

  tools/bench_ab.py OLD_BENCH NEW_BENCH [--rounds 4] [--repetitions 3] [--json OUT]
                    [--taskset CPUS | --side-by-side A,B] [--time real|cpu] [--counter NAME]
                    -- [benchmark args, e.g. --benchmark_filter=...]
"""
import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path


def command(binary, args, taskset, out_name):
    return ([] if not taskset else ["taskset", "-c", taskset]) + [
        binary, *args, "--benchmark_enable_random_interleaving=true",
        f"--benchmark_out={out_name}", "--benchmark_out_format=json"]


def run(binary, args, taskset, time_key):
    with tempfile.NamedTemporaryFile(suffix=".json") as out:
        subprocess.run(command(binary, args, taskset, out.name), check=True, stdout=subprocess.DEVNULL)
        return rows_of(json.loads(Path(out.name).read_text()), time_key)


def run_side_by_side(jobs, args, time_key):
    """jobs: [(tag, binary, cpu)], all started at once, each pinned to its CPU; rows per tag."""
    with tempfile.TemporaryDirectory() as tmp:
        procs = []
        for tag, binary, cpu in jobs:
            out = str(Path(tmp) / f"{tag}.json")
            procs.append((tag, out, subprocess.Popen(command(binary, args, cpu, out), stdout=subprocess.DEVNULL)))
        got = {}
        for tag, out, proc in procs:
            if proc.wait() != 0:
                for _, _, other in procs:  # no benchmark left running on its CPU
                    other.kill()
                    other.wait()
                raise SystemExit(f"bench_ab.py: {tag} exited with {proc.returncode}")
            got[tag] = rows_of(json.loads(Path(out).read_text()), time_key)
    return got


def rows_of(doc, time_key):
    rows = {}
    for b in doc["benchmarks"]:
        if b.get("run_type") == "aggregate":
            continue
        if time_key.startswith("counter:"):  # a counter in ms, e.g. steady_ms
            ms = b.get(time_key[len("counter:"):], float("nan"))
        else:
            ms = b[time_key] * {"ms": 1.0, "us": 1e-3, "ns": 1e-6, "s": 1e3}[b.get("time_unit", "ns")]
        r = rows.setdefault(b["run_name"], {"ms": [], "deform_ms": [], "collapse_ms": [], "triangles": []})
        r["ms"].append(ms)
        for k in ("deform_ms", "collapse_ms", "triangles"):
            if k in b:
                r[k].append(b[k])
    return rows


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--rounds", type=int, default=4)
    ap.add_argument("--repetitions", type=int, default=3)
    pin = ap.add_mutually_exclusive_group()
    pin.add_argument("--taskset", default="")
    pin.add_argument("--side-by-side", default="",
                     help="two CPUs 'A,B': OLD and NEW run at the same time, pinned to A and B (swapped every "
                          "round), so that both see the same spell of the host (one thread each)")
    ap.add_argument("--json")
    ap.add_argument("--time", choices=("real", "cpu"), default="real")
    ap.add_argument("--counter", default="", help="compare this counter (ms) instead of the time, e.g. steady_ms")
    argv = sys.argv[1:]
    cut = argv.index("--") if "--" in argv else len(argv)
    a = ap.parse_args(argv[:cut])
    a.bench_args = argv[cut + 1:]
    extra = [f"--benchmark_repetitions={a.repetitions}", *a.bench_args]
    cpus = a.side_by_side.split(",") if a.side_by_side else []
    if a.side_by_side and len(cpus) != 2:
        raise SystemExit("bench_ab.py: --side-by-side wants two CPUs, e.g. 0,1")
    time_key = f"counter:{a.counter}" if a.counter else f"{a.time}_time"
    rounds = []
    for i in range(a.rounds):
        order = [("old", a.old), ("new", a.new)] if i % 2 == 0 else [("new", a.new), ("old", a.old)]
        if cpus:
            got = run_side_by_side([(tag, binary, cpus[k]) for k, (tag, binary) in enumerate(order)], extra,
                                   time_key)
            print(f"round {i + 1}/{a.rounds}: both done ({order[0][0]} on CPU {cpus[0]})", file=sys.stderr)
            rounds.append(got)
            continue
        got = {}
        for tag, binary in order:
            got[tag] = run(binary, extra, a.taskset, time_key)
            print(f"round {i + 1}/{a.rounds}: {tag} done", file=sys.stderr)
        rounds.append(got)
    names = []
    for r in rounds:
        for tag in ("old", "new"):
            names += [n for n in r[tag] if n not in names]
    table = []
    what = a.counter or "ms"
    w = max(9, len(what) + 5)
    print(f"{'benchmark':<58}{'old ' + what:>{w}}{'new ' + what:>{w}}{'new/old':>9}{'deform':>8}{'collapse':>9}{'tri':>9}")
    for n in names:
        old = [x for r in rounds for x in r["old"].get(n, {}).get("ms", [])]
        new = [x for r in rounds for x in r["new"].get(n, {}).get("ms", [])]
        ratios = [med(r["new"][n]["ms"]) / med(r["old"][n]["ms"]) for r in rounds
                  if n in r["new"] and n in r["old"]]
        counters = {k: med([x for r in rounds for x in r["new"].get(n, {}).get(k, [])])
                    for k in ("deform_ms", "collapse_ms", "triangles")}
        old_c = {k: med([x for r in rounds for x in r["old"].get(n, {}).get(k, [])])
                 for k in ("deform_ms", "collapse_ms")}
        row = {"name": n, "old_ms": med(old), "new_ms": med(new), "ratio": med(ratios),
               "ratios": ratios, **counters, "old_deform_ms": old_c["deform_ms"],
               "old_collapse_ms": old_c["collapse_ms"]}
        table.append(row)
        print(f"{n:<58}{row['old_ms']:>{w}.3f}{row['new_ms']:>{w}.3f}{row['ratio']:>9.3f}"
              f"{counters['deform_ms']:>8.3f}{counters['collapse_ms']:>9.3f}{counters['triangles']:>9.0f}")
    if a.json:
        Path(a.json).write_text(json.dumps({"rounds": a.rounds, "repetitions": a.repetitions,
                                            "time": a.counter or a.time,
                                            "args": a.bench_args, "rows": table}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
