"""One live session of loadidd over LCM, run inside a private network
namespace by test_live_lcm.py (not collected by pytest):

    live_session.py LOADIDD CONFIG RECORDING LCM_PYTHON_DIR LOADID_CLI [no-commands]

Sets loopback up with a multicast route, starts loadidd live with the
recording's can.log as its CAN source (replayed from an epoch 1.5 s ahead),
publishes the recording's joint states and commands on LCM at the same
times, and prints as JSON what came back on LOADID_ESTIMATE, LOADID_STATUS
and LOADID_WRENCH; then asks the CLI for the status, resets the daemon
through the CLI, asks again, and stops the daemon with SIGTERM.
LOADID_DAEMON_PRELOAD in the environment is the daemon's LD_PRELOAD (only
the daemon's). LOADID_SESSION_FLOOD_HZ in the environment: a second LCM
handle publishes that many messages a second on foreign channels (other
robots' joint states and a camera's, 100-400 bytes) from the daemon's start
to its stop; the count sent is in the JSON ("flood_sent").
LOADID_SESSION_STALL=T0:T1[,T2:T3...] (recording utimes): the joint states
stamped in those spans are not published (the joint stream stalls and
resumes), the daemon runs with --verbose, and the session ends when the
recording reaches LOADID_SESSION_UNTIL (a recording utime, if given),
without the CLI's calls. LOADID_SESSION_FREEZE=T0:T1 (recording utimes):
the daemon is stopped (SIGSTOP) from T0 to T1 while the streams go on, as
a loop the kernel did not run for that long; --verbose as with a stall.
"shift" in the JSON is the daemon's clock less the recording's.
"""

from __future__ import annotations

import atexit
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

import lcm

from lcm_loopback import open_session


def main():
    loadidd, config, rec, pydir, cli = sys.argv[1:6]
    with_commands = len(sys.argv) < 7 or sys.argv[6] != "no-commands"
    loadid, first_can, events, lc, out = open_session(pydir, rec)  # lcm-gen's types as loadid
    got = out.got

    # systemd's side of Type=notify: a datagram socket in NOTIFY_SOCKET.
    notify_dir = tempfile.mkdtemp(prefix="loadid-notify-")
    atexit.register(shutil.rmtree, notify_dir, True)
    notify_path = os.path.join(notify_dir, "notify")
    notify = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
    notify.bind(notify_path)
    notify.setblocking(False)
    env = dict(os.environ, NOTIFY_SOCKET=notify_path, WATCHDOG_USEC="200000")
    # test_live_no_alloc.py: the allocation counter, preloaded into the
    # daemon only (it writes its report to LOADID_ALLOC_REPORT at exit).
    if os.environ.get("LOADID_DAEMON_PRELOAD"):
        env["LD_PRELOAD"] = os.environ["LOADID_DAEMON_PRELOAD"]

    stalls = [tuple(int(x) for x in span.split(":"))
              for span in os.environ.get("LOADID_SESSION_STALL", "").split(",") if span]
    until = int(os.environ.get("LOADID_SESSION_UNTIL", "0")) or None
    freeze = [int(x) for x in os.environ.get("LOADID_SESSION_FREEZE", "").split(":") if x]
    frozen = False
    epoch = int(time.time() * 1e6) + 1_500_000
    daemon = subprocess.Popen([loadidd, "--config", config, "--can-file", f"{rec}/can.log",
                               "--can-file-epoch", str(epoch), "--publish-every", "100",
                               *(["--verbose"] if stalls or freeze else [])],
                              stderr=subprocess.PIPE, text=True, env=env)
    flood = {"sent": 0, "stop": threading.Event()}

    def flood_lcm(hz):
        # Bursts every millisecond, paced against the clock.
        fl = lcm.LCM("udpm://239.255.76.67:7667?ttl=0")
        payloads = [(b"R2_LOADID_JOINTS", bytes(100)), (b"LOADID_JOINTS_X", bytes(180)),
                    (b"CAMERA_FRAME_META", bytes(400))]
        t0, k = time.time(), 0
        while not flood["stop"].is_set():
            due = int((time.time() - t0) * hz)
            while k < due:
                ch, data = payloads[k % len(payloads)]
                fl.publish(ch.decode(), data)
                k += 1
            time.sleep(0.001)
        flood["sent"] = k

    flooder = None
    if os.environ.get("LOADID_SESSION_FLOOD_HZ"):
        flooder = threading.Thread(target=flood_lcm,
                                   args=(float(os.environ["LOADID_SESSION_FLOOD_HZ"]),))
        flooder.start()
    sched = None  # /proc/PID/stat: fields 40 (rt_priority) and 41 (policy)
    shift = epoch - first_can

    notes = []

    def drain_notify():
        # systemd reads its socket at once; so must we, or the daemon's
        # sd_notify blocks when the datagram queue is full.
        while True:
            try:
                notes.append(notify.recv(4096).decode())
            except BlockingIOError:
                return

    def pump(until):
        out.pump(until, drain_notify)

    for t, channel, data in events:
        if until and t >= until:
            break
        pump((t + shift) / 1e6)
        if freeze and not frozen and freeze[0] <= t < freeze[1]:
            daemon.send_signal(signal.SIGSTOP)
            frozen = True
        elif frozen and t >= freeze[1]:
            daemon.send_signal(signal.SIGCONT)
            frozen, freeze = False, []
        if channel == "LOADID_JOINTS" and any(t0 <= t < t1 for t0, t1 in stalls):
            continue  # the stream stalls
        if channel == "LOADID_JOINTS":
            msg = loadid.joint_state_t.decode(data)
            msg.utime += shift
        elif with_commands:
            msg = loadid.command_t.decode(data)
            msg.utime += shift
        else:
            continue
        lc.publish(channel, msg.encode())
        if sched is None and daemon.poll() is None and t + shift > epoch + 500_000:
            status = open(f"/proc/{daemon.pid}/status").read()
            stat = open(f"/proc/{daemon.pid}/stat").read().rsplit(")", 1)[1].split()
            sched = {"policy": int(stat[38]), "rt_priority": int(stat[37]),
                     "cpus": next(l.split()[1] for l in status.splitlines()
                                  if l.startswith("Cpus_allowed_list")),
                     "vmlck_kb": int(next(l.split()[1] for l in status.splitlines()
                                          if l.startswith("VmLck")))}
    pump(time.time() + (0.3 if until else 1.5))  # the last samples (and wrenches after DONE)
    memory = {}
    if daemon.poll() is None:
        for line in open(f"/proc/{daemon.pid}/status"):
            if line.startswith(("VmHWM", "VmRSS", "VmLck")):
                memory[line.split(":")[0]] = int(line.split()[1])

    def cli_run(*args):
        r = subprocess.run([cli, "--config", config, *args], capture_output=True, text=True,
                           timeout=20)
        return {"rc": r.returncode, "out": r.stdout, "err": r.stderr}

    cli_log = []
    if not until:
        cli_log = [cli_run("status", "--timeout", "3"), cli_run("reset")]
        pump(time.time() + 0.2)
        cli_log.append(cli_run("status", "--timeout", "3"))
    daemon.terminate()  # SIGTERM: a clean stop
    deadline = time.time() + 10
    while daemon.poll() is None and time.time() < deadline:
        drain_notify()
        time.sleep(0.02)
    err = daemon.communicate(timeout=10)[1]
    if flooder:
        flood["stop"].set()
        flooder.join()
    pump(time.time() + 0.3)
    drain_notify()

    def est(m):
        return {"method": m.method, "state": m.state, "samples": m.samples, "phi": list(m.phi),
                "utime": m.utime,
                "load_name": m.load_name, "mass": m.mass}

    print(json.dumps({
        "returncode": daemon.returncode, "stderr": err, "cli": cli_log, "notify": notes,
        "sched": sched, "memory_kb": memory, "reencoded_differ": out.reencoded_differ,
        "flood_sent": flood["sent"], "shift": shift,
        "estimate": [est(m) for m in got["estimate"]],
        "status": [{"state": m.state, "samples_ok": m.samples_ok, "frames_bad": m.frames_bad,
                    "samples_incomplete": m.samples_incomplete,
                    "samples_saturated": m.samples_saturated, "sequence_gaps": m.sequence_gaps,
                    "joint_msgs_bad": m.joint_msgs_bad, "p50": m.loop_us_p50,
                    "p99": m.loop_us_p99, "max": m.loop_us_max} for m in got["status"]],
        "wrench": [list(m.force) + list(m.torque) for m in got["wrench"]],
        "model": [{"method": m.method, "identified": m.identified, "projected": m.projected,
                   "phi": list(m.phi), "phi_std": list(m.phi_std), "mass": m.mass,
                   "com": list(m.com), "inertia_com": list(m.inertia_com),
                   "load_name": m.load_name} for m in got["model"]],
    }))


if __name__ == "__main__":
    main()
