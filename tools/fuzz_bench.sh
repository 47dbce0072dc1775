#!/usr/bin/env bash
# tools/fuzz_bench.sh — how far libFuzzer gets on each fuzz target.
#
#   bash tools/fuzz_bench.sh [-n RUNS] [-j JOBS] [TARGET...]
#
# Builds the fuzz preset (clang; libFuzzer, ASan, UBSan), then runs each
# target (default: all of tests/fuzz) for RUNS executions (default 10^7)
# from its committed seeds, JOBS targets at a time (default 1), and prints
# per target: executions, wall time and executions per second, coverage
# (libFuzzer's cov: edges and ft: features at the end), the corpus it grew
# to, and crashes (any crash, sanitizer report, leak or timeout; the target
# is 0). A crash's reproducer is kept in build/fuzz/bench/<target>/ and
# named; the exit status is 1 when any target crashed.
#
# 10^7 executions take from a minute (lcm_udpm) to hours (config, urdf) on
# one core; -n 100000 is a quick look.
set -euo pipefail

CMAKE=/usr/bin/cmake
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
cd "$ROOT"

runs=10000000 jobs=1
usage() { echo "usage: bash tools/fuzz_bench.sh [-n RUNS] [-j JOBS] [TARGET...]" >&2; exit 2; }
help() {
  echo "usage: bash tools/fuzz_bench.sh [-n RUNS] [-j JOBS] [TARGET...]"
  echo "Runs each fuzz target (default all) for RUNS executions (default 10^7), JOBS at a"
  echo "time (default 1), and prints executions, coverage and crashes per target."
  exit 0
}
[[ "${1:-}" == "--help" ]] && help
while getopts 'n:j:h' opt; do
  case "$opt" in
    n) runs="$OPTARG" ;;
    j) jobs="$OPTARG" ;;
    h) help ;;
    *) usage ;;
  esac
done
shift $((OPTIND - 1))
[[ "$runs" =~ ^[1-9][0-9]*$ && "$jobs" =~ ^[1-9][0-9]*$ ]] || usage

# The targets: every corpus folder, which every harness has.
if (($# == 0)); then
  mapfile -t targets < <(cd tests/fuzz/corpus && ls -d -- */ | tr -d /)
else
  targets=("$@")
fi

"$CMAKE" --preset fuzz >/dev/null
"$CMAKE" --build --preset fuzz
bin=build/fuzz/tests/fuzz
out=build/fuzz/bench
for t in "${targets[@]}"; do
  [[ -x "$bin/fuzz_$t" ]] || { echo "fuzz_bench.sh: no fuzz target '$t'" >&2; exit 2; }
done

# One target: a fresh corpus folder (new inputs go there; the seeds are
# read only), the log, and a result line "target execs secs cov ft corpus crashes".
bench_one() {
  local t=$1 dir=$out/$1
  rm -rf "$dir"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  local start=$EPOCHREALTIME rc=0
  "$bin/fuzz_$t" -runs="$runs" -timeout=10 -print_final_stats=1 \
    -artifact_prefix="$dir/artifacts/" "$dir/corpus" "tests/fuzz/corpus/$t" \
    >"$dir/fuzz.log" 2>&1 || rc=$?
  local secs
  secs="$(awk -v a="$start" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f", b - a }')"
  local last execs cov ft corp crashes
  last="$(grep -E '^#[0-9]+' "$dir/fuzz.log" | tail -n 1 || true)"
  execs="$(sed -nE 's/^stat::number_of_executed_units: *([0-9]+).*/\1/p' "$dir/fuzz.log")"
  cov="$(sed -nE 's/.* cov: ([0-9]+) .*/\1/p' <<<"$last")"
  ft="$(sed -nE 's/.* ft: ([0-9]+) .*/\1/p' <<<"$last")"
  corp="$(sed -nE 's/.* corp: ([0-9]+\/[0-9]+[a-zA-Z]*) .*/\1/p' <<<"$last")"
  crashes="$(find "$dir/artifacts" -type f | wc -l)"
  if ((rc != 0 && crashes == 0)); then crashes=1; fi
  printf '%s %s %s %s %s %s %s\n' "$t" "${execs:-0}" "$secs" "${cov:-?}" "${ft:-?}" \
    "${corp:-?}" "$crashes" >"$dir/result"
}

echo "fuzz_bench: ${#targets[@]} targets, $runs executions each, $jobs at a time"
running=0
for t in "${targets[@]}"; do
  bench_one "$t" &
  running=$((running + 1))
  if ((running >= jobs)); then
    wait -n || true
    running=$((running - 1))
  fi
done
wait

failed=0
printf '\n%-10s %12s %8s %9s %6s %7s %12s %8s\n' target executions time_s exec/s cov ft corpus crashes
while read -r t execs secs cov ft corp crashes; do
  rate="$(awk -v n="$execs" -v s="$secs" 'BEGIN { printf "%.0f", (s > 0 ? n / s : 0) }')"
  printf '%-10s %12s %8s %9s %6s %7s %12s %8s\n' "$t" "$execs" "$secs" "$rate" "$cov" "$ft" \
    "$corp" "$crashes"
  if ((crashes > 0)); then
    failed=1
    for f in "$out/$t"/artifacts/*; do
      [[ -e "$f" ]] && echo "    reproducer: $f (replay: $bin/fuzz_$t $f)"
    done
    [[ -e "$out/$t"/artifacts/ ]] && ! compgen -G "$out/$t/artifacts/*" >/dev/null \
      && echo "    exited non-zero without a reproducer: see $out/$t/fuzz.log"
  fi
done < <(for t in "${targets[@]}"; do cat "$out/$t/result"; done)
exit "$failed"
