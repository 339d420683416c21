#!/usr/bin/env python3
"""Every subcommand with a run folder writes the one provenance record (core/provenance.h).

Runs simulate, compare, fit, render, synth-sequence and manufacture at tiny sizes and asserts
that each record file carries a "provenance" object of the same shape: the same keys, the
same hardware keys, this binary's version and git revision, the command line as given (one
list element per argument), UTC timestamps in order and timings_s with a total; and that the
old scattered fields (meltlab_version, git_revision, hardware, ... at the top level) are gone.

Usage: provenance_test.py <meltlab binary>
"""
import json
import os
import re
import subprocess
import sys
import tempfile

KEYS = {"subcommand", "meltlab", "hardware", "command_line", "started_utc", "finished_utc", "timings_s", "batch_job"}
HARDWARE_KEYS = {"cpu", "threads", "host", "tbb_default_concurrency"}
OPTIONAL_HARDWARE_KEYS = {"caches", "caches_source"}  # where the machine tells (Linux sysfs, else CPUID)
OLD_TOP_LEVEL = {"meltlab", "meltlab_version", "git_revision", "command", "command_line", "hardware",
                 "started_utc", "finished_utc"}
STAMP = re.compile(r"^\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ$")


def fail(msg):
    print(f"FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


def run(argv):
    r = subprocess.run(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        fail(f"exit {r.returncode}: {' '.join(argv)} / stderr: {r.stderr.strip()}")
    return r.stdout


def main():
    meltlab = os.path.abspath(sys.argv[1])
    for k in [k for k in os.environ if k.startswith("SLURM")]:
        del os.environ[k]  # the suite may itself run inside a Slurm job
    version_line = run([meltlab, "--version"]).strip()  # "meltlab <version> (<git revision>)"
    m = re.fullmatch(r"meltlab (\S+) \((\S+)\)", version_line)
    if not m:
        fail(f"unexpected --version output: {version_line!r}")
    version, revision = m.groups()

    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        # (subcommand, argv after the binary, record file)
        runs = [
            ("synth-sequence", ["synth-sequence", "--mesh", "airplane", "--photos", "3", "--cycles-per-photo", "5",
                                "--width", "160", "--height", "120", "--seed", "3", "--out", "seq"],
             "seq/truth/truth.json"),
            ("simulate", ["simulate", "--mesh", "airplane", "--cycles", "10", "--out", "run"], "run/run.json"),
            ("compare", ["compare", "--sim", "run", "--observations", "seq/manifest.yaml", "--cycles-per-photo", "5",
                         "--out", "cmp"], "cmp/compare.json"),
            ("fit", ["fit", "--mesh", "airplane", "--observations", "seq/manifest.yaml", "--cycles-per-photo", "5",
                     "--fit", "kg", "--out", "fit"], "fit/fit.json"),
            ("render", ["render", "--mesh", "benchmark_a", "--cycles", "2", "--every", "2", "--width", "32",
                        "--height", "24", "--mask-resolution", "32", "--out", "ren"], "ren/render.json"),
            ("manufacture", ["manufacture", "--mesh", "giraffe", "--photos", "2", "--interval-s", "600",
                             "--voxel-mm", "8", "--width", "160", "--height", "120", "--out", "man"],
             "man/truth/truth.json"),
            ("volume render", ["volume", "render", "--scene", "vol.yaml", "--out", "vol"], "vol/render.json"),
            ("fog render", ["fog", "render", "--scene", "sphere", "--width", "16", "--height", "12", "--table-n", "8",
                            "--out", "fog"], "fog/render.json"),
            ("fog bench", ["fog", "bench", "--study", "model", "--repeats", "1", "--out", "fogb"], "fogb/bench.json"),
        ]
        with open("vol.yaml", "w") as f:
            f.write("model: hg\nvolume: {generate: {kind: turbulence_sphere, size: 8}}\n"
                    "camera: {type: pinhole, width: 16, height: 16, fov_deg: 45, eye: [400, -550, 300], "
                    "target: [0, 0, 0]}\n")
        shapes = {}
        for subcommand, args, record in runs:
            run([meltlab] + args)
            with open(record) as f:
                j = json.load(f)
            p = j.get("provenance")
            if not isinstance(p, dict):
                fail(f"{record}: no provenance object")
            if set(p) != KEYS:
                fail(f"{record}: provenance keys {sorted(p)} != {sorted(KEYS)}")
            if not HARDWARE_KEYS <= set(p["hardware"]) <= HARDWARE_KEYS | OPTIONAL_HARDWARE_KEYS:
                fail(f"{record}: hardware keys {sorted(p['hardware'])}: want {sorted(HARDWARE_KEYS)} "
                     f"(and optionally {sorted(OPTIONAL_HARDWARE_KEYS)})")
            hw = p["hardware"]
            if ("caches" in hw) != ("caches_source" in hw) or hw.get("caches_source", "sysfs") not in ("sysfs", "cpuid"):
                fail(f"{record}: caches {hw.get('caches')!r} from {hw.get('caches_source')!r}: both or neither, "
                     "from sysfs or cpuid")
            for level, size in hw.get("caches", {}).items():
                if not re.fullmatch(r"L[1-4][di]?", level) or not re.fullmatch(r"[1-9][0-9]*K", str(size)):
                    fail(f"{record}: cache {level} {size!r}: want a level L1d..L4 and a size like 1024K")
            if not isinstance(p["hardware"]["threads"], int) or p["hardware"]["threads"] < 1:
                fail(f"{record}: hardware.threads {p['hardware']['threads']!r}")
            if p["subcommand"] != subcommand:
                fail(f"{record}: subcommand {p['subcommand']!r} != {subcommand!r}")
            if p["meltlab"] != {"version": version, "git_revision": revision}:
                fail(f"{record}: meltlab {p['meltlab']} != --version's {version} ({revision})")
            if p["command_line"] != [meltlab] + args:
                fail(f"{record}: command_line {p['command_line']} != {[meltlab] + args}")
            for k in ("started_utc", "finished_utc"):
                if not STAMP.match(p[k]):
                    fail(f"{record}: {k} {p[k]!r} is not an ISO-8601 UTC timestamp")
            if p["started_utc"] > p["finished_utc"]:
                fail(f"{record}: started {p['started_utc']} after finished {p['finished_utc']}")
            t = p["timings_s"]
            if not isinstance(t.get("total"), (int, float)) or t["total"] < 0:
                fail(f"{record}: timings_s.total missing or negative: {t}")
            # outside a batch job (the test clears SLURM_* below); the Slurm test checks the object
            if p["batch_job"] is not None:
                fail(f"{record}: batch_job {p['batch_job']!r} outside a batch job")
            left = OLD_TOP_LEVEL & set(j)
            if left:
                fail(f"{record}: provenance fields still at the top level: {sorted(left)}")
            shapes[subcommand] = (tuple(sorted(p)), tuple(sorted(p["hardware"])))
        if len(set(shapes.values())) != 1:
            fail(f"provenance shapes differ between subcommands: {shapes}")
        print("provenance: one shape in", ", ".join(r[2] for r in runs))


if __name__ == "__main__":
    main()
