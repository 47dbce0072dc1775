"""One live session of loadidd on a serial F/T sensor over Modbus RTU, run
inside a private network namespace by test_live_modbus.py (not collected by
pytest):

    modbus_session.py LOADIDD MODBUS_SIM CONFIG RECORDING LCM_PYTHON_DIR LINK

Sets loopback up with a multicast route, starts loadid-modbus-sim on a new
pseudo-terminal (behind the symlink LINK, the configuration's
modbus.device) serving the recording's JR3 wrench in real time from an
epoch 2 s ahead, starts loadidd live (sensor.type modbus, --verbose), and
publishes the recording's joint states and commands on LCM at the same
times. On the recording's timeline (PLAN, seconds after its first sample)
the sensor vanishes twice and comes back behind the same link, serving the
same recording from the same epoch: once after zeroing and before START
(the estimate comes after it), once while DONE (the compensated wrench
shows when its samples are used again); the second sensor leaves some
reads unanswered and answers some with a bad CRC. Before the recording
ends the last sensor goes too, then the daemon is stopped. Prints as JSON what came back on LOADID_ESTIMATE,
LOADID_STATUS and LOADID_WRENCH, the daemon's stderr and exit status after
SIGTERM, and for each sensor its stderr (its own tally of what it answered)
and the wall times it was ready and gone.
LOADID_DAEMON_PRELOAD in the environment is the daemon's LD_PRELOAD (only
the daemon's: test_live_no_alloc.py's allocation counter).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

from lcm_loopback import open_session

# Seconds after the recording's first sample (ZERO at 0.05 s, zeroing until
# 0.25 s, START at 1.0 s, DONE at 2.5 s, its end at 3.3 s).
PLAN = {"lost": [0.30, 2.70], "back": [0.40, 2.90], "silent": (0.70, 0.85),
        "bad_crc": (0.88, 0.93), "until": 3.20}


def start_sim(sim, *args):
    p = subprocess.Popen([sim, *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for line in p.stdout:  # "pty /dev/pts/N", "link PATH", "samples N"
        if line.startswith("samples"):
            return p
    raise RuntimeError("loadid-modbus-sim did not start: " + p.stderr.read())


def main():
    loadidd, sim, config, rec, pydir, link = sys.argv[1:7]
    loadid, first_can, events, lc, out = open_session(pydir, rec)  # lcm-gen's types as loadid
    got = out.got
    pump = out.pump

    epoch = int(time.time() * 1e6) + 2_000_000
    # --loop: the last sensor must not end with the recording before the
    # daemon does (one more loss).
    common = ["--recording", rec, "--config", config, "--link", link, "--epoch", str(epoch),
              "--loop"]
    sensors = []  # {"proc", "ready_us", "gone_us", "stderr"}

    def sensor_up(*extra):
        p = start_sim(sim, *common, *extra)
        sensors.append({"proc": p, "ready_us": int(time.time() * 1e6)})

    def sensor_down():
        s = sensors[-1]
        s["proc"].terminate()  # it closes the pty and removes the link
        s["stderr"] = s["proc"].communicate(timeout=10)[1]
        s["gone_us"] = int(time.time() * 1e6)

    sensor_up()
    env = dict(os.environ)
    if os.environ.get("LOADID_DAEMON_PRELOAD"):
        env["LD_PRELOAD"] = os.environ["LOADID_DAEMON_PRELOAD"]
    daemon = subprocess.Popen([loadidd, "--config", config, "--publish-every", "100",
                               "--verbose"], stderr=subprocess.PIPE, text=True, env=env)
    faults = ["--silent", "%g:%g" % PLAN["silent"], "--bad-crc", "%g:%g" % PLAN["bad_crc"]]
    actions = sorted([(t, sensor_down, ()) for t in PLAN["lost"]] +
                     [(PLAN["back"][0], sensor_up, faults), (PLAN["back"][1], sensor_up, ())],
                     key=lambda a: a[0])
    shift = epoch - first_can
    for t, channel, data in events:
        rel = (t - first_can) / 1e6
        if rel >= PLAN["until"]:
            break
        pump((t + shift) / 1e6)
        while actions and actions[0][0] <= rel:
            _, act, args = actions.pop(0)
            act(*args)
        cls = loadid.joint_state_t if channel == "LOADID_JOINTS" else loadid.command_t
        msg = cls.decode(data)
        msg.utime += shift
        lc.publish(channel, msg.encode())
    # The last sensor goes first, so that the daemon's counts at exit hold
    # every read any sensor answered (a third loss).
    sensor_down()
    pump(time.time() + 0.1)
    daemon.terminate()  # SIGTERM: a clean stop
    err = daemon.communicate(timeout=15)[1]
    pump(time.time() + 0.3)

    print(json.dumps({
        "returncode": daemon.returncode, "stderr": err, "plan": PLAN,
        "sensors": [{k: v for k, v in s.items() if k != "proc"} for s in sensors],
        "estimate": [{"method": m.method, "state": m.state, "samples": m.samples,
                      "phi": list(m.phi), "mass": m.mass, "com": list(m.com)}
                     for m in got["estimate"]],
        "status": [{"state": m.state, "samples_ok": m.samples_ok, "frames_bad": m.frames_bad,
                    "samples_incomplete": m.samples_incomplete,
                    "samples_saturated": m.samples_saturated, "sequence_gaps": m.sequence_gaps,
                    "joint_msgs_bad": m.joint_msgs_bad} for m in got["status"]],
        "wrench_utimes": [m.utime for m in got["wrench"]],
        "wrench": [list(m.force) + list(m.torque) for m in got["wrench"]],
    }))


if __name__ == "__main__":
    main()
