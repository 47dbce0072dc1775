#!/bin/bash
# bench_compare.sh: bench_pipeline of this tree against an earlier commit's,
# side by side in one run.
#
# This machine's speed swings by half from run to run (2 shared cores), so
# figures from two runs apart say little. This builds REV's bench_pipeline
# and loadidd in a scratch worktree (committed code of REV; kept, and
# reused while it is at REV) and this tree's in build/release, then runs
# the two benchmarks alternately, ROUNDS times (the order swapped every
# round, so that a drift of the machine weighs on both alike), each with
# REPS repetitions on the same recording and configuration. Printed: per
# round both figures and their ratio (new / old) for the pipeline in
# memory, --offline with the files parsed and the 1.5 s estimation
# window; then the medians of the figures and of the ratios. The ratios
# are the result; the figures are this machine's at the time. Also checks
# that both loadidd --offline print the same estimates on the recording.
#
# usage: tools/bench_compare.sh [--base REV] [--rounds N] [--reps R] [--config FILE] [--recording DIR]
#
# --base: the commit to compare with (default main); --rounds: default 8;
# --reps: bench_pipeline's repetitions per round, default 5; --config:
# default host/config/loadid.yaml; --recording: default
# build/release/bench-recording (simulated as tools/setup.sh bench does
# when missing). The scratch worktree is $BENCH_COMPARE_DIR or
# /tmp/loadid-bench-base. Takes a few minutes to build REV the first time.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
base=main rounds=8 reps=5
config=$root/host/config/loadid.yaml
rec=$root/build/release/bench-recording
scratch=${BENCH_COMPARE_DIR:-/tmp/loadid-bench-base}
while [ $# -gt 0 ]; do
    case $1 in
        --base) base=$2; shift 2 ;;
        --rounds) rounds=$2; shift 2 ;;
        --reps) reps=$2; shift 2 ;;
        --config) config=$2; shift 2 ;;
        --recording) rec=$2; shift 2 ;;
        -h|--help) sed -n '2,26p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "bench_compare.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done
rev=$(git -C "$root" rev-parse --verify "$base^{commit}") ||
    { echo "bench_compare.sh: no commit $base" >&2; exit 2; }
say() { echo "bench_compare.sh: $*"; }

# REV's programs, in a scratch worktree kept between runs.
if [ "$(git -C "$scratch" rev-parse HEAD 2>/dev/null || true)" != "$rev" ]; then
    git -C "$root" worktree remove --force "$scratch" 2>/dev/null || rm -rf "$scratch"
    git -C "$root" worktree add --detach --force "$scratch" "$rev" >/dev/null 2>&1
fi
mkdir -p "$scratch/build" "$root/build/logs"
[ -e "$scratch/build/venv" ] || ln -s "$root/build/venv" "$scratch/build/venv"
log=$root/build/logs/bench_compare.log
say "building $(git -C "$root" rev-parse --short "$rev")'s bench_pipeline and loadidd in $scratch (log $log)"
(cd "$scratch" && cmake --preset release >"$log" 2>&1 &&
    cmake --build --preset release -j2 --target bench_pipeline loadidd >>"$log" 2>&1) ||
    { echo "bench_compare.sh: $base does not build (see $log)" >&2; exit 1; }
say "building this tree's (build/release)"
(cd "$root" && cmake --preset release >>"$log" 2>&1 &&
    cmake --build --preset release -j2 --target bench_pipeline loadidd loadid-traj loadid-sim >>"$log" 2>&1) ||
    { echo "bench_compare.sh: this tree does not build (see $log)" >&2; exit 1; }
old_bench=$scratch/build/release/tests/bench_pipeline new_bench=$root/build/release/tests/bench_pipeline
old_d=$scratch/build/release/host/loadidd new_d=$root/build/release/host/loadidd

if [ ! -f "$rec/can.log" ]; then
    say "simulating $rec"
    "$root/build/release/tools/loadid-traj" --config "$config" --quiet --monte-carlo 300 --candidates 1 \
        --max-evals 800 --out "$root/build/release/bench-trajectory.yaml"
    "$root/build/release/tools/loadid-sim" --config "$config" \
        --trajectory "$root/build/release/bench-trajectory.yaml" --out "$rec" --force
fi

# The same estimates from both (the JSON's numbers are printed with 17 digits).
if cmp -s <("$old_d" --config "$config" --offline "$rec" 2>/dev/null) \
          <("$new_d" --config "$config" --offline "$rec" 2>/dev/null); then
    say "loadidd --offline: the same result from both, to the last bit"
else
    say "loadidd --offline: the results differ (compare them by hand)"
fi

# One bench_pipeline run: "pipeline offline window_ms".
figures() {
    "$1" "$config" "$rec" "$reps" | awk '
        /pipeline median/ { p = $3 }
        /--offline median/ { o = $3 }
        /estimation window median/ { w = $4 }
        END { print p, o, w }'
}

printf '\n%5s  %-28s %-28s %-26s\n' round "pipeline samples/s" "--offline samples/s" "window ms"
printf '%5s  %9s %9s %7s  %9s %9s %7s  %7s %7s %7s\n' "" old new ratio old new ratio old new ratio
table=$(mktemp)
trap 'rm -f "$table"' EXIT
for ((r = 1; r <= rounds; ++r)); do
    if ((r % 2)); then o=$(figures "$old_bench"); n=$(figures "$new_bench")
    else n=$(figures "$new_bench"); o=$(figures "$old_bench"); fi
    echo "$o $n" | awk -v r="$r" '{
        printf "%5d  %9.0f %9.0f %7.2f  %9.0f %9.0f %7.2f  %7.2f %7.2f %7.2f\n",
               r, $1, $4, $4 / $1, $2, $5, $5 / $2, $3, $6, $3 / $6 }' | tee -a "$table"
done
# Medians over the rounds, columns as above (the window's ratio is old / new:
# how many times quicker).
awk '{ for (i = 2; i <= NF; ++i) v[i, NR] = $i } END {
    printf "%5s ", "median"
    for (i = 2; i <= 10; ++i) {
        n = 0; for (k = 1; k <= NR; ++k) a[++n] = v[i, k]
        for (x = 1; x <= n; ++x) for (y = x + 1; y <= n; ++y) if (a[y] < a[x]) { t = a[x]; a[x] = a[y]; a[y] = t }
        m = n % 2 ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2
        printf (i == 2 || i == 3 || i == 5 || i == 6) ? " %9.0f" : " %7.2f", m
        if (i == 4 || i == 7) printf " "
    }
    printf "\n" }' "$table"
echo
say "old: $(git -C "$root" rev-parse --short "$rev"), new: this tree; ratios new / old for samples/s, old / new for the window"
