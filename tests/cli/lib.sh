# Shared set-up of the CLI test scripts (sourced): the binary, the case, a scratch folder
# removed on exit, and the expectations. Usage in a script: source lib.sh "$@"
set -uo pipefail
M=$1
CASE=$2
ASSETS=$(cd "$(dirname "${BASH_SOURCE[0]}")/../assets" && pwd)   # tests/assets (small committed inputs)
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cd "$W"

fail() { echo "FAIL [$CASE]: $*" >&2; exit 1; }
run_ok() { "$@" >out.txt 2>err.txt || fail "exit $?: $* / stderr: $(cat err.txt)"; }
expect_exit() {  # expect_exit CODE cmd...
  local want=$1; shift
  "$@" >out.txt 2>err.txt
  local got=$?
  [ "$got" -eq "$want" ] || fail "exit $got, want $want: $* / stderr: $(cat err.txt)"
}
expect_err() { grep -qF -- "$1" err.txt || fail "stderr lacks '$1': $(cat err.txt)"; }
expect_one_line_err() { [ "$(wc -l < err.txt)" -eq 1 ] || fail "expected a one-line error, got: $(cat err.txt)"; }
expect_no_dir() { [ ! -e "$1" ] || fail "$1 must not exist after a refused run"; }
json() { python3 -c "import json,sys; d=json.load(open('$1')); print($2)"; }
py() { python3 - "$@" || fail "python check failed"; }
