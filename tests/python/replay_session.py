"""One session of loadidd --replay over LCM, run inside a private network
namespace by test_live_replay.py (not collected by pytest):

    replay_session.py LOADIDD CONFIG RECORDING LCM_PYTHON_DIR

Sets loopback up with a multicast route, starts loadidd with --replay
RECORDING (the daemon replays the recording's JR3 frames, joint states and
commands itself, in real time; no CAN, nothing published by this side),
collects what comes back on LOADID_ESTIMATE, LOADID_STATUS, LOADID_WRENCH
and LOADID_MODEL until the recording has been replayed (its span after the
daemon's start, and a second more), stops the daemon with SIGTERM and
prints it all as JSON. LOADID_DAEMON_PRELOAD in the environment is the
daemon's LD_PRELOAD (only the daemon's).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

from lcm_loopback import open_session


def main():
    loadidd, config, rec, pydir = sys.argv[1:5]
    _, first_can, events, _, out = open_session(pydir, rec)
    span_s = (max(events[-1][0], first_can) - min(events[0][0], first_can)) / 1e6
    t0 = time.time()
    # The allocation counter, preloaded into the daemon only (test_live_replay.py).
    env = dict(os.environ)
    if os.environ.get("LOADID_DAEMON_PRELOAD"):
        env["LD_PRELOAD"] = os.environ["LOADID_DAEMON_PRELOAD"]
    daemon = subprocess.Popen([loadidd, "--config", config, "--replay", rec, "--verbose"],
                              stderr=subprocess.PIPE, text=True, env=env)
    out.pump(t0 + span_s + 1.5)
    daemon.terminate()  # SIGTERM: a clean stop
    err = daemon.communicate(timeout=20)[1]
    out.pump(time.time() + 0.3)
    got = out.got
    print(json.dumps({
        "returncode": daemon.returncode, "stderr": err, "span_s": span_s,
        "estimate": [{"method": m.method, "state": m.state, "samples": m.samples,
                      "phi": list(m.phi), "utime": m.utime, "load_name": m.load_name}
                     for m in got["estimate"]],
        "status": [{"utime": m.utime, "state": m.state, "samples_ok": m.samples_ok,
                    "frames_bad": m.frames_bad, "sequence_gaps": m.sequence_gaps,
                    "joint_msgs_bad": m.joint_msgs_bad} for m in got["status"]],
        "wrench": len(got["wrench"]),
        "model": [{"method": m.method, "phi": list(m.phi)} for m in got["model"]],
        "wall_start_us": int(t0 * 1e6),
    }))


if __name__ == "__main__":
    main()
