"""What the live sessions (live_session.py, modbus_session.py) share: LCM
multicast on the loopback of a private network namespace, a recording's
two streams, and the daemon's four output channels collected (not
collected by pytest)."""

from __future__ import annotations

import importlib
import select
import subprocess
import sys
import time

import lcm

URL = "udpm://239.255.76.67:7667?ttl=0"


def loopback_multicast():
    """lo up with a multicast route (docs/ARCHITECTURE.md, the live tests)."""
    subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
    subprocess.run(["ip", "route", "add", "224.0.0.0/4", "dev", "lo"], check=True)


def recording_streams(rec):
    """The utime of can.log's first frame, and lcm.log's events as
    (timestamp, channel, data)."""
    with open(f"{rec}/can.log") as f:
        line = f.readline()
        sec, usec = line[1:line.index(")")].split(".")
        first_can = int(sec) * 1_000_000 + int(usec)
    events = [(ev.timestamp, ev.channel, ev.data) for ev in lcm.EventLog(f"{rec}/lcm.log", "r")]
    return first_can, events


def open_session(pydir, rec):
    """What every live session starts with: lcm-gen's Python types (from
    pydir), the loopback multicast, the recording's streams, an LCM handle
    and the daemon's outputs subscribed. Returns (types, first_can, events,
    lc, outputs)."""
    sys.path.insert(0, pydir)
    types = importlib.import_module("loadid")
    loopback_multicast()
    first_can, events = recording_streams(rec)
    lc = lcm.LCM(URL)
    return types, first_can, events, lc, Outputs(lc, types)


class Outputs:
    """estimate_t, status_t, wrench_t and load_model_t from the daemon, decoded with
    lcm-gen's Python types; reencoded_differ counts the messages whose
    re-encoding differs from the bytes received. prefix: the daemon's
    lcm.channel_prefix."""

    def __init__(self, lc, types, prefix=""):
        self.lc = lc
        self.got = {"estimate": [], "status": [], "wrench": [], "model": []}
        self.reencoded_differ = 0
        for kind, channel, cls in (("estimate", "LOADID_ESTIMATE", types.estimate_t),
                                   ("status", "LOADID_STATUS", types.status_t),
                                   ("wrench", "LOADID_WRENCH", types.wrench_t),
                                   ("model", "LOADID_MODEL", types.load_model_t)):
            lc.subscribe(prefix + channel, self._keeper(kind, cls))

    def _keeper(self, kind, cls):
        def handler(channel, data):
            m = cls.decode(data)
            self.reencoded_differ += m.encode() != data
            self.got[kind].append(m)
        return handler

    def pump(self, until, each=None):
        """Handles what arrives until the wall time `until`, calling
        each() (if given) on every turn."""
        while True:
            if each:
                each()
            left = until - time.time()
            if left <= 0:
                return
            if select.select([self.lc.fileno()], [], [], min(left, 0.05))[0]:
                self.lc.handle()
