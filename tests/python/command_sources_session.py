"""One session of loadidd with lcm.command_sources, run inside a private
network namespace by test_command_sources.py (not collected by pytest):

    command_sources_session.py LOADIDD CONFIG CAN_LOG LCM_PYTHON_DIR LOADID_CLI

Sets loopback up with a multicast route, starts loadidd live (its CAN
input a candump log replayed in real time; no joint states), waits for its
first status_t, then sends command_t ZERO as raw LCM datagrams from
sockets bound to chosen loopback addresses (the sender address the daemon
sees): first from 127.0.0.2 (three times), then, after the daemon has had
time to act, a status_t is read; then `loadid zero` (the CLI, from the
host's own address: the multicast route's source, 127.0.0.1), then from
127.0.0.1 bound by hand; a status_t after each. Prints as JSON the states of the status_t read after each step and
the daemon's stderr (with --verbose: its state changes and counters).
"""

from __future__ import annotations

import importlib
import json
import socket
import struct
import subprocess
import sys
import time

import lcm

from lcm_loopback import URL, Outputs, loopback_multicast

GROUP, PORT = "239.255.76.67", 7667


def send_command(types, source, seqno, action=1):
    """command_t on LOADID_COMMAND as one LCM short message (LC02), sent
    from a socket bound to source."""
    m = types.command_t()
    m.utime = int(time.time() * 1e6)
    m.action = action
    m.load_name = "from " + source
    datagram = (struct.pack(">II", 0x4C433032, seqno) + b"LOADID_COMMAND\0" + m.encode())
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 0)
    s.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_LOOP, 1)
    s.bind((source, 0))
    s.sendto(datagram, (GROUP, PORT))
    s.close()


def main():
    loadidd, config, can_log, pydir, cli = sys.argv[1:6]
    sys.path.insert(0, pydir)
    types = importlib.import_module("loadid")  # lcm-gen's types
    loopback_multicast()
    # The route's source: without it, a sender that does not bind its
    # socket (the CLI, liblcm) gets no address of a fitting scope on lo
    # (127.0.0.1 is host scope) and its datagrams come from 0.0.0.0; a
    # host's real interface has an address of its own.
    subprocess.run(["ip", "route", "replace", "224.0.0.0/4", "dev", "lo", "src", "127.0.0.1"],
                   check=True)
    out = Outputs(lcm.LCM(URL), types)
    daemon = subprocess.Popen([loadidd, "--config", config, "--can-file", can_log, "--verbose"],
                              stderr=subprocess.PIPE, text=True)

    def next_status(timeout=10.0):
        """The state in the next status_t (once a second), or None."""
        n = len(out.got["status"])
        end = time.time() + timeout
        while len(out.got["status"]) == n and time.time() < end:
            out.pump(min(end, time.time() + 0.1))
        return out.got["status"][n].state if len(out.got["status"]) > n else None

    steps = {"first": next_status()}
    for k in range(3):
        send_command(types, "127.0.0.2", k)
    # Commands act within the smoother's lag plus the tick's grace (0.1 s);
    # the status after the next one is surely later.
    next_status()
    steps["after_refused"] = next_status()
    cli_run = subprocess.run([cli, "--config", config, "zero", "--load-name", "cli"],
                             capture_output=True, text=True, timeout=20)
    next_status()
    steps["after_cli"] = next_status()
    send_command(types, "127.0.0.1", 10)
    next_status()
    steps["after_allowed"] = next_status()
    daemon.terminate()
    err = daemon.communicate(timeout=20)[1]
    print(json.dumps({"returncode": daemon.returncode, "stderr": err, "steps": steps,
                      "cli": {"rc": cli_run.returncode, "err": cli_run.stderr}}))


if __name__ == "__main__":
    main()
