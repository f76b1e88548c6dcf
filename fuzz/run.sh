#!/usr/bin/env bash
# Runs one fuzz target for a fixed time with the limits that make unbounded allocation and hangs
# findings, then prints libFuzzer's final figures in one line (docs/fuzzing.md).
#
#   fuzz/run.sh TARGET [SECONDS] [more libFuzzer flags...]
#
# New inputs go to fuzz/work/TARGET (ignored by git), seeded from fuzz/corpus/TARGET (committed);
# a crash, timeout or out-of-memory input is written to fuzz/artifacts/TARGET/. Needs a nightly
# toolchain and `cargo install cargo-fuzz`.
set -euo pipefail
cd "$(dirname "$0")"
target=${1:?usage: fuzz/run.sh TARGET [SECONDS] [libFuzzer flags...]}
seconds=${2:-900}
shift $(($# < 2 ? $# : 2))
mkdir -p "work/$target"
log="work/$target.log"
start=$(date -u +%Y-%m-%dT%H:%MZ)
status=0
cargo +nightly fuzz run "$target" "$PWD/work/$target" "$PWD/corpus/$target" -- \
    -rss_limit_mb=2048 -malloc_limit_mb=2048 -timeout=10 -max_total_time="$seconds" \
    -print_final_stats=1 "$@" >"$log" 2>&1 || status=$?
# The last status line (#N ... cov: C ft: F corp: U/S ...) and the final statistics.
last=$(grep -E '^#[0-9]+' "$log" | tail -n 1 || true)
stat() { grep -E "^stat::$1:" "$log" | awk '{print $2}' | tail -n 1; }
cov=$(sed -nE 's/.* cov: ([0-9]+).*/\1/p' <<<"$last")
ft=$(sed -nE 's/.* ft: ([0-9]+).*/\1/p' <<<"$last")
corp=$(sed -nE 's/.* corp: ([0-9]+)\/([0-9]+[a-zA-Z]*).*/\1 inputs, \2/p' <<<"$last")
echo "$target: started $start, ${seconds} s: $(stat number_of_executed_units) executions," \
    "$(stat average_exec_per_sec) exec/s, cov $cov, ft $ft, corpus $corp," \
    "peak RSS $(stat peak_rss_mb) MB, exit $status"
if [ "$status" -ne 0 ]; then
    grep -iE 'error|panicked|SUMMARY|Test unit written' "$log" | head -n 20 || true
fi
exit "$status"
