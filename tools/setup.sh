#!/usr/bin/env bash
# tools/setup.sh — install what is missing, build, and run loadid.
#
# On a fresh Debian 12 (bookworm), as root (or a user with sudo), from any
# directory:
#   bash tools/setup.sh deps        Debian packages + Python venv (build/venv)
#   bash tools/setup.sh demo [ARGS] the build's packages, the plots' Python
#                                   packages, release build, run loadid-demo
#                                   --out build/demo ARGS
#   bash tools/setup.sh test        deps, release + asan + fuzz builds, all ctest
#                                   tests (the 30 s fuzzing runs when CI=true)
#   bash tools/setup.sh bench       deps, release build, run the benchmarks
#
# System packages come only from Debian (apt-get), Python packages only from
# PyPI, pinned in tools/requirements.txt (the demo: only those of
# tools/requirements-demo.txt), installed into build/venv. Nothing
# else is downloaded. Every step is idempotent: a second run installs nothing
# and only rebuilds what changed. Each step prints one line; apt's, pip's
# and the builds' output goes to build/logs/ (its tail is shown on failure).
set -euo pipefail

# Debian packages (bookworm, main). Keep one group per line, with its reason.
# What the build and the demo need:
BUILD_PACKAGES=(
  # compilers and the build: gcc/g++/make, cmake (presets need >= 3.25), ninja
  build-essential cmake ninja-build pkg-config
  # libraries of the estimation core and of the unit tests (built with it)
  libeigen3-dev libcmocka-dev
  # the robot model: URDF reader (kinematics of the sensor frame)
  liburdfdom-dev
  # the wire formats: LCM (lcm-gen, the C library; lcm.pc requires glib's .pc)
  liblcm-dev liblcm-bin libglib2.0-dev
  # the configuration (YAML, libyaml) and the trajectory designer's optimiser (NLopt)
  libyaml-dev libnlopt-dev
  # the serial F/T sensor: Modbus RTU (libmodbus)
  libmodbus-dev
  # sd_notify for the systemd unit (Type=notify, WatchdogSec)
  libsystemd-dev
  # the Debian Python that makes build/venv (its packages come from PyPI)
  python3 python3-venv
  # HTTPS to PyPI for pip, and git for working in the clone
  ca-certificates git
)
# What only the tests (and bench_live) need besides:
TEST_PACKAGES=(
  # the fuzz preset: clang 14, and libFuzzer (libclang_rt.fuzzer), which
  # clang only recommends
  clang libclang-rt-14-dev
  # format_check: the code as .clang-format says
  clang-format
  # candump and canplayer (the VM's tests)
  can-utils
  # the live tests' private network namespace (ip; unshare is in util-linux)
  iproute2
  # the unit's test: systemd-analyze (security, syscall-filter) and strace
  systemd strace
  # the vcan test's virtual machine: qemu, busybox for its initramfs, cpio
  qemu-system-x86 busybox-static cpio
  # lcm-spy with the project's types: Java, lcm.jar, jchart2d; Xvfb and a screenshot.
  # The headless JDK compiles the jar; lcm-spy's window needs the JRE's AWT
  # X11 library (libawt_xawt.so), which only default-jre brings.
  default-jdk-headless default-jre liblcm-java libjchart2d-java xvfb imagemagick
)
DEBIAN_PACKAGES=("${BUILD_PACKAGES[@]}")

# The Debian tools, by absolute path: a different python3 or cmake that comes
# first on PATH (pyenv, pip, /usr/local) must not be picked up.
DEBIAN_PYTHON=/usr/bin/python3
CMAKE=/usr/bin/cmake
CTEST=/usr/bin/ctest
PYPI_INDEX=https://pypi.org/simple

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
cd "$ROOT"

VENV=build/venv
REQUIREMENTS=tools/requirements.txt
STAMP="$VENV/.requirements.sha256"
# The demo's plots need only numpy and matplotlib: a subset of the above.
DEMO_REQUIREMENTS=tools/requirements-demo.txt
DEMO_STAMP="$VENV/.requirements-demo.sha256"
DEMO_OUT=build/demo

usage() {
  cat <<'EOF'
usage: bash tools/setup.sh COMMAND [ARGS]

commands:
  deps         install missing Debian packages (apt-get; the build's and the
               tests') and the Python virtual environment build/venv
               (pinned, tools/requirements.txt)
  demo [ARGS]  the build's packages only (not the tests' qemu, JDK, clang)
               and the plots' Python packages (tools/requirements-demo.txt),
               build the release preset, run loadid-demo --out build/demo
               with ARGS (its table, verdicts and timing; its plots in
               build/demo)
  test         deps, build the release, asan and fuzz presets, run every ctest
               test; each fuzz target fuzzes 30 s only when CI=true or
               LOADID_FUZZ_TIME=1 (else its seeds are replayed)
  bench        deps, build the release preset, run bench_core, bench_core_float, bench_signals, bench_pipeline, bench_live
EOF
}

say() { printf '== %s  [%ss]\n' "$*" "$SECONDS"; } # seconds since start
die() { printf 'setup.sh: %s\n' "$*" >&2; exit 1; }

# quietly NAME CMD...: runs CMD with its output in build/logs/NAME.log; on
# failure prints the log's last 40 lines and where all of it is.
LOGS=build/logs
quietly() {
  local name=$1 rc=0
  shift
  mkdir -p "$LOGS"
  "$@" >"$LOGS/$name.log" 2>&1 || rc=$?
  if ((rc != 0)); then
    tail -n 40 "$LOGS/$name.log" >&2
    printf 'setup.sh: %s failed (exit %d); the whole output: %s\n' "$name" "$rc" \
      "$LOGS/$name.log" >&2
  fi
  return "$rc"
}

# --- Debian packages ---------------------------------------------------------

missing_packages() {
  local p
  for p in "${DEBIAN_PACKAGES[@]}"; do
    if [[ "$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)" != "install ok installed" ]]; then
      printf '%s\n' "$p"
    fi
  done
}

install_debian_packages() {
  command -v dpkg-query >/dev/null 2>&1 || die "needs Debian 12 (dpkg-query not found)"
  local missing
  mapfile -t missing < <(missing_packages)
  if ((${#missing[@]} == 0)); then
    say "Debian packages: all ${#DEBIAN_PACKAGES[@]} present"
    return
  fi
  local -a as_root=()
  if ((EUID != 0)); then
    command -v sudo >/dev/null 2>&1 \
      || die "must run as root to install ${missing[*]} (not root, and no sudo)"
    as_root=(sudo)
    [[ -t 0 ]] || as_root+=(-n) # no terminal to ask a password on: fail fast
  fi
  say "installing ${#missing[@]} Debian packages (log: $LOGS/apt.log): ${missing[*]}"
  quietly apt "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get update -q || exit 1
  quietly apt-install "${as_root[@]}" env DEBIAN_FRONTEND=noninteractive \
    apt-get install -y -q --no-install-recommends "${missing[@]}" || exit 1
  mapfile -t missing < <(missing_packages)
  ((${#missing[@]} == 0)) || die "apt-get did not install: ${missing[*]}"
}

# --- Python virtual environment ----------------------------------------------

# make_venv [demo]: build/venv with tools/requirements.txt, or (demo) with
# only tools/requirements-demo.txt's packages (which the full set holds).
make_venv() {
  local req=$REQUIREMENTS stamp=$STAMP
  if [[ "${1:-}" == demo ]]; then
    req=$DEMO_REQUIREMENTS stamp=$DEMO_STAMP
  fi
  # The demo's pins are the full set's: one version of each package.
  local pin
  while read -r pin; do
    [[ -z "$pin" || "$pin" == \#* ]] && continue
    grep -qxF "$pin" "$REQUIREMENTS" \
      || die "$DEMO_REQUIREMENTS: $pin is not in $REQUIREMENTS (keep the two in step)"
  done <"$DEMO_REQUIREMENTS"
  # Recreate the venv if it is broken or was made by another Python.
  if [[ -x "$VENV/bin/python" && -f "$VENV/pyvenv.cfg" ]] \
    && grep -qx 'home = /usr/bin' "$VENV/pyvenv.cfg" \
    && "$VENV/bin/python" -c '' 2>/dev/null; then
    :
  else
    say "creating Python virtual environment $VENV ($DEBIAN_PYTHON)"
    rm -rf "$VENV"
    mkdir -p build
    "$DEBIAN_PYTHON" -m venv "$VENV"
  fi

  local want full
  want="$(sha256sum "$req" | cut -d' ' -f1)"
  full="$(sha256sum "$REQUIREMENTS" | cut -d' ' -f1)"
  if [[ -f "$stamp" && "$(cat "$stamp")" == "$want" ]]; then
    say "Python packages: up to date ($req)"
    return
  fi
  if [[ "$req" != "$REQUIREMENTS" && -f "$STAMP" && "$(cat "$STAMP")" == "$full" ]]; then
    say "Python packages: up to date ($REQUIREMENTS, which holds $req)"
    return
  fi
  say "installing Python packages from PyPI ($req; log: $LOGS/pip.log)"
  rm -f "$stamp"
  # --isolated: ignore pip's configuration files and PIP_* variables (such as
  # PIP_FIND_LINKS or PIP_EXTRA_INDEX_URL), so PyPI is the only source.
  # --only-binary: the pins all have wheels; never compile one from source.
  # Debian's CA bundle (package ca-certificates) for the HTTPS to PyPI.
  local -a cert=()
  if [[ -f /etc/ssl/certs/ca-certificates.crt ]]; then
    cert=(--cert /etc/ssl/certs/ca-certificates.crt)
  fi
  quietly pip "$VENV/bin/python" -m pip install --isolated --no-input \
    --disable-pip-version-check --index-url "$PYPI_INDEX" --only-binary=:all: --timeout 60 \
    "${cert[@]}" -r "$req" || exit 1
  quietly pip-check "$VENV/bin/python" -m pip check --isolated --disable-pip-version-check \
    || exit 1
  printf '%s\n' "$want" >"$stamp"
}

# deps [test|demo]: the build's packages, and with `test` the tests' too;
# the Python packages, with `demo` only the plots'.
deps() {
  DEBIAN_PACKAGES=("${BUILD_PACKAGES[@]}")
  [[ "${1:-}" == test ]] && DEBIAN_PACKAGES+=("${TEST_PACKAGES[@]}")
  install_debian_packages
  if [[ "${1:-}" == demo ]]; then make_venv demo; else make_venv; fi
}

# --- builds ------------------------------------------------------------------

build() { # build PRESET (explicit returns: callers may test it in an `if`)
  say "configuring and building $1 (log: $LOGS/build-$1.log)"
  quietly "build-$1" sh -c '"$1" --preset "$2" && "$1" --build --preset "$2"' sh "$CMAKE" "$1" \
    || return 1
}

# run_tests PRESET [CTEST ARGS]: runs ctest, prints nothing of its own; sets
# SUMMARY.
SUMMARY=
run_tests() {
  local preset=$1 log="build/$1/ctest.log" rc=0
  shift
  say "testing $preset"
  # --no-tests=error: a suite that registered no test fails, it does not pass.
  "$CTEST" --preset "$preset" -j2 --output-on-failure --no-tests=error --timeout 900 "$@" \
    2>&1 | tee "$log" || rc=$?
  local total failed skipped
  total="$(sed -nE 's/.* tests? failed out of ([0-9]+).*/\1/p' "$log" | tail -n1)"
  failed="$(sed -nE 's/.* ([0-9]+) tests? failed out of.*/\1/p' "$log" | tail -n1)"
  skipped="$(grep -cE '^[[:space:]]+[0-9]+ - .+ \(Skipped\)$' "$log" || true)"
  if [[ -n "$total" && -n "$failed" ]]; then
    SUMMARY="$preset: $((total - failed - skipped)) passed, $failed failed, $skipped skipped"
    ((rc == 0 && failed == 0))
  else
    SUMMARY="$preset: ctest did not run (exit $rc)"
    return 1
  fi
}

cmd_test() {
  deps test
  local -a presets=(release asan fuzz) built=() summary=() args
  local i ok=1
  for i in "${!presets[@]}"; do
    if build "${presets[i]}"; then built[i]=1; else built[i]=0; fi
  done
  for i in "${!presets[@]}"; do
    args=()
    # The fuzz preset: every seed is replayed (label fuzz-replay); the
    # fuzzing itself (label fuzz, 30 s a target, two at a time) in CI, or
    # when asked for.
    if [[ "${presets[i]}" == fuzz && "${CI:-}" != true && "${LOADID_FUZZ_TIME:-}" != 1 ]]; then
      say "fuzz: replaying the seeds only (CI=true or LOADID_FUZZ_TIME=1 fuzzes each target 30 s)"
      args=(-LE '^fuzz$')
    fi
    if ((built[i] == 0)); then
      summary+=("${presets[i]}: build failed")
      ok=0
    elif run_tests "${presets[i]}" "${args[@]}"; then
      summary+=("$SUMMARY")
    else
      summary+=("$SUMMARY")
      ok=0
    fi
  done
  say "summary"
  printf '%s\n' "${summary[@]}"
  ((ok)) || { say "FAILED"; exit 1; }
}

# --- main --------------------------------------------------------------------

# The whole command runs from a function, so bash has parsed the file before
# any of it runs (an edit during a long run cannot break it).
main() {
  if (($# == 0)); then
    usage >&2
    exit 2
  fi
  cmd="$1"
  shift
  case "$cmd" in
    deps)
      (($# == 0)) || { usage >&2; exit 2; }
      deps test
      ;;
    demo)
      deps demo
      build release
      say "running build/release/tools/loadid-demo --out $DEMO_OUT${*:+ $*}"
      exec build/release/tools/loadid-demo --out "$DEMO_OUT" "$@"
      ;;
    test)
      (($# == 0)) || { usage >&2; exit 2; }
      cmd_test
      ;;
    bench)
      (($# == 0)) || { usage >&2; exit 2; }
      deps test # bench_live runs in a network namespace (iproute2)
      build release
      say "running build/release/tests/bench_core"
      build/release/tests/bench_core
      say "running build/release/tests/bench_core_float"
      build/release/tests/bench_core_float
      say "running build/release/tests/bench_signals"
      build/release/tests/bench_signals
      say "simulating a recording for bench_pipeline (build/release/bench-recording)"
      build/release/tools/loadid-traj --quiet --monte-carlo 300 --candidates 1 --max-evals 800 \
        --out build/release/bench-trajectory.yaml
      build/release/tools/loadid-sim --trajectory build/release/bench-trajectory.yaml \
        --out build/release/bench-recording --force  # made again on every run
      say "running build/release/tests/bench_pipeline"
      build/release/tests/bench_pipeline host/config/loadid.yaml build/release/bench-recording
      say "running tests/bench/bench_live.py (the live loop in a network namespace; needs root)"
      build/venv/bin/python tests/bench/bench_live.py "$PWD/build/release/host/loadidd" \
        "$PWD/build/release/host/loadid" "$PWD/build/release/bench-recording" \
        "$PWD/build/release/proto/python"
      ;;
    -h | --help | help)
      usage
      ;;
    *)
      printf 'setup.sh: unknown command: %s\n' "$cmd" >&2
      usage >&2
      exit 2
      ;;
  esac
}

main "$@"
