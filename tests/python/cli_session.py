"""The CLI's commands against no daemon and against a real one, run inside
a private network namespace by test_live_cli.py (not collected by pytest):

    cli_session.py LOADIDD LOADID_CLI WORKDIR

Sets loopback up with a multicast route; runs `loadid` commands with no
daemon on the LCM network, then starts loadidd live (an empty candump log
as its CAN source: no sensor data, no joint states) and runs commands
against it; then stops the daemon with SIGTERM. Prints as JSON every CLI
run (arguments, exit status, stdout, stderr, seconds taken) and the
daemon's exit status and stderr.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

from lcm_loopback import URL, loopback_multicast


def main():
    loadidd, cli, work = sys.argv[1:4]
    loopback_multicast()
    cfg = os.path.join(work, "c.yaml")
    with open(cfg, "w") as f:
        # offset_model estimate: START needs no completed ZERO, so that
        # start can take effect without sensor data; a window that lasts
        # until the reset, however slow the machine.
        f.write(f"lcm:\n  url: {URL}\nestimation:\n  offset_model: estimate\n"
                "  duration_s: 60\n")
    empty = os.path.join(work, "empty.log")
    open(empty, "w").close()
    runs = []

    def cli_run(name, *args):
        t0 = time.monotonic()
        r = subprocess.run([cli, "--config", cfg, *args], capture_output=True, text=True,
                           timeout=30)
        runs.append({"name": name, "args": list(args), "rc": r.returncode, "out": r.stdout,
                     "err": r.stderr, "seconds": time.monotonic() - t0})

    cli_run("no daemon: zero", "--timeout", "1.5", "zero")
    cli_run("no daemon: status", "--timeout", "1", "status")

    daemon = subprocess.Popen([loadidd, "--config", cfg, "--can-file", empty],
                              stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 15
    while time.monotonic() < deadline:  # up when it answers
        r = subprocess.run([cli, "--config", cfg, "--timeout", "2", "status"],
                           capture_output=True, text=True, timeout=30)
        if r.returncode == 0 or daemon.poll() is not None:
            break
    cli_run("zero", "--timeout", "3", "zero")
    time.sleep(1)  # no samples: zeroing fails once its window is over
    cli_run("start while FAILED", "--timeout", "3", "start")
    cli_run("reset", "--timeout", "3", "reset")
    cli_run("stop while IDLE", "--timeout", "1", "stop")
    cli_run("start", "--timeout", "3", "start", "--load-name", "box")
    cli_run("start while estimating", "--timeout", "1", "start")
    cli_run("reset again", "--timeout", "3", "reset")
    daemon.terminate()
    err = daemon.communicate(timeout=10)[1]
    print(json.dumps({"runs": runs, "returncode": daemon.returncode, "stderr": err}))


if __name__ == "__main__":
    main()
