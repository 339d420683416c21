#!/usr/bin/env bash
# Integration test of the Slurm executor on a real single-node Slurm cluster started here
# (tests/slurm/local_cluster.sh: munged, slurmctld and slurmd from Debian's slurm-wlm and munge,
# a generated slurm.conf, all inside a temporary folder; stopped at the end).
# Usage: slurm_test.sh <meltlab> <repository>
# Exit 77 (ctest: skipped) with a message only when the packages are missing and cannot be
# installed, or the daemons cannot start on this machine.
#   1. reproduce tab_2_3 (real), tiny_melt and always_fails (test configs) locally and on Slurm:
#      the same results (byte-identical CSVs), the failed job reported with its Slurm state and
#      log, nothing half-written taken as done; host, job id and array index in the provenance
#   2. a second Slurm run reuses the finished experiments
#   3. --detach, scancel of a running job, the collecting run reports it CANCELLED, the next run
#      resumes only the steps that had not finished
#   4. a sweep locally and as a job array: byte-identical sweep.csv, reuse on a second run
set -uo pipefail
M=$(realpath "$1")
REPO=$(realpath "$2")
W=$(mktemp -d)
CLUSTER=$W/cluster
cleanup() {
  "$REPO/tests/slurm/local_cluster.sh" stop "$CLUSTER" >/dev/null 2>&1
  rm -rf "$W"
}
trap cleanup EXIT
cd "$W"
CASE=setup
fail() {
  echo "FAIL [$CASE]: $*" >&2
  for f in "$CLUSTER"/log/slurmctld.log "$CLUSTER"/log/slurmd.log; do
    [ -f "$f" ] && { echo "--- tail $f" >&2; tail -5 "$f" >&2; }
  done
  exit 1
}
PY=/usr/bin/python3

# --- the packages (scripts/install-deps installs them; try once more if missing) and the cluster
export PATH=$PATH:/usr/sbin
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  "$REPO/scripts/install-deps" >install.log 2>&1 ||
    { echo "SKIP: slurm-wlm/munge not installed and scripts/install-deps failed: $(tail -1 install.log)"; exit 77; }
fi
start_out=$("$REPO/tests/slurm/local_cluster.sh" start "$CLUSTER" $$ 2>start.err)
rc=$?
if [ $rc -eq 77 ]; then echo "SKIP: $(cat start.err)"; exit 77; fi
[ $rc -eq 0 ] || fail "local_cluster.sh start: exit $rc: $(cat start.err)"
eval "$start_out"
[ -n "${SLURM_CONF:-}" ] || fail "no SLURM_CONF from local_cluster.sh"
echo "cluster up: $(sinfo -h -o '%P %D %t %c')"
# the test's own jobs: small, so several run at once on this one node
SL=(--executor slurm --poll-seconds 0.3 --cpus 1 --mem 300M --time 0:10:00)
TC=$REPO/tests/experiments/reproduce/configs
SC=$REPO/tests/slurm/configs
REAL=$REPO/experiments/reproduce
ONLY=tab_2_3,tiny_melt,always_fails

# --- 1. the same experiments locally and on Slurm
CASE=reproduce
"$M" reproduce --quick --configs "$REAL" --configs "$TC" --only $ONLY --out local --no-report >l.out 2>l.err
[ $? -eq 1 ] || fail "local run: want exit 1 (always_fails): $(tail -3 l.err)"
"$M" reproduce --quick --configs "$REAL" --configs "$TC" --only $ONLY --out slurm "${SL[@]}" >s.out 2>s.err
rc=$?
[ $rc -eq 1 ] || fail "Slurm run: exit $rc, want 1: $(tail -5 s.err)"
grep -Eq "^2 ran, 0 reused, 1 failed" s.out || fail "Slurm summary: $(cat s.out)"
grep -q "tab_2_3: submitted 8 step(s) as Slurm job(s)" s.err || fail "no submission line: $(head -5 s.err)"
grep -q "tab_2_3: submitted 8 step(s) as Slurm job(s) [0-9]* (array of 7), [0-9]*$" s.err ||
  fail "tab_2_3's seven independent steps are not one job array before the report: $(grep submitted s.err)"
# (a step shorter than one poll may go from PENDING to COMPLETED without being seen RUNNING)
grep -Eq "tiny_melt: step 1/3 run: (RUNNING|COMPLETED) \(Slurm job [0-9]+" s.err || fail "no progress line of tiny_melt"
grep -q "tiny_melt: step 3/3 report: COMPLETED (Slurm job [0-9]* on $(hostname))" s.err ||
  fail "no COMPLETED line naming the host: $(grep tiny_melt s.err)"
grep -q "always_fails: FAILED on Slurm" s.err || fail "no FAILED line: $(tail -5 s.err)"
$PY - <<'PY' || fail "summary, the failure report, done.json"
import json, os
s = json.load(open("slurm/summary.json"))
assert s["executor"] == "slurm", s["executor"]
st = {e["name"]: e for e in s["experiments"]}
assert st["tab_2_3"]["status"] == "ran" and st["tiny_melt"]["status"] == "ran", st
f = st["always_fails"]
# the failed job: its Slurm state, the step's error and both log paths, which exist
assert f["status"] == "failed", f
err = f["error"]
assert "step run: Slurm job" in err and "FAILED" in err, err
assert "no_such_mesh_for_the_test" in err and "step exited with code 2" in err, err
logs = err[err.index("(logs: ") + 7:err.index(")", err.index("(logs: "))].split(", ")
assert all(os.path.isfile(p) for p in logs), logs
assert logs[0].endswith("always_fails/logs/run.err") and "slurm/logs/job-" in logs[1], logs
# nothing half-written taken as done: the failed experiment has no done.json, its report step never ran
assert not os.path.exists("slurm/always_fails/done.json")
assert not os.path.exists("slurm/always_fails/slurm/steps/report.json")
for n in ("tab_2_3", "tiny_melt"):
    d = json.load(open(f"slurm/{n}/done.json"))
    assert d["hash"] == st[n]["hash"] and d["executor"] == "slurm" and len(d["slurm_jobs"]) >= 1, d
    local = json.load(open(f"local/{n}/done.json"))
    assert [x["name"] for x in d["steps"]] == [x["name"] for x in local["steps"]], d["steps"]
    assert all(x["exit_code"] == 0 for x in d["steps"])
# provenance: the run folder of a step, and every step record, name the host, the job and the array task
run = json.load(open("slurm/tiny_melt/run/run.json"))["provenance"]
job = run["batch_job"]
assert job["scheduler"] == "slurm" and job["job_id"] and job["array_task_id"] is None, job
assert run["hardware"]["host"], run["hardware"]
assert json.load(open("local/tiny_melt/run/run.json"))["provenance"]["batch_job"] is None
tasks = set()
for name in os.listdir("slurm/tab_2_3/slurm/steps"):
    r = json.load(open(f"slurm/tab_2_3/slurm/steps/{name}"))
    bj = r["provenance"]["batch_job"]
    assert r["exit_code"] == 0 and bj["job_id"] and r["provenance"]["hardware"]["host"], r
    if bj["array_task_id"] is not None:
        tasks.add((bj["array_job_id"], int(bj["array_task_id"])))
assert len(tasks) == 7 and sorted(t for _, t in tasks) == list(range(7)), tasks
PY
# the same results: every CSV byte-identical (the columns of measured times, "ms", cut out first)
$PY - <<'PY' || fail "CSV files differ between the local and the Slurm run"
import os, re, sys
timing = re.compile(r"(^ms$|_ms$| ms$|_seconds$|^seconds$)")
n = 0
for exp in ("tab_2_3", "tiny_melt"):
    for folder, _, names in os.walk(f"local/{exp}"):
        for name in sorted(names):
            if not name.endswith(".csv"):
                continue
            a = os.path.join(folder, name)
            b = "slurm" + a[len("local"):]
            la, lb = open(a).read().split("\n"), open(b).read().split("\n")
            keep = [i for i, c in enumerate(la[0].split(",")) if not timing.search(c)]
            cut = lambda lines: "\n".join(",".join(l.split(",")[i] for i in keep if i < len(l.split(","))) for l in lines)
            assert la[0] == lb[0], (a, la[0], lb[0])
            assert cut(la) == cut(lb), f"{a} and {b} differ"
            n += 1
assert n >= 3, n
print(n, "CSV files identical")
PY
$PY "$REPO/tools/compare_trees.py" local/tab_2_3 slurm/tab_2_3 >cmp1.txt ||
  fail "tab_2_3 differs: $(tail -5 cmp1.txt)"
$PY "$REPO/tools/compare_trees.py" local/tiny_melt slurm/tiny_melt --ignore '*/summary.png' >cmp2.txt ||
  fail "tiny_melt differs: $(tail -5 cmp2.txt)"
echo "ok [$CASE]"

# --- 2. a second run reuses the finished experiments; the failed one is resubmitted and fails again
CASE=reuse
stamp=$(stat -c %y slurm/tiny_melt/done.json)
"$M" reproduce --quick --configs "$REAL" --configs "$TC" --only $ONLY --out slurm "${SL[@]}" >s2.out 2>s2.err
[ $? -eq 1 ] || fail "second run: want exit 1: $(tail -3 s2.err)"
grep -Eq "^0 ran, 2 reused, 1 failed" s2.out || fail "second run: $(cat s2.out)"
[ "$(stat -c %y slurm/tiny_melt/done.json)" = "$stamp" ] || fail "a reused folder was rewritten"
# and a local run reuses what Slurm finished (one hash, whichever executor made the folder)
"$M" reproduce --quick --configs "$REAL" --configs "$TC" --only tab_2_3,tiny_melt --out slurm --no-report >l2.out 2>&1
grep -Eq "^0 ran, 2 reused, 0 failed" l2.out || fail "local run over the Slurm folder: $(cat l2.out)"
echo "ok [$CASE]"

# --- 3. detach, cancel a running job, collect (reported), resume
CASE=cancel
MELTLAB_TEST_SLEEP_S=120 "$M" reproduce --configs "$SC" --only cancel_me --out c "${SL[@]}" --detach >d.out 2>d.err
rc=$?
[ $rc -eq 0 ] || fail "--detach: exit $rc: $(tail -3 d.err)"
grep -q "1 still on Slurm" d.out || fail "--detach summary: $(cat d.out)"
[ "$($PY -c "import json; print(json.load(open('c/summary.json'))['experiments'][0]['status'])")" = submitted ] ||
  fail "summary status after --detach"
# a local run does not run over a submission that is not collected (its jobs write into the folder)
"$M" reproduce --configs "$SC" --only cancel_me --out c --no-report >lc.out 2>&1
[ $? -eq 1 ] && grep -q "submitted to Slurm .* and not collected" lc.out || fail "local run over live jobs: $(cat lc.out)"
slow_job=$($PY -c "import json; p=json.load(open('c/cancel_me/slurm/plan.json')); print([j['id'] for j in p['jobs'] if j['steps']==['slow']][0])")
for _ in $(seq 300); do
  [ "$(squeue -h -j "$slow_job" -o %T 2>/dev/null)" = RUNNING ] && break
  sleep 0.2
done
[ "$(squeue -h -j "$slow_job" -o %T)" = RUNNING ] || fail "the slow job never ran: $(squeue -h -o '%i %T %r')"
scancel "$slow_job" || fail "scancel $slow_job"
"$M" reproduce --configs "$SC" --only cancel_me --out c "${SL[@]}" >c1.out 2>c1.err
rc=$?
[ $rc -eq 1 ] || fail "collecting run: exit $rc, want 1: $(tail -3 c1.err)"
grep -q "cancel_me: collecting the Slurm jobs submitted" c1.err || fail "did not collect: $(head -3 c1.err)"
grep -q "step slow: Slurm job $slow_job CANCELLED" c1.out || fail "cancel not reported: $(cat c1.out)"
grep -q "c/cancel_me/slurm/logs/job-1.log" c1.out || fail "no Slurm log path: $(cat c1.out)"
[ ! -e c/cancel_me/done.json ] || fail "a cancelled experiment got done.json"
[ ! -e c/cancel_me/slurm/steps/slow.json ] || fail "the cancelled step has a record"
info_record=$(stat -c %y c/cancel_me/slurm/steps/info.json)
"$M" reproduce --configs "$SC" --only cancel_me --out c "${SL[@]}" >c2.out 2>c2.err || fail "resume: $(tail -3 c2.err)"
grep -q "cancel_me: resubmitted 2 step(s)" c2.err || fail "not resumed with the two unfinished steps: $(grep -i submitted c2.err)"
grep -Eq "^1 ran, 0 reused, 0 failed" c2.out || fail "resume summary: $(cat c2.out)"
[ "$(stat -c %y c/cancel_me/slurm/steps/info.json)" = "$info_record" ] || fail "the finished step ran again"
[ -s c/cancel_me/slow/slept.txt ] && [ -s c/cancel_me/done.json ] && [ -s c/report/index.html ] || fail "resumed run incomplete"
echo "ok [$CASE]"

# --- 4. a sweep: locally and as a Slurm job array, the same sweep.csv; reused the second time
CASE=sweep
SW=$REPO/tests/slurm/sweeps/tiny_sweep.yaml
"$M" sweep --config "$SW" --out sw_local --no-report >w1.out 2>w1.err || fail "local sweep: $(tail -3 w1.err)"
"$M" sweep --config "$SW" --out sw_slurm --executor slurm --poll-seconds 0.3 >w2.out 2>w2.err ||
  fail "Slurm sweep: $(tail -3 w2.err)"
grep -q "tiny_sweep: submitted 6 step(s) as Slurm job(s) [0-9]* (array of 4)" w2.err || fail "points not one array: $(grep submitted w2.err)"
cmp sw_local/tiny_sweep/sweep.csv sw_slurm/tiny_sweep/sweep.csv || fail "sweep.csv differs"
[ "$(wc -l <sw_slurm/tiny_sweep/sweep.csv)" -eq 5 ] || fail "sweep.csv: $(cat sw_slurm/tiny_sweep/sweep.csv)"
for m in triangles_final volume_final status; do
  [ -s "sw_slurm/tiny_sweep/sweep_$m.png" ] || fail "no figure for $m"
done
grep -q "sweep_volume_final.png" sw_slurm/report/index.html || fail "the sweep's figures are not in the report"
"$M" sweep --config "$SW" --out sw_slurm --executor slurm --poll-seconds 0.3 >w3.out 2>w3.err || fail "second sweep"
grep -Eq "^0 ran, 1 reused" w3.out || fail "sweep not reused: $(cat w3.out)"
echo "ok [$CASE]"
echo "slurm: 4 passed, 0 failed"
