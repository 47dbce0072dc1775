"""A soak of loadidd: one live daemon fed a recording over and over in real
time for a given time, run inside a private network namespace by
tests/bench/bench_soak.py and test_soak.py (not collected by pytest):

    soak_session.py LOADIDD CONFIG RECORDING LCM_PYTHON_DIR SECONDS WORKDIR

The recording (a clean loadid-sim one: ZERO, START, back at rest at its
end) is played as one endless session after another: its JR3 frames go
through a FIFO into `loadidd --can-file` (written ahead by a child
process, each pass's times shifted by the recording's length and its JR3
sequence numbers continued, so the daemon sees one gapless stream and
replays it on its own clock), and its joint states and commands are
published on LCM at the same times (at SCHED_FIFO ten below the daemon's
when the configuration sets a priority), each pass's commands with the
load name soakK (pass K). Every pass is a whole session: zeroing,
estimating, REFINED on the worker, the result saved, the compensated
wrench. The input lasts whole passes, at least SECONDS.

Prints as JSON: the daemon's resident memory every few seconds
(/proc/PID/status), every status_t, the final estimates per pass, the
compensated wrench's statistics per pass, the saved results, the
daemon's exit status and --verbose summary (with the samples handled late),
and how late a bare 1 ms timer one priority below the daemon's woke
meanwhile (the machine's share of the lateness).
The daemon's stderr goes to WORKDIR/loadidd.log (a pipe nobody read for an
hour would fill and block it). LOADID_SOAK_RSS_EVERY: seconds between
memory samples (default 5).

    soak_session.py feed-can FIFO RECORDING PASSES

is the child that writes the passes' JR3 frames into the FIFO, and

    soak_session.py probe START END PRIORITY

the one that measures the machine's own timer latency meanwhile.
"""

from __future__ import annotations

import fcntl
import json
import math
import os
import re
import select
import struct
import subprocess
import sys
import time

import lcm

from lcm_loopback import URL, loopback_multicast, recording_streams

# live.c's throttled line: "N samples handled more than 1 ms after arrival so
# far (K new, worst W us)".
LATE_LINE = re.compile(r"loadidd: (\d+) samples handled more than 1 ms after arrival so far "
                       r"\(\d+ new, worst (\d+) us\)")
STATUS_FIELDS = ("utime", "state", "samples_ok", "frames_bad", "samples_incomplete",
                 "samples_saturated", "sequence_gaps", "joint_msgs_bad", "loop_us_p50",
                 "loop_us_p99", "loop_us_max")


def read_can(rec):
    """can.log as (time [us], head, sequence byte or None, tail): a JR3
    sample frame (base+0..3, the lowest identifier being base+0) is
    f"({t}){head}{seq:02X}{tail}" (head: " vcan0 1A0#" and bytes 0-5), any
    other line f"({t}){head}"."""
    lines = []
    with open(f"{rec}/can.log") as f:
        for line in f:
            stamp, rest = line.rstrip("\n").split(")", 1)
            sec, usec = stamp[1:].split(".")
            ident, payload = rest.split()[1].split("#", 1)
            lines.append((int(sec) * 1_000_000 + int(usec), rest, int(ident, 16), len(payload)))
    base = min(i for _, _, i, _ in lines)
    return [(t, rest[:-4], int(rest[-4:-2], 16), rest[-2:]) if base <= i <= base + 3 and n == 16
            else (t, rest, None, "") for t, rest, i, n in lines]


def pass_shape(frames):
    """A pass's length [us] and JR3 samples: the span of the base+0 frames'
    times plus one sample period. The sequence numbers must run without a
    gap (in a damaged recording every pass would repeat its gaps)."""
    base0 = min(int(head.split()[1].split("#")[0], 16) for _, head, seq, _ in frames
                if seq is not None)
    base = [(t, seq) for t, head, seq, _ in frames
            if seq is not None and int(head.split()[1].split("#")[0], 16) == base0]
    n = len(base)
    for k in range(1, n):
        if (base[k][1] - base[k - 1][1]) % 256 != 1:
            raise SystemExit(f"can.log: a sequence gap at sample {k}: a clean recording, please")
    return round((base[-1][0] - base[0][0]) * n / (n - 1)), n


def feed_can(fifo, rec, passes):
    """Writes `passes` passes of can.log into the FIFO, as fast as the
    daemon takes them (the pipe raised to 1 MB: seconds of frames ahead)."""
    frames = read_can(rec)
    length, n = pass_shape(frames)
    fd = os.open(fifo, os.O_WRONLY)
    try:
        fcntl.fcntl(fd, fcntl.F_SETPIPE_SZ, 1 << 20)
    except OSError:
        pass  # the default 64 kB (a third of a second) still works unloaded
    for k in range(passes):
        shift, add = k * length, k * n
        out = []
        for t, head, seq, tail in frames:
            t += shift
            if seq is None:
                out.append(f"({t // 1_000_000}.{t % 1_000_000:06d}){head}\n")
            else:
                out.append(f"({t // 1_000_000}.{t % 1_000_000:06d}){head}{(seq + add) & 255:02X}"
                           f"{tail}\n")
        data = memoryview("".join(out).encode())
        while data:
            data = data[os.write(fd, data):]
    os.close(fd)


def probe(start, end, priority):
    """The machine's own timer latency over the soak: a 1 ms periodic
    deadline from the wall time start to end, at SCHED_FIFO priority (0:
    normal scheduling); every period handled more than 1 ms after it was
    due counts, as the daemon counts its samples. Prints JSON."""
    if priority:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    time.sleep(max(0.0, start - time.time()))
    t = time.monotonic()
    stop = t + (end - start)
    n = late = 0
    worst = 0.0
    while t < stop:
        t += 0.001
        left = t - time.monotonic()
        if left > 0:
            time.sleep(left)
        lateness = time.monotonic() - t
        n += 1
        late += lateness > 0.001
        worst = max(worst, lateness)
    print(json.dumps({"periods": n, "late": late, "worst_us": worst * 1e6,
                      "priority": priority}))


def proc_status(pid):
    """VmRSS, RssAnon, RssFile, VmHWM, VmLck [kB] of pid, or None."""
    try:
        with open(f"/proc/{pid}/status") as f:
            return {l.split(":")[0]: int(l.split()[1]) for l in f
                    if l.startswith(("VmRSS", "RssAnon", "RssFile", "VmHWM", "VmLck"))}
    except OSError:
        return None


def main():
    if sys.argv[1] == "feed-can":
        feed_can(sys.argv[2], sys.argv[3], int(sys.argv[4]))
        return
    if sys.argv[1] == "probe":
        probe(float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4]))
        return
    loadidd, config, rec, pydir, seconds, work = sys.argv[1:7]
    sys.path.insert(0, pydir)
    import loadid as types  # lcm-gen's Python output
    loopback_multicast()
    first_can, events = recording_streams(rec)
    lc = lcm.LCM(URL)
    length, _ = pass_shape(read_can(rec))
    passes = max(1, math.ceil(float(seconds) * 1e6 / length))
    rss_every = float(os.environ.get("LOADID_SOAK_RSS_EVERY", "5"))

    # What comes back: final estimates per pass (by load name), the load
    # models, every status_t, the compensated wrench's sums per pass.
    final, models, status = {}, {}, []
    wrench = {"n": 0, "nonfinite": 0, "by_pass": {}}
    current = {"pass": -1}

    def on_estimate(channel, data):
        m = types.estimate_t.decode(data)
        if m.state == 3:  # DONE: the session's final estimate of one method
            final.setdefault(m.load_name, {})[m.method] = {
                "samples": m.samples, "mass": m.mass, "com": list(m.com),
                "inertia_com": list(m.inertia_com), "phi": list(m.phi), "utime": m.utime}

    def on_model(channel, data):
        m = types.load_model_t.decode(data)
        models[m.load_name] = {"method": m.method, "identified": m.identified,
                               "mass": m.mass, "com": list(m.com)}

    def on_status(channel, data):
        m = types.status_t.decode(data)
        status.append([getattr(m, f) for f in STATUS_FIELDS] + [time.time()])

    def on_wrench(channel, data):
        # wrench_t: fingerprint, utime, force[3], torque[3] (big-endian)
        v = struct.unpack(">6d", data[16:64])
        wrench["n"] += 1
        if not all(math.isfinite(x) for x in v):
            wrench["nonfinite"] += 1
            return
        s = wrench["by_pass"].setdefault(current["pass"], [0, 0.0, 0.0, 0.0, 0.0])
        f2, t2 = v[0] ** 2 + v[1] ** 2 + v[2] ** 2, v[3] ** 2 + v[4] ** 2 + v[5] ** 2
        s[0] += 1
        s[1] += f2
        s[2] += t2
        s[3] = max(s[3], math.sqrt(f2))
        s[4] = max(s[4], math.sqrt(t2))

    for channel, handler in (("LOADID_ESTIMATE", on_estimate), ("LOADID_MODEL", on_model),
                             ("LOADID_STATUS", on_status), ("LOADID_WRENCH", on_wrench)):
        lc.subscribe(channel, handler)

    fifo = os.path.join(work, "can.fifo")
    os.mkfifo(fifo)
    feeder = subprocess.Popen([sys.executable, os.path.abspath(__file__), "feed-can", fifo, rec,
                               str(passes)])
    epoch = int(time.time() * 1e6) + 2_000_000
    log = open(os.path.join(work, "loadidd.log"), "w")
    daemon = subprocess.Popen([loadidd, "--config", config, "--can-file", fifo,
                               "--can-file-epoch", str(epoch), "--publish-every", "100",
                               "--verbose"], stderr=log)
    # Beside it, one priority below the daemon's (SCHED_FIFO when the
    # configuration asks for it), the machine's own timer latency.
    prio = re.search(r"^  priority: (\d+)", open(config).read(), re.M)
    prober = subprocess.Popen([sys.executable, os.path.abspath(__file__), "probe",
                               str(epoch / 1e6), str((epoch + passes * length) / 1e6),
                               str(max(1, int(prio.group(1)) - 1) if prio else 0)],
                              stdout=subprocess.PIPE, text=True)
    if prio:
        # The publisher is the robot controller's real-time side: joint
        # states more than the pipeline's 0.5 s of pending samples late
        # (seen once in 10 minutes at normal priority on a loaded machine)
        # would make samples stale and a session incomplete. Children keep
        # normal scheduling.
        os.sched_setscheduler(0, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK,
                              os.sched_param(max(1, int(prio.group(1)) - 10)))
    memory = []
    wall_mono0 = time.time() - time.monotonic()
    next_rss = [time.time()]
    late = {"count": 0, "worst_us": 0.0}
    tail = open(log.name)
    pending = [""]  # a line the daemon is still writing

    def each():
        now = time.time()
        if now >= next_rss[0]:
            # The daemon's throttled line on samples handled late, as it comes.
            text = pending[0] + tail.read()
            *lines, pending[0] = text.split("\n")
            for line in lines:
                m = LATE_LINE.search(line)
                if m:
                    late["count"], late["worst_us"] = int(m.group(1)), float(m.group(2))
            m = proc_status(daemon.pid)
            if m:
                # clock_ms: how far the wall clock moved against the
                # monotonic one since the start (a step, e.g. a VM snapshot
                # restored, desynchronises --can-file's replay, which keeps
                # the wall time of its start, from the LCM side).
                clock_ms = (now - time.monotonic() - wall_mono0) * 1e3
                memory.append({"t": now - epoch / 1e6, "sessions": len(models),
                               "late": late["count"], "late_worst_us": late["worst_us"],
                               "clock_ms": clock_ms, **m})
            next_rss[0] = now + rss_every

    def pump(until):
        while True:
            each()
            left = until - time.time()
            if left <= 0:
                return
            if select.select([lc.fileno()], [], [], min(left, 0.05))[0]:
                lc.handle()

    # The recording's LCM events once, pre-encoded; a pass patches the
    # utime (the first field after the 8-byte fingerprint) and, for a
    # command, the load name.
    joint_fp = types.joint_state_t._get_packed_fingerprint()
    plan = []
    for t, channel, data in events:
        if channel == "LOADID_JOINTS" and data[:8] == joint_fp:
            plan.append((t, channel, data, None))
        elif channel == "LOADID_COMMAND":
            plan.append((t, channel, None, types.command_t.decode(data)))
    shift0 = epoch - first_can
    # How late the publisher itself got (a joint stream held up 50 ms ends
    # the daemon's smoother piece, as a real controller's would).
    publisher = {"worst_late_ms": 0.0, "worst_pass": -1}
    for k in range(passes):
        current["pass"] = k
        shift = shift0 + k * length
        for t, channel, data, cmd in plan:
            due = t + shift
            pump(due / 1e6)
            late_ms = (time.time() - due / 1e6) * 1e3
            if late_ms > publisher["worst_late_ms"]:
                publisher["worst_late_ms"], publisher["worst_pass"] = late_ms, k
            if cmd is None:
                lc.publish(channel, data[:8] + struct.pack(">q", due) + data[16:])
            else:
                cmd.utime = due
                cmd.load_name = f"soak{k}"
                lc.publish(channel, cmd.encode())
        if daemon.poll() is not None:
            break
    end_input = (epoch + passes * length) / 1e6
    if daemon.poll() is None:
        pump(max(end_input, time.time()) + 1.5)  # the last window, REFINED, the save
    current["pass"] = passes
    next_rss[0] = 0
    each()  # the memory at the end, before SIGTERM
    daemon.terminate()  # SIGTERM: a clean stop
    try:
        rc = daemon.wait(timeout=20)
    except subprocess.TimeoutExpired:
        daemon.kill()
        rc = daemon.wait()
    feeder.kill()  # gone already unless the daemon stopped reading
    feeder.wait()
    machine = json.loads(prober.communicate(timeout=60)[0] or "null")
    log.close()
    tail.close()
    pump(time.time() + 0.3)
    results_dir = os.path.join(work, "results")
    saved = sorted(n for n in os.listdir(results_dir) if n.startswith("soak")) \
        if os.path.isdir(results_dir) else []
    print(json.dumps({
        "returncode": rc, "passes": passes, "pass_us": length, "epoch": epoch,
        "log": os.path.join(work, "loadidd.log"), "memory_kb": memory, "machine": machine,
        "publisher": publisher,
        "status": status, "status_fields": list(STATUS_FIELDS) + ["received"],
        "final": final, "models": models, "saved": saved,
        "wrench": {"n": wrench["n"], "nonfinite": wrench["nonfinite"],
                   "by_pass": {k: v for k, v in wrench["by_pass"].items()}},
    }))


if __name__ == "__main__":
    main()
