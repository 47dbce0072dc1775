"""One live session of loadidd on a serial F/T sensor over Modbus RTU, run
inside a private network namespace by test_live_modbus.py (not collected by
pytest):

    modbus_session.py LOADIDD MODBUS_SIM CONFIG RECORDING LCM_PYTHON_DIR LINK

Sets loopback up with a multicast route, starts loadid-modbus-sim on a new
pseudo-terminal (behind the symlink LINK, the configuration's
modbus.device) serving the recording's JR3 wrench in real time from an
epoch 2 s ahead, starts loadidd live (sensor.type modbus), and publishes
the recording's joint states and commands on LCM at the same times. When
the recording ends the simulated sensor exits (the daemon must report the
device lost and go on); a second simulator then serves a constant wrench
behind the same link (the daemon must reopen it: wrench_t flows again).
Prints as JSON what came back on LOADID_ESTIMATE, LOADID_STATUS and
LOADID_WRENCH, the daemon's stderr and exit status after SIGTERM.
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
    sensor = start_sim(sim, "--recording", rec, "--config", config, "--link", link,
                       "--epoch", str(epoch))
    env = dict(os.environ)
    if os.environ.get("LOADID_DAEMON_PRELOAD"):
        env["LD_PRELOAD"] = os.environ["LOADID_DAEMON_PRELOAD"]
    daemon = subprocess.Popen([loadidd, "--config", config, "--publish-every", "100",
                               "--verbose"], stderr=subprocess.PIPE, text=True, env=env)
    shift = epoch - first_can
    for t, channel, data in events:
        pump((t + shift) / 1e6)
        cls = loadid.joint_state_t if channel == "LOADID_JOINTS" else loadid.command_t
        msg = cls.decode(data)
        msg.utime += shift
        lc.publish(channel, msg.encode())
    pump(time.time() + 0.5)
    # The recording is over: the simulated sensor exits on its own.
    sensor.wait(timeout=10)
    pump(time.time() + 2.5)  # the daemon notices (a timeout or EIO), retries once a second
    restart_us = int(time.time() * 1e6)
    sensor = start_sim(sim, "--wrench", "0,0,9.81,0,0,0", "--config", config, "--link", link)
    # Joint states go on (the last pose, now) so that wrench_t can be computed.
    last = loadid.joint_state_t.decode(next(d for _, c, d in reversed(events)
                                            if c == "LOADID_JOINTS"))
    until = time.time() + 3.0
    while time.time() < until:
        last.utime = int(time.time() * 1e6)
        lc.publish("LOADID_JOINTS", last.encode())
        pump(time.time() + 0.002)
    daemon.terminate()  # SIGTERM: a clean stop
    err = daemon.communicate(timeout=15)[1]
    sensor.terminate()
    sensor.wait(timeout=10)
    pump(time.time() + 0.3)

    print(json.dumps({
        "returncode": daemon.returncode, "stderr": err, "restart_us": restart_us,
        "estimate": [{"method": m.method, "state": m.state, "samples": m.samples,
                      "phi": list(m.phi), "mass": m.mass, "com": list(m.com)}
                     for m in got["estimate"]],
        "status": [{"state": m.state, "samples_ok": m.samples_ok, "frames_bad": m.frames_bad,
                    "samples_incomplete": m.samples_incomplete,
                    "samples_saturated": m.samples_saturated, "sequence_gaps": m.sequence_gaps,
                    "joint_msgs_bad": m.joint_msgs_bad} for m in got["status"]],
        "wrench_utimes": [m.utime for m in got["wrench"]],
    }))


if __name__ == "__main__":
    main()
