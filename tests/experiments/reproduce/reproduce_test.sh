#!/usr/bin/env bash
# End to end test of `meltlab reproduce` and the HTML report.
# Usage: reproduce_test.sh <meltlab> <test configs dir> <experiments/reproduce dir>
# Runs tab_2_3 (a real experiment), tiny_melt (test-only) and always_fails (its mesh does
# not exist) in quick mode; checks the summary, the reuse of finished experiments on a second
# run, that a changed config is run again, and the report in headless Chromium; then the
# stress_summary report kind on tiny_stress (two small meshes in float and double).
set -uo pipefail
M=$1
TEST_CONFIGS=$2
REAL_CONFIGS=$3
CASE=end_to_end
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"
fail() { echo "FAIL [$CASE]: $*" >&2; exit 1; }
PY=/usr/bin/python3

cp -r "$TEST_CONFIGS" tc   # a copy, so the test can change a config
repro() { "$M" reproduce --quick --configs "$REAL_CONFIGS" --configs tc --only tab_2_3,tiny_melt,always_fails --out out "$@"; }

# --- bad input: one-line error, exit 2
"$M" reproduce --quick --configs tc --only nope --out bad >o.txt 2>e.txt; rc=$?
[ $rc -eq 2 ] || fail "--only nope: exit $rc, want 2"
[ "$(wc -l <e.txt)" -eq 1 ] && grep -q "no experiment 'nope'" e.txt || fail "--only nope: $(cat e.txt)"
[ ! -e bad ] || fail "a refused run wrote its output folder"

# --- modes: a full-only experiment is left out of quick runs and refused by --only
"$M" reproduce --quick --configs tc --list --out bad >o.txt 2>e.txt || fail "--list: $(cat e.txt)"
grep -q "tiny_melt" o.txt && ! grep -q "full_only" o.txt || fail "quick --list: $(cat o.txt)"
"$M" reproduce --configs tc --list --out bad >o.txt 2>e.txt || fail "--list (full): $(cat e.txt)"
grep -q "full_only" o.txt || fail "full --list lacks full_only: $(cat o.txt)"
"$M" reproduce --quick --configs tc --only full_only --out bad >o.txt 2>e.txt; rc=$?
[ $rc -eq 2 ] && grep -q "runs only in full mode" e.txt || fail "--quick --only full_only: exit $rc: $(cat e.txt)"
[ ! -e bad ] || fail "a refused run wrote its output folder"

# --- first run: two experiments finish, the failing one is listed with its error (exit 1)
repro >run1.out 2>run1.err; rc=$?
[ $rc -eq 1 ] || fail "first run: exit $rc, want 1 (one failed experiment): $(cat run1.err)"
grep -q "always_fails: FAILED" run1.err || fail "no FAILED progress line: $(cat run1.err)"
grep -q "tab_2_3: step 1/8" run1.err || fail "no step progress lines"
grep -Eq "^2 ran, 0 reused, 1 failed" run1.out || fail "summary line: $(cat run1.out)"
$PY - <<'PY' || fail "summary.json after the first run"
import json
s = json.load(open("out/summary.json"))
st = {e["name"]: e for e in s["experiments"]}
assert set(st) == {"tab_2_3", "tiny_melt", "always_fails"}, st.keys()
assert st["tab_2_3"]["status"] == "ran" and st["tiny_melt"]["status"] == "ran", st
f = st["always_fails"]
assert f["status"] == "failed" and "no_such_mesh_for_the_test" in f["error"] and "exited with code 2" in f["error"], f
assert [x["name"] for x in f["steps"]] == ["run"], f["steps"]  # the report step did not run after the failure
for n in ("tab_2_3", "tiny_melt"):
    d = json.load(open(f"out/{n}/done.json"))
    assert d["hash"] == st[n]["hash"] and len(d["steps"]) == len(st[n]["steps"]), d
import os
assert not os.path.exists("out/always_fails/done.json")
# the real experiment's numbers: every row of Tab. 2.3 comes out exactly (polygon forms)
import csv
rows = {r["mesh"]: r for r in csv.DictReader(open("out/tab_2_3/tab_2_3.csv"))}
assert len(rows) == 6 and all(r["identical"] == "yes" for r in rows.values()), rows
assert all(r["chi meltlab"] == "0" for r in rows.values()), rows
PY

# --- the report: every figure and CSV the HTML names exists, every table has rows
R=out/report/index.html
[ -s "$R" ] || fail "no report"
$PY - "$R" <<'PY' || fail "report contents"
import sys, os
from html.parser import HTMLParser
class P(HTMLParser):
    def __init__(self):
        super().__init__(); self.imgs, self.links, self.tables, self.in_tbody, self.rows = [], [], [], False, 0
    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img": self.imgs.append(a["src"])
        if tag == "a" and a.get("href", "").endswith(".csv"): self.links.append(a["href"])
        if tag == "tbody": self.in_tbody, self.rows = True, 0
        if tag == "tr" and self.in_tbody: self.rows += 1
    def handle_endtag(self, tag):
        if tag == "tbody": self.in_tbody = False; self.tables.append(self.rows)
p = P(); text = open(sys.argv[1]).read(); p.feed(text)
base = os.path.dirname(sys.argv[1])
assert len(p.imgs) >= 2, p.imgs
for src in p.imgs:
    f = os.path.join(base, src)
    assert os.path.isfile(f) and open(f, "rb").read(8) == b"\x89PNG\r\n\x1a\n", f
for href in p.links:
    assert os.path.isfile(os.path.join(base, href)), href
assert len(p.tables) >= 4 and all(n >= 1 for n in p.tables), p.tables
assert "FAILED" in text and "no_such_mesh_for_the_test" in text
assert "Tab. 2.3" in text and "Intel Core 2 Duo P8400" in text
print(len(p.imgs), "figures,", len(p.tables), "tables")
PY

# --- headless Chromium renders it: a non-empty, non-uniform screenshot; the DOM has the figures
export HOME=$W   # chromium writes its profile there
timeout 120 chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1200,2400 \
  --screenshot="$W/shot.png" "file://$W/$R" >chrome.out 2>chrome.err || fail "chromium screenshot: $(tail -3 chrome.err)"
[ -s shot.png ] || fail "empty screenshot"
timeout 120 chromium --headless --no-sandbox --disable-gpu --dump-dom "file://$W/$R" >dom.html 2>>chrome.err \
  || fail "chromium dump-dom: $(tail -3 chrome.err)"
$PY - <<'PY' || fail "screenshot / DOM"
import matplotlib.image as mpimg
a = mpimg.imread("shot.png")
assert a.shape[0] >= 2000 and a.shape[1] >= 1000, a.shape
assert a[..., :3].std() > 0.05, a[..., :3].std()   # not a blank page
dom = open("dom.html").read()
assert "meltlab reproduction report" in dom
assert dom.count("<img") == open("out/report/index.html").read().count("<img") and dom.count("<img") >= 2
PY

# --- second run: the finished experiments are reused (their folders untouched), the failing one fails again
stamp=$(stat -c %y out/tiny_melt/done.json)
sleep 1
repro >run2.out 2>run2.err; rc=$?
[ $rc -eq 1 ] || fail "second run: exit $rc"
grep -Eq "^0 ran, 2 reused, 1 failed" run2.out || fail "second run summary: $(cat run2.out)"
grep -q "tiny_melt: reused" run2.err || fail "no reuse progress line"
[ "$(stat -c %y out/tiny_melt/done.json)" = "$stamp" ] || fail "reused folder rewritten"
[ -s out/report/index.html ] || fail "report not rebuilt"

# --- --only one of them: the other finished experiment stays in the summary and the report as "kept"
"$M" reproduce --quick --configs "$REAL_CONFIGS" --configs tc --only tiny_melt --out out >run2b.out 2>&1 || fail "--only: $(cat run2b.out)"
grep -Eq "^0 ran, 1 reused, 0 failed .* 1 more kept" run2b.out || fail "kept: $(cat run2b.out)"
$PY - <<'PY' || fail "kept experiment in the summary and the report"
import json
st = {e["name"]: e["status"] for e in json.load(open("out/summary.json"))["experiments"]}
assert st == {"tiny_melt": "reused", "tab_2_3": "kept"}, st
assert 'id="tab_2_3"' in open("out/report/index.html").read()
PY

# --- a changed config (another cycle count) is run again; --force runs a finished one again
sed -i 's/quick: 40/quick: 30/' tc/tiny_melt.yaml
"$M" reproduce --quick --configs tc --only tiny_melt --out out --no-report >run3.out 2>run3.err || fail "third run: $(cat run3.err)"
grep -Eq "^1 ran, 0 reused, 0 failed" run3.out || fail "changed config not rerun: $(cat run3.out)"
[ "$($PY -c "import json; print(json.load(open('out/tiny_melt/run/run.json'))['cycles_requested'])")" = 30 ] || fail "not rerun with 30 cycles"
"$M" reproduce --quick --configs tc --only tiny_melt --out out --no-report --force >run4.out 2>&1 || fail "--force"
grep -Eq "^1 ran, 0 reused" run4.out || fail "--force did not run again: $(cat run4.out)"
echo "ok [$CASE]"

# --- the stress_summary report kind: two small meshes melted away in float and double
CASE=stress_summary
"$M" reproduce --quick --configs tc --only tiny_stress --out out_stress --no-report >s.out 2>s.err || fail "tiny_stress: $(cat s.err)"
$PY - <<'PY' || fail "stress_summary.csv / report.json"
import csv, json
rows = list(csv.DictReader(open("out_stress/tiny_stress/stress_summary.csv")))
assert len(rows) == 4, rows
for r in rows:
    assert r["status"] == "melted" and int(r["cycles survived"]) > 0, r
    # --check-every 10 until the mesh is gone: one check per 10 cycles survived (and cycle 0)
    assert int(r["topology checks passed"]) >= int(r["cycles survived"]) // 10, r
by = {(r["mesh"], r["precision"]): r for r in rows}
assert int(by[("torus", "float")]["self-intersection checks"]) > 1, by
for mesh in ("torus", "icosphere_3"):
    f, d = by[(mesh, "float")], by[(mesh, "double")]
    drift = float(f["max |V_float - V_double| / V0 (while V >= 0.1 V0)"])
    # Float and double differ (else the precision flag did nothing) by rounding only: these
    # meshes keep the same triangle counts in both precisions, so the volumes differ by the
    # float rounding of a few hundred cycles (measured 1e-7 .. 4e-7 of V0), far below 1e-4.
    assert f["first cycle with different triangle counts"] == "never", f
    assert 0 < drift < 1e-4, (mesh, drift)
    assert f["cycles survived"] == d["cycles survived"], (f, d)
j = json.load(open("out_stress/tiny_stress/report.json"))
assert j["matches"] is True and j["verdict"].startswith("4 of 4 runs"), j
PY
echo "ok [$CASE]"
