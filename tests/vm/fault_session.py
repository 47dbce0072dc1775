"""Hand-made JR3 sessions for the fault-injection phase of the vcan VM test
(test_vcan_vm.py): recording folders (can.log of hand-made frames, lcm.log
of a still robot's joint states) that loadid-replay puts on vcan0 and LCM
one after the other while loadidd runs live (PARTS below).

What each frame should do is written down here from docs/INTERFACE.md ("JR3 over
CAN") and the kernel filter of drivers/socketcan.h (the daemon's socket
receives the standard identifiers base..base+4 only), not from the
decoder's code: every helper adds its frames and the counts they must move.

The expected counts are those of status_t (samples_saturated holds the
saturated and the faulty samples: status_t has no field for faults) plus
  est_samples      good samples sent between START and STOP (what every
                   estimator must have been fed, and nothing else)
  kernel_filtered  frames the socket's filter keeps from the daemon
  full_scale_logs  base+4 frames that change a full scale (one log line each)
"""

from __future__ import annotations

import json
import os
import struct
from collections import Counter

BASE = 0x1A0
JOINTS = 6                        # the RX60's movable joints
POSE = [0.1, -0.6, 1.2, 0.0, 0.7, 0.2]   # rad, a still pose
SAMPLE_PERIOD_US = 10_000         # 100 Hz: slow enough for TCG
JOINT_PERIOD_US = 2_000           # 500 Hz joint states
FIRST_SEQUENCE = 200              # wraps 255 -> 0 during the session
# The parts, replayed in this order; between them the VM sends `loadid
# zero` (after idle), `start` (after zeroing), `stop` (after flood). status_t
# must then count exactly what they hold. The commands come from the CLI at
# the moment they act, after the daemon has read the part before, so that
# which samples fall into zeroing and estimation does not depend on how far
# the emulated CPUs lag behind a replay's schedule.
PARTS = ("idle", "zeroing", "window", "quiet", "flood", "done")
# Good samples only, each PART_S long, while estimating: `quiet` alone and
# `flood` beside can_flood's foreign frames at the full bus rate (the VM
# reads the loop times during both).
PART_S = 4
FLOOD_RATE = 8000     # frames/s: 1 Mbit/s over 125 bits (an 8-byte frame: 111
                      # bits, up to 24 more stuffed; 10 % stuffing on average)
# A second run (`loadid start` after DONE, `stop` after it): OUTAGE_S of
# good samples, vcan0 removed 1 s in and added again 1 s later. At most
# about 2 s of samples are lost (the daemon reopens once a second), fewer
# than the 256 sequence numbers the decoder can count as a gap.
OUTAGE = "outage"
OUTAGE_S = 4
# Then a daemon of its own: OVERFLOW_PRE samples, the daemon stopped
# (SIGSTOP), OVERFLOW_BURST samples more than its socket's receive buffer
# holds (2 MiB with SO_RCVBUFFORCE as root: at most 9000 frames of 232
# bytes, a sk_buff's size without its data), the daemon continued, then
# OVERFLOW_POST samples, whose first frame brings the kernel's drop count.
OVERFLOW = ("pre", "burst", "post")
OVERFLOW_PRE = 10
OVERFLOW_BURST = 3000
OVERFLOW_BURST_PERIOD_US = 400  # the burst's samples: 1.2 s in all
OVERFLOW_POST = 10

CONFIG = """robot:
  urdf: ../robot.urdf
can:
  interface: vcan0
lcm:
  url: udpm://239.255.76.67:7667?ttl=0
estimation:
  duration_s: 30.0              # ended by `loadid stop`
zeroing:
  window_s: 30.0                # ended by `loadid start`
kalman:
  max_joint_age_s: 5.0          # a still robot: no sample may be refused as stale
  lag_s: 0.0                    # the causal filter: the parts come with seconds between
                                # them, each restarting the joint stream, and under TCG
                                # one sample at a restart was refused by the fixed-lag
                                # smoother (counted as stale); live_lcm tests the smoother live
"""


def frame_data(counts, seq, status):
    return struct.pack("<hhhBB", *counts, seq & 0xFF, status)


class Session:
    """One recording folder being written, with what it must make the
    daemon count. Times are microseconds from the session's start."""

    def __init__(self, seq, window=False, t0_us=1_700_000_000_000_000):
        self.t0 = t0_us
        self.window = window  # between START and STOP
        self.can = []       # (t, id, extended, data bytes)
        self.seq = seq
        self.exp = Counter()
        self.bad_joints = []  # t of joint states with a wrong joint count
        self.end_us = 0

    # -- frames
    def _frame(self, t, can_id, data, extended=False):
        self.can.append((t, can_id, extended, bytes(data)))
        self.end_us = max(self.end_us, t)

    def _sample(self, t, status=(0, 0, 0, 0), groups=(0, 1, 2, 3), frame_us=100):
        counts = {0: (12, -40, 1640), 1: (-15, 20, 3), 2: (0, 0, 1638), 3: (2, -1, 0)}
        for i, g in enumerate(groups):   # 0.1 ms apart, as a 4 kHz bus would
            self._frame(t + frame_us * i, BASE + g, frame_data(counts[g], self.seq, status[g]))
        self.seq = (self.seq + 1) & 0xFF

    def good(self, t, frame_us=100):
        self._sample(t, frame_us=frame_us)
        self.exp["samples_ok"] += 1
        if self.window:
            self.exp["est_samples"] += 1

    def saturated(self, t):   # bit 0 in the moment group
        self._sample(t, status=(0, 0x01, 0, 0))
        self.exp["samples_saturated"] += 1

    def faulty(self, t):      # bit 1 (sensor fault) in every group
        self._sample(t, status=(0x02, 0x02, 0x02, 0x02))
        self.exp["samples_saturated"] += 1

    def reserved(self, t):    # bit 2 in the linear frame: that frame is bad,
        self._sample(t, status=(0, 0, 0x04, 0))  # so the sample stays incomplete
        self.exp["frames_bad"] += 1
        self.exp["samples_incomplete"] += 1

    def incomplete(self, t):  # three frames of four
        self._sample(t, groups=(0, 1, 2))
        self.exp["samples_incomplete"] += 1

    def gap(self, skipped):   # sequence numbers never sent
        self.seq = (self.seq + skipped) & 0xFF
        self.exp["sequence_gaps"] += skipped

    def wrong_dlc(self, t):
        self._frame(t, BASE, frame_data((1, 2, 3), self.seq, 0)[:6])
        self.exp["frames_bad"] += 1

    def unknown_ids(self, t):  # other devices on the bus: filtered by the kernel
        self._frame(t, 0x123, frame_data((1, 2, 3), self.seq, 0))
        self._frame(t + 100, BASE + 5, frame_data((1, 2, 3), self.seq, 0))
        self.exp["kernel_filtered"] += 2

    def extended_in_sample(self, t):
        """A good sample with an extended frame of id 0x1A0 (next sequence
        number) between its second and third frame: filtered, and the
        sample stays good."""
        self._frame(t, BASE, frame_data((12, -40, 1640), self.seq, 0))
        self._frame(t + 100, BASE + 1, frame_data((-15, 20, 3), self.seq, 0))
        self._frame(t + 150, BASE, frame_data((5, 5, 5), self.seq + 1, 0),
                    extended=True)
        self._frame(t + 200, BASE + 2, frame_data((0, 0, 1638), self.seq, 0))
        self._frame(t + 300, BASE + 3, frame_data((2, -1, 0), self.seq, 0))
        self.seq = (self.seq + 1) & 0xFF
        self.exp["kernel_filtered"] += 1
        self.exp["samples_ok"] += 1
        if self.window:
            self.exp["est_samples"] += 1

    def full_scale(self, t, group, units, changes):
        self._frame(t, BASE + 4, struct.pack("<BBHHH", group, 0, *units))
        self.exp["full_scale_logs"] += 1 if changes else 0

    def malformed_full_scales(self, t):
        self._frame(t, BASE + 4, struct.pack("<BBHHH", 7, 0, 2000, 2000, 2000))  # group 7
        self._frame(t + 100, BASE + 4, struct.pack("<BBHHH", 0, 1, 2000, 2000, 2000))  # byte 1
        self._frame(t + 200, BASE + 4, struct.pack("<BBHHH", 1, 0, 1200, 0, 1200))  # zero fs
        self.exp["frames_bad"] += 3

    # -- LCM
    def bad_joint_state(self, t):
        self.bad_joints.append(t)
        self.exp["joint_msgs_bad"] += 1

    def write(self, folder, lcm_python_dir, ifname="vcan0"):
        import sys
        sys.path.insert(0, lcm_python_dir)
        import lcm
        import loadid
        os.makedirs(folder, exist_ok=True)
        with open(os.path.join(folder, "can.log"), "w") as f:
            for t, can_id, ext, data in sorted(self.can, key=lambda c: c[0]):
                tt = self.t0 + t
                ident = f"{can_id:08X}" if ext else f"{can_id:03X}"
                f.write(f"({tt // 1_000_000:010d}.{tt % 1_000_000:06d}) {ifname} "
                        f"{ident}#{data.hex().upper()}\n")
        events = []
        for t in range(0, self.end_us + 200_000, JOINT_PERIOD_US):
            m = loadid.joint_state_t()
            m.utime = self.t0 + t
            m.num_joints = JOINTS
            m.position = list(POSE)
            m.setpoint = list(POSE)
            events.append((t, "LOADID_JOINTS", m.encode()))
        for t in self.bad_joints:
            m = loadid.joint_state_t()
            m.utime = self.t0 + t
            m.num_joints = JOINTS - 1
            m.position = POSE[:-1]
            m.setpoint = POSE[:-1]
            events.append((t, "LOADID_JOINTS", m.encode()))
        log = lcm.EventLog(os.path.join(folder, "lcm.log"), "w", overwrite=True)
        for t, ch, data in sorted(events, key=lambda e: e[0]):
            log.write_event(self.t0 + t, ch, data)
        log.close()


def build(out_dir, lcm_python_dir):
    """Writes the recording folders of PARTS, OUTAGE and OVERFLOW and
    faults.yaml into out_dir; returns the counts status_t must show after
    PARTS (est_samples: the good samples between START and STOP), and
    the samples of each other part by name."""
    p = SAMPLE_PERIOD_US
    parts = {}
    seq = FIRST_SEQUENCE

    # IDLE: every kind of fault once, between good samples.
    s = Session(seq)
    t = 20_000
    for _ in range(5):
        s.good(t); t += p
    s.wrong_dlc(t); t += p
    s.unknown_ids(t); t += p
    s.extended_in_sample(t); t += p
    s.saturated(t); t += p
    s.good(t); t += p
    s.faulty(t); t += p
    s.good(t); t += p
    s.reserved(t); t += p
    s.good(t); t += p
    s.incomplete(t); t += p
    s.good(t); t += p
    s.gap(3)
    s.good(t); t += p
    s.malformed_full_scales(t); t += p
    s.full_scale(t, 0, (2500, 2500, 2500), changes=True); t += p    # 200 N -> 250 N
    s.good(t); t += p
    s.full_scale(t, 0, (2500, 2500, 2500), changes=False); t += p   # the repetition
    s.good(t); t += p
    s.full_scale(t, 0, (2000, 2000, 2000), changes=True); t += p    # back to 200 N
    s.bad_joint_state(t + 1000)
    for _ in range(5):
        s.good(t); t += p
    parts["idle"] = s

    # After `loadid zero`: good samples only (zeroing takes at least 10).
    s = Session(s.seq)
    t = 20_000
    for _ in range(15):
        s.good(t); t += p
    parts["zeroing"] = s

    # After `loadid start`, until `loadid stop`: good samples mixed with
    # every kind of fault; only the good ones may reach an estimator.
    s = Session(s.seq, window=True)
    t = 20_000
    pattern = ["good", "good", "saturated", "good", "faulty", "good", "incomplete",
               "good", "reserved", "good", "wrong_dlc", "good", "gap", "good",
               "unknown_ids", "extended_in_sample"]
    for i in range(3 * len(pattern)):
        kind = pattern[i % len(pattern)]
        if kind == "gap":
            s.gap(2)
            continue
        getattr(s, kind)(t)
        t += p
    s.good(t)  # the last sample complete: what came before is all counted
    parts["window"] = s

    def good_part(name, seq, n, period_us, window, frame_us=100):
        s = Session(seq, window=window)
        t = 20_000
        for _ in range(n):
            s.good(t, frame_us); t += period_us
        parts[name] = s
        return s.seq

    # Still estimating: the same good samples, once alone and once beside
    # the flood.
    seq = good_part("quiet", s.seq, PART_S * 1_000_000 // p, p, True)
    seq = good_part("flood", seq, PART_S * 1_000_000 // p, p, True)
    # DONE: a few good samples (compensated wrenches).
    seq = good_part("done", seq, 10, p, False)
    # The second run, with vcan0 removed and added again inside it.
    seq = good_part(OUTAGE, seq, OUTAGE_S * 1_000_000 // p, p, True)
    # The overflow: a burst of samples 0.4 ms apart (10 000 frames/s).
    seq = good_part("pre", seq, OVERFLOW_PRE, p, False)
    seq = good_part("burst", seq, OVERFLOW_BURST, OVERFLOW_BURST_PERIOD_US, False)
    good_part("post", seq, OVERFLOW_POST, p, False)

    exp = Counter()
    for name in PARTS + (OUTAGE,) + OVERFLOW:
        parts[name].write(os.path.join(out_dir, name), lcm_python_dir)
        if name in PARTS:
            exp += parts[name].exp
        with open(os.path.join(out_dir, name, "expected.json"), "w") as f:
            json.dump(dict(parts[name].exp), f)  # for the offline cross-check
    with open(os.path.join(out_dir, "faults.yaml"), "w") as f:
        f.write(CONFIG)
    with open(os.path.join(out_dir, "flood.args"), "w") as f:
        f.write(f"{FLOOD_RATE} {PART_S}\n")   # can_flood's RATE SECONDS
    exp = dict(exp)
    for k in ("samples_ok", "frames_bad", "samples_incomplete", "samples_saturated",
              "sequence_gaps", "joint_msgs_bad", "est_samples", "kernel_filtered",
              "full_scale_logs"):
        exp.setdefault(k, 0)
    return exp, {name: parts[name].exp["samples_ok"] for name in (OUTAGE,) + OVERFLOW}
