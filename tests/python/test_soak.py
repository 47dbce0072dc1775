"""A minute of bench_soak (tests/bench/bench_soak.py runs an hour): one live
loadidd under SCHED_FIFO with mlockall, a recording replayed over and over
in real time (JR3 frames through a FIFO into --can-file, joint states and
commands over LCM in a private network namespace), one whole session per
pass: zeroing, estimating, REFINED on the worker, the result saved, the
compensated wrench. What a loaded 2-core CI machine cannot upset is
asserted: every session completes with the estimate --offline makes of one
pass, the resident memory does not grow after the first two sessions, no
input is refused, and SIGTERM ends the daemon with 0. The deadline figures
(samples handled more than 1 ms after arrival, the worst lateness, the
loop's p99 and max, and a bare timer's beside them) are printed, not
asserted: see test_deadline_figures_are_measured. LOADID_SOAK_SECONDS sets
the length (default 60).
"""

from __future__ import annotations

import os
import shutil

import pytest

import soak_run
from recordings import program

SECONDS = float(os.environ.get("LOADID_SOAK_SECONDS", "60"))


@pytest.fixture(scope="module")
def soak(recording, tmp_path_factory):
    if os.geteuid() != 0 or not shutil.which("unshare") or not shutil.which("ip"):
        pytest.fail("the soak needs root, unshare (util-linux) and ip (iproute2): CI runs as "
                    "root and tools/setup.sh installs both")
    work = tmp_path_factory.mktemp("soak")
    loadidd = program("LOADIDD_EXE")
    offline = soak_run.offline_reference(loadidd, recording, work)
    out = soak_run.run_soak(loadidd, recording, os.environ["LOADID_LCM_PYTHON_DIR"], SECONDS,
                            work, realtime=True)
    s = soak_run.summarize(out, recording, offline)
    print()
    print(f"soak: {SECONDS:.0f} s, {s['passes']} passes of {s['pass_s']:.3f} s, "
          "SCHED_FIFO 50 + mlockall")
    print("\n".join(soak_run.report(s, rows=12)))
    return s


def test_daemon_stops_cleanly(soak):
    assert soak["returncode"] == 0


def test_every_session_completes_with_offlines_estimate(soak):
    """Every pass is a session of its own (ZERO, START, the window, DONE,
    REFINED, the model, the saved result), and ends with the estimate
    --offline makes of one pass: the daemon carries nothing over from one
    session to the next that changes an estimate. To 1e-9 (as live_lcm's
    live-equals-offline; seen: 6e-14 over an hour) unless the loop or the
    joint states' publisher was held up 40 ms or more: 50 ms
    (TICK_GRACE_US) ends the joint smoother's piece at the next tick, also
    when the loop, not the joint stream, was late (the joint states still
    wait in the socket), and that session's on-line estimates move by about
    1e-4 (seen: up to 5.3e-4 on a machine loaded by fuzzers). Then to 1e-3,
    which still catches what carries over: a first version of this soak
    that rewrote a byte of the JR3 full-scale frames in every pass moved the
    mass 0.26 % a session."""
    ses = soak["sessions"]
    # A wall-clock step (a VM snapshot restored) desynchronises --can-file's
    # replay from the LCM side: say so rather than fail on its effects.
    steps = [m for m in soak["memory_series"] if abs(m["clock_ms"]) > 50]
    assert not steps, f"the wall clock stepped during the soak: {steps[0]}"
    assert soak["passes"] >= SECONDS / soak["pass_s"]
    assert soak["completed"] == soak["passes"], [s for s in ses if not s["complete"]][:3]
    worst = [max(s[m]["offline_rel"] for m in soak_run.METHODS.values()) for s in ses]
    held_up = soak["late"]["worst_us"] >= 40e3 or soak["publisher"]["worst_late_ms"] >= 40
    assert max(worst) < (1e-3 if held_up else 1e-9), (soak["late"], soak["publisher"], worst)
    for s in ses:
        # And sane on its own: the simulated load's mass (1 kg) within 3 %
        # and its COM within 5 mm (seen: -0.19 % and 0.07 mm for RTLS).
        assert abs(s["RTLS"]["mass_err"]) < 0.03 and s["RTLS"]["com_err_mm"] < 5, s["RTLS"]


def test_compensated_wrench_flows_in_every_session(soak):
    """wrench_t from DONE to the next ZERO of every pass (seen: about 850
    of 3300 samples a pass), all finite, and small: the load's wrench
    compensated (seen: 0.25 N RMS, the sensor's noise and vibration)."""
    assert soak["wrench_nonfinite"] == 0
    for s in soak["sessions"]:
        assert s["wrench_n"] >= 300, s
        assert s["wrench_f_rms"] < 1.0, s


def test_memory_does_not_grow_after_warm_up(soak):
    """mlockall keeps every mapped page resident, so VmRSS moves only when
    the daemon maps or touches memory: after the first two sessions (every
    path of a session has run: zeroing, the window, REFINED's worker, the
    save) it must not, by a single page, in any sample (every 5 s)."""
    mem = soak["memory"]
    assert mem["warm"] is not None, "fewer than two sessions"
    assert len(soak["memory_series"]) >= SECONDS / 5 - 2
    for key in ("VmRSS", "RssAnon"):
        assert mem[key + "_growth_kb"] == 0, (key, soak["memory_series"])
        assert mem[key + "_max_above_kb"] == 0, (key, soak["memory_series"])


def test_no_input_refused_or_lost(soak):
    """The passes join without a sequence gap or a bad frame, every sample
    is decoded, every joint state taken: the loop kept up with an endless
    input."""
    c = soak["counters"]
    assert c is not None, "no --verbose summary"
    assert c["samples_ok"] == soak["passes"] * round(soak["pass_s"] * 1000)
    assert c["frames_bad"] == c["incomplete"] == c["gaps"] == c["joint_msgs_bad"] == 0, c


def test_deadline_figures_are_measured(soak):
    """The daemon reports the samples handled more than 1 ms after they
    arrived (were due, for --can-file) and the worst lateness, and a bare
    1 ms timer one priority below it measured the machine meanwhile. The
    1 ms is not asserted: this kernel is PREEMPT_NONE (no preempt= on its
    command line), so a SCHED_FIFO thread that wakes waits until the task
    on its CPU leaves the kernel, and on 2 virtual CPUs shared with other
    builds that is milliseconds now and then: the bare timer misses 1 ms
    too (seen: 54 to 175 periods in 30 s, worst 5 to 15 ms, while the
    daemon's own events stay under 0.3 ms but for preempted ones). A bound
    here would test the machine; bench_soak.py prints the figures over an
    hour."""
    late = soak["late"]
    assert late is not None, "the --verbose summary lacks 'samples late'"
    assert late["count"] >= 0 and late["worst_us"] >= 0
    assert soak["loop"]["reports"] >= SECONDS - 5
    machine = soak["machine"]
    assert machine and machine["priority"] == 49, machine
    assert machine["periods"] >= 0.99 * soak["passes"] * soak["pass_s"] * 1000, machine
