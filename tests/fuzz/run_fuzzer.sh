#!/bin/sh
# run_fuzzer.sh FUZZER SEEDS WORK SECONDS [libFuzzer options]: the ctest
# test fuzz_<target>. Fuzzes for SECONDS from the committed seeds (read
# only) and the inputs earlier runs found (WORK/corpus, where new ones go).
# A crash, sanitizer report, leak or timeout fails the test and prints the
# reproducer's path (WORK/artifacts/crash-...) and how to replay it.
set -u
fuzzer=$1 seeds=$2 work=$3 seconds=$4
shift 4
mkdir -p "$work/corpus" "$work/artifacts"
rm -f "$work/artifacts/"*
set -- -max_total_time="$seconds" -timeout=10 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" "$@" "$work/corpus"
[ -d "$seeds" ] && set -- "$@" "$seeds"
"$fuzzer" "$@" >"$work/fuzz.log" 2>&1
rc=$?
# The last status line: executions, coverage (cov: edges, ft: features).
grep -E '^#[0-9]+' "$work/fuzz.log" | tail -n 1
grep -E '^stat::(number_of_executed_units|new_units_added)' "$work/fuzz.log"
found=$(ls "$work/artifacts" 2>/dev/null)
if [ "$rc" -ne 0 ] || [ -n "$found" ]; then
  echo "--- $fuzzer failed (exit $rc); the end of $work/fuzz.log:"
  tail -n 60 "$work/fuzz.log"
  for f in $found; do
    echo "reproducer: $work/artifacts/$f"
    echo "replay with: $fuzzer $work/artifacts/$f"
  done
  exit 1
fi
exit 0
