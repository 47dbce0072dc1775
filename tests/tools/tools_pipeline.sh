#!/bin/sh
# The tools end to end on every build (release and the sanitizers): design
# a trajectory, simulate a clean and a damaged recording (every kind of
# damage at once), compute their condition numbers, and refuse bad input
# with a message and a non-zero exit. Sanitizer findings fail the run.
# And loadidd --offline over both recordings.
# Usage: tools_pipeline.sh TRAJ SIM KAPPA LOADIDD WORKDIR
set -eu
traj=$1 sim=$2 kappa=$3 loadidd=$4 work=$5
rm -rf "$work" && mkdir -p "$work"

"$traj" --monte-carlo 40 --candidates 1 --max-evals 80 --quiet --out "$work/traj.yaml" \
    --setpoints "$work/setpoints.csv"
"$sim" --trajectory "$work/traj.yaml" --out "$work/clean"
"$sim" --trajectory "$work/traj.yaml" --out "$work/damaged" --damage bit-errors=0.05 \
    --damage drop-frames=0.02 --damage skip-samples=0.01 --damage saturate=0.01 \
    --damage fault=0.01 --damage bad-frames=0.01 --damage nan-joints=0.01 \
    --damage stall-joints=1.0:1.1 --load-phi 2,0.1,0,0.05,0.01,0,0,0.012,0,0.008
grep -q "phi: \[2, 0.10000000000000001, 0, 0.050000000000000003" "$work/damaged/truth.yaml"
for f in can.log lcm.log truth.yaml; do
    test -s "$work/clean/$f" && test -s "$work/damaged/$f"
done
"$kappa" "$work/clean" "$work/damaged" > "$work/kappa.txt"
test "$(wc -l < "$work/kappa.txt")" -eq 3

printf 'estimation:\n  methods: [RTLS, RIV, RLS, LS_BATCH, TLS_BATCH]\n' > "$work/all.yaml"
"$loadidd" --config "$work/all.yaml" --offline "$work/clean" --result "$work/clean.json"
# The damaged recording lacks joint data for 0.1 s of the window (the
# stall): incomplete, so exit 3 and "complete": false, unless allowed.
set +e
"$loadidd" --config "$work/all.yaml" --offline "$work/damaged" > "$work/damaged.json" \
    2> "$work/damaged.err"
rc=$?
set -e
test "$rc" -eq 3 || { echo "damaged: expected exit 3, got $rc" >&2; cat "$work/damaged.err" >&2; exit 1; }
grep -q "incomplete recording: joint data missing" "$work/damaged.err"
"$loadidd" --config "$work/all.yaml" --offline "$work/damaged" --allow-incomplete --verbose \
    > "$work/damaged.json"
test "$(grep -c '"method"' "$work/clean.json")" -eq 5
test "$(grep -c '"method"' "$work/damaged.json")" -eq 5
test "$(grep -c '"complete": true' "$work/clean.json")" -eq 5
test "$(grep -c '"complete": false' "$work/damaged.json")" -eq 5

# Bad input: a clear one-line reason and exit status 1 or 2, never a crash.
expect_refusal() {
    set +e
    "$@" > "$work/out.txt" 2> "$work/err.txt"
    rc=$?
    set -e
    if [ "$rc" -ne 1 ] && [ "$rc" -ne 2 ]; then
        echo "expected exit 1 or 2 from: $*; got $rc" >&2
        cat "$work/err.txt" >&2
        exit 1
    fi
    grep -q . "$work/err.txt" || { echo "no message from: $*" >&2; exit 1; }
}
printf 'format: loadid-trajectory-1\nq0: [0, 0]\n' > "$work/short.yaml"
printf 'robot: [not, a, mapping]\n' > "$work/bad_config.yaml"
expect_refusal "$sim" --trajectory "$work/short.yaml" --out "$work/x"
expect_refusal "$sim" --trajectory "$work/missing.yaml" --out "$work/x"
expect_refusal "$sim" --trajectory "$work/traj.yaml" --out "$work/x" --damage melt=1
expect_refusal "$sim" --config "$work/bad_config.yaml" --trajectory "$work/traj.yaml" --out "$work/x"
expect_refusal "$traj" --config "$work/bad_config.yaml"
grep -q "bad_config.yaml:1: robot" "$work/err.txt" || { cat "$work/err.txt" >&2; exit 1; }
expect_refusal "$traj" --monte-carlo 0
expect_refusal "$sim" --trajectory "$work/traj.yaml" --out "$work/x" --load-phi 1,2,3
expect_refusal "$kappa" "$work/nothing"
expect_refusal "$loadidd" --config "$work/all.yaml" --offline "$work/nothing"
expect_refusal "$loadidd" --config "$work/bad_config.yaml" --offline "$work/clean"
expect_refusal "$loadidd" --offline "$work/clean"
echo "tools pipeline: ok"
