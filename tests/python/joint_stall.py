"""Which sensor samples the daemon must refuse when the joint stream
stalls, computed here from the rule docs/ARCHITECTURE.md states ("A
stalled joint stream"), independently of the C code (not collected by
pytest):

* a sample is served from the newest joint state at or before it, or from
  the next one when that is within kalman.max_joint_age_s and the newest
  is not; further than max_joint_age_s from that joint state it is refused;
* a step between joint states longer than max_joint_age_s (at least two
  periods) restarts the joint filters, and the first `settle` joint states
  after a restart (or after the first) serve no sample: `settle` is the
  number of updates until the filter's predicted covariance of q, qd and
  qdd is within 1.5 times its steady state's, from its prior, here by the
  Riccati recursion in numpy.
"""

from __future__ import annotations

import bisect
import math

import lcm
import numpy as np

from recordings import program, run_tool

# The joint filter's defaults (firmware/include/loadid/joint_filter.h) and
# the daemon's (host/config/loadid.yaml).
MEAS_SIGMA = 2 * math.pi / 2**20 / math.sqrt(12)
INIT_SIGMA_VEL, INIT_SIGMA_ACC = 1.0, 10.0


def settle_steps(jerk_psd=1.0, meas_sigma=MEAS_SIGMA, dt=1e-3, factor=1.5):
    """Updates after a (re)start before the filter serves a sample."""
    F = np.array([[1, dt, dt * dt / 2], [0, 1, dt], [0, 0, 1]])
    d2, d3 = dt * dt, dt ** 3
    Q = jerk_psd * np.array([[d3 * d2 / 20, d2 * d2 / 8, d3 / 6], [d2 * d2 / 8, d3 / 3, d2 / 2],
                             [d3 / 6, d2 / 2, dt]])
    r = meas_sigma ** 2
    H = np.array([1.0, 0, 0])

    def run(steps, steady=None):
        P = np.diag([r, INIT_SIGMA_VEL ** 2, INIT_SIGMA_ACC ** 2])
        for k in range(1, steps):
            Pp = F @ P @ F.T + Q
            if steady is not None and np.all(np.diag(Pp) <= factor * steady):
                return k
            K = Pp @ H / (Pp[0, 0] + r)
            A = np.eye(3) - np.outer(K, H)
            P = A @ Pp @ A.T + r * np.outer(K, K)
        return np.diag(Pp)

    return run(100000, run(20000))


def refused(sample_times, joint_times, max_age_us=5000, settle=None, period_us=1000):
    """The sample times (us) the daemon refuses, given the times of the
    joint states it accepted (sorted)."""
    settle = settle_steps() if settle is None else settle
    max_step = max(max_age_us, 2 * period_us)
    # seq[i]: joint states since the filter's last (re)start
    seq, n = [], 0
    for i, t in enumerate(joint_times):
        n = 0 if i == 0 or t - joint_times[i - 1] > max_step else n + 1
        seq.append(n)
    out = []
    for t in sample_times:
        j = bisect.bisect_right(joint_times, t) - 1
        if j < 0:  # before every joint state: the first, when close
            j = 0
        elif t - joint_times[j] > max_age_us and j + 1 < len(joint_times) and \
                joint_times[j + 1] - t <= max_age_us:
            j += 1
        if not joint_times or abs(t - joint_times[j]) > max_age_us or seq[j] < settle:
            out.append(t)
    return out


def sample_times(rec):
    """The usable JR3 samples' times in can.log (the project's decoder)."""
    out = run_tool([program("LOADID_JR3_DECODE_LOG"), rec / "can.log"]).stdout
    return [int(f[2]) for f in (line.split() for line in out.splitlines())
            if f[0] == "S" and int(f[1]) == 1]


def joint_times(rec, lcmtypes):
    """The stamps of lcm.log's finite joint states (the others are refused
    as joint_msgs_bad), read with liblcm's reader and lcm-gen's types."""
    out = []
    for ev in lcm.EventLog(str(rec / "lcm.log"), "r"):
        if ev.channel == "LOADID_JOINTS":
            m = lcmtypes.joint_state_t.decode(ev.data)
            if all(math.isfinite(x) for x in list(m.position) + list(m.setpoint)):
                out.append(m.utime)
    return out
