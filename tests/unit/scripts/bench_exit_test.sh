#!/usr/bin/env bash
# scripts/bench exits non-zero when a figure misses its target or a benchmark fails, and zero
# when every target is met. Runs scripts/bench on fake benchmarks (CAIRN_BENCH_BIN).
set -uo pipefail
src="$1"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/pass" "$tmp/miss" "$tmp/crash"
fig() { echo "echo 'FIGURE {\"name\": \"$1\", \"value\": 1, \"pass\": $2}'"; }
printf '#!/bin/sh\n%s\n' "$(fig t.a true)" > "$tmp/pass/bench_transport"
printf '#!/bin/sh\n%s\n%s\n' "$(fig t.a true)" "$(fig t.b false)" > "$tmp/miss/bench_transport"
printf '#!/bin/sh\n%s\nexit 3\n' "$(fig t.a true)" > "$tmp/crash/bench_transport"
chmod +x "$tmp"/*/bench_transport
fail=0
run() {  # run <case> <expected: 0 or nonzero>
  CAIRN_BENCH_BIN="$tmp/$1" CAIRN_BENCH_OUT="$tmp/out_$1" "$src/scripts/bench" transport \
    > "$tmp/$1.log" 2>&1
  local rc=$?
  if { [ "$2" = 0 ] && [ $rc -ne 0 ]; } || { [ "$2" != 0 ] && [ $rc -eq 0 ]; }; then
    echo "FAIL: case $1 exited $rc, expected $2"; cat "$tmp/$1.log"; fail=1
  else
    echo "ok: case $1 exited $rc"
  fi
}
run pass 0
run miss nonzero
run crash nonzero
grep -q "1 below target: t.b" "$tmp/miss.log" || { echo "FAIL: the missed target is not named"; fail=1; }
exit $fail
