#!/bin/bash
# mutants.sh: does the test suite catch the product getting worse?
#
# Applies each deliberate regression below, one at a time, to a scratch
# worktree of HEAD (committed code only), builds its release preset and runs
# ctest there (stopping at the first failure), then prints which mutant was
# caught, by which test, and how long it took. Every mutant must be caught.
# A script for people, not part of CI: a full run takes about 8 minutes here.
#
# usage: tools/mutants.sh [--list] [--only NAME]... [--keep] [--no-baseline]
#
# --list prints the mutants; --only runs the named ones; --keep leaves the
# scratch worktree (default $MUTANTS_DIR or /tmp/loadid-mutants); without
# --no-baseline the unmutated suite runs first and must pass, else every
# mutant would look caught.
set -euo pipefail

root=$(cd "$(dirname "$0")/.." && pwd)
python=$root/build/venv/bin/python
scratch=${MUTANTS_DIR:-/tmp/loadid-mutants}
keep=0 baseline=1 list=0
only=()
while [ $# -gt 0 ]; do
    case $1 in
        --list) list=1; shift ;;
        --only) only+=("$2"); shift 2 ;;
        --keep) keep=1; shift ;;
        --no-baseline) baseline=0; shift ;;
        -h|--help) sed -n '2,16p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "mutants.sh: unknown argument $1 (see --help)" >&2; exit 2 ;;
    esac
done
[ -x "$python" ] || { echo "mutants.sh: $python missing: run tools/setup.sh deps first" >&2; exit 1; }

# name <TAB> file <TAB> text to replace <TAB> replacement; several lines of
# one name are one mutant. Each text must occur exactly once in its file.
MUTANTS=$(cat <<'EOF'
distal-not-subtracted	host/src/pipeline/pipeline.c	loadid_phi_subtract(phi, p->distal, load);	memcpy(load, phi, sizeof load);
tls-weights-identity	firmware/src/estimator.cpp	est->cfg.row_sigma[i] = row_sigma[i];	est->cfg.row_sigma[i] = 1;
tls-weights-identity	firmware/src/estimator.cpp	est->cfg.col_weight[j] = col_weight[j];	est->cfg.col_weight[j] = 1;
tls-weights-identity	firmware/src/estimator.cpp	cfg->col_weight[j] = std::sqrt(Real(LOADID_NROWS) / col_var[j]);	cfg->col_weight[j] = 0 * col_var[j] + 1;
joint-time-skew-2ms	host/src/pipeline/pipeline.c	if (loadid_signals_push_joints(p->sig, utime, num_joints,	if (loadid_signals_push_joints(p->sig, utime + 2000, num_joints,
zeroing-term-dropped	firmware/src/regressor.cpp	out += zeroing_term(Vec3(g_init[0], g_init[1], g_init[2]));	(void)zeroing_term(Vec3(g_init[0], g_init[1], g_init[2]));
ixx-doubled	firmware/src/inertia.cpp	const Real v[6] = {Ic(0, 0),	const Real v[6] = {2 * Ic(0, 0),
riv-instruments-measured	firmware/src/signals.cpp	if (instruments) motion_of(set, *instruments);	if (instruments) motion_of(meas, *instruments);
saturation-bit-ignored	drivers/src/jr3.c	s->saturated = s->saturated || (s->status[i] & LOADID_JR3_STATUS_SATURATED);	s->saturated = s->saturated || (s->status[i] & 0);
jr3-sequence-off-by-one	drivers/src/jr3.c	(uint8_t)(seq - dec->seq - 1u)	(uint8_t)(seq - dec->seq)
gravity-in-base-frame	firmware/src/kinematics.cpp	Vec3 g = f.rot.transpose() * kin->gravity;	Vec3 g = kin->gravity;
publish-every-ignored	host/src/pipeline/pipeline.c	if (p->publish_every > 0 && ++p->since_publish >= p->publish_every) {	if (p->publish_every > 0) {
offset-share-dropped	firmware/src/uncertainty.cpp	cov = hi * meat * hi + offset_share(in, t, hi);	cov = hi * meat * hi;
offset-cov-white	host/src/pipeline/noise_model.c	f[i] = sqrt((1 + r) / (1 - r));	f[i] = 1;
lcm-one-message-a-round	host/src/daemon/lcm_link.c	for (int n = 0; n < max; ++n) {	for (int n = 0; n < 1; ++n) {
EOF
)
names=$(printf '%s\n' "$MUTANTS" | cut -f1 | uniq)
if [ "$list" = 1 ]; then printf '%s\n' "$names"; exit 0; fi
if [ ${#only[@]} -gt 0 ]; then
    for n in "${only[@]}"; do
        printf '%s\n' "$names" | grep -qx -- "$n" || { echo "mutants.sh: no mutant $n" >&2; exit 2; }
    done
    names=$(printf '%s\n' "${only[@]}")
fi

cleanup() {
    if [ "$keep" = 0 ]; then git -C "$root" worktree remove --force "$scratch" 2>/dev/null || true; fi
}
trap cleanup EXIT
git -C "$root" worktree remove --force "$scratch" 2>/dev/null || rm -rf "$scratch"
git -C "$root" worktree add --detach --force "$scratch" HEAD >/dev/null
mkdir -p "$scratch/build"
ln -s "$root/build/venv" "$scratch/build/venv"
log=$scratch/build/mutants.log
echo "mutants.sh: scratch worktree $scratch at $(git -C "$root" rev-parse --short HEAD); log $log"
(cd "$scratch" && cmake --preset release >"$log" 2>&1 && cmake --build --preset release -j2 >>"$log" 2>&1) ||
    { echo "mutants.sh: the unmutated tree does not build (see $log)" >&2; exit 1; }

# Runs ctest; prints the first failing test's name, or nothing.
run_suite() {
    (cd "$scratch" && ctest --preset release --stop-on-failure --timeout 900 >>"$log" 2>&1) && return 0
    grep -E '^\s*[0-9]+/[0-9]+ Test +#[0-9]+: ' "$log" | grep -v ' Passed ' | tail -1 |
        sed -E 's/.*Test +#[0-9]+: ([^ ]+).*/\1/'
}

if [ "$baseline" = 1 ]; then
    echo "mutants.sh: the unmutated suite first"
    : >"$log"
    failed=$(run_suite || true)
    if [ -n "$failed" ]; then echo "mutants.sh: the unmutated suite fails ($failed); see $log" >&2; exit 1; fi
fi

apply() {  # name: apply its substitutions; prints what went wrong
    printf '%s\n' "$MUTANTS" | awk -F'\t' -v n="$1" '$1 == n' | "$python" -c '
import sys, pathlib
root = pathlib.Path(sys.argv[1])
for line in sys.stdin.read().splitlines():
    _, f, old, new = line.split("\t")
    p = root / f
    s = p.read_text()
    if s.count(old) != 1:
        sys.exit(f"{f}: the text to replace occurs {s.count(old)} times: {old}")
    p.write_text(s.replace(old, new))
' "$scratch"
}

printf '\n%-26s %-8s %-28s %s\n' mutant caught "first failing test" seconds
missed=0
for name in $names; do
    t0=$(date +%s)
    : >"$log"
    if ! apply "$name" >>"$log" 2>&1; then
        printf '%-26s %-8s %s\n' "$name" ERROR "does not apply: $(tail -1 "$log")"
        missed=$((missed + 1))
        continue
    fi
    if ! (cd "$scratch" && cmake --build --preset release -j2 >>"$log" 2>&1); then
        result="ERROR" by="does not build (see the log)"
        missed=$((missed + 1))
    else
        by=$(run_suite || true)
        if [ -n "$by" ]; then result=yes; else result=NO by="-"; missed=$((missed + 1)); fi
    fi
    printf '%-26s %-8s %-28s %d\n' "$name" "$result" "$by" $(($(date +%s) - t0))
    git -C "$scratch" checkout -q -- .
    cp "$log" "$scratch/build/mutant-$name.log"
done
(cd "$scratch" && cmake --build --preset release -j2 >/dev/null 2>&1) || true
echo
if [ "$missed" = 0 ]; then echo "mutants.sh: every mutant was caught"; else echo "mutants.sh: $missed not caught"; fi
[ "$missed" = 0 ]
