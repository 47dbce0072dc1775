"""Two loadidd for two robots on one LCM network, told apart by
lcm.channel_prefix (R1_, R2_), run inside a private network namespace by
test_channel_prefix.py (not collected by pytest):

    two_robots_session.py LOADIDD CONFIG_R1 CONFIG_R2 RECORDING LCM_PYTHON_DIR

Both daemons replay the recording's can.log; its joint states go to both
robots' channels, its commands to R1's only and, as a third robot's, to the
unprefixed channel. Prints as JSON what came back on each robot's and the
unprefixed output channels, and each daemon's exit code and stderr.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

from lcm_loopback import Outputs, open_session


def main():
    loadidd, cfg1, cfg2, rec, pydir = sys.argv[1:6]
    loadid, first_can, events, lc, plain = open_session(pydir, rec)
    robots = {"R1_": Outputs(lc, loadid, "R1_"), "R2_": Outputs(lc, loadid, "R2_")}
    epoch = int(time.time() * 1e6) + 1_500_000
    daemons = [subprocess.Popen([loadidd, "--config", c, "--can-file", f"{rec}/can.log",
                                 "--can-file-epoch", str(epoch), "--publish-every", "100"],
                                stderr=subprocess.PIPE, text=True) for c in (cfg1, cfg2)]
    shift = epoch - first_can
    for t, channel, data in events:
        plain.pump((t + shift) / 1e6)
        if channel == "LOADID_JOINTS":
            msg = loadid.joint_state_t.decode(data)
            msg.utime += shift
            for prefix in robots:
                lc.publish(prefix + channel, msg.encode())
        else:
            msg = loadid.command_t.decode(data)
            msg.utime += shift
            lc.publish("R1_" + channel, msg.encode())
            lc.publish(channel, msg.encode())   # a third robot's: neither acts
    plain.pump(time.time() + 1.5)
    for d in daemons:
        d.terminate()
    errs = [d.communicate(timeout=10)[1] for d in daemons]
    plain.pump(time.time() + 0.3)

    def summary(o):
        return {"estimate": [{"method": m.method, "state": m.state, "samples": m.samples,
                              "phi": list(m.phi)} for m in o.got["estimate"]],
                "states": [m.state for m in o.got["status"]],
                "wrench": len(o.got["wrench"]), "model": len(o.got["model"])}

    print(json.dumps({"returncodes": [d.returncode for d in daemons], "stderr": errs,
                      "R1_": summary(robots["R1_"]), "R2_": summary(robots["R2_"]),
                      "plain": summary(plain)}))


if __name__ == "__main__":
    main()
