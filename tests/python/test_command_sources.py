"""lcm.command_sources live: loadidd in a private network namespace
(command_sources_session.py) obeys command_t only from the senders listed.
The namespace's loopback carries every address of 127.0.0.0/8, so a sender
socket bound to 127.0.0.2 is a second host as far as the daemon can tell:
its ZERO commands must be refused (logged with the sender, counted in the
--verbose summary) and change nothing, while the CLI's `loadid zero` (sent
from the host's own address, 127.0.0.1) and a datagram bound to 127.0.0.1
act. And a provider that does not say who sent a message refuses the key.
"""

from __future__ import annotations

import os
import re
import subprocess

import pytest

from recordings import program
from test_live_lcm import run_in_netns

IDLE, ZEROING, FAILED = 0, 1, 4


@pytest.fixture(scope="module")
def session(recording, tmp_path_factory):
    d = tmp_path_factory.mktemp("sources")
    cfg = d / "c.yaml"
    cfg.write_text("lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\n"
                   "  command_sources: [127.0.0.1]\n")
    return run_in_netns("command_sources_session.py", program("LOADIDD_EXE"), cfg,
                        os.path.join(str(recording), "can.log"),
                        os.environ["LOADID_LCM_PYTHON_DIR"], program("LOADID_CLI_EXE"))


def test_daemon_ran_and_stopped_cleanly(session):
    assert session["returncode"] == 0, session["stderr"]
    assert session["steps"]["first"] == IDLE, session["steps"]
    assert session["cli"]["rc"] == 0, session["cli"]["err"]


def test_commands_from_an_unlisted_sender_are_refused_counted_and_logged(session):
    err = session["stderr"]
    refusals = re.findall(r"^loadidd: LOADID_COMMAND from (\S+) refused: not in "
                          r"lcm.command_sources \((\d+) refused so far\)$", err, re.M)
    # Three within a second: one line (throttled), with the sender.
    assert refusals == [("127.0.0.2", "1")], err
    m = re.search(r"commands refused (\d+)$", err, re.M)
    assert m and int(m.group(1)) == 3, err
    # They changed nothing: still IDLE well after they came.
    assert session["steps"]["after_refused"] == IDLE, session["steps"]


def test_commands_from_listed_senders_act(session):
    err, steps = session["stderr"], session["steps"]
    zeroing = [m.start() for m in re.finditer(r"^loadidd: \d+: ZEROING$", err, re.M)]
    # The CLI's and the one bound to 127.0.0.1: one ZEROING each, both
    # after the refusal (which came first).
    assert len(zeroing) == 2, err
    assert err.index("refused") < zeroing[0], err
    # No joint states in this session: zeroing ends FAILED (no gravity
    # without the kinematics), which shows that it ran.
    assert steps["after_cli"] in (ZEROING, FAILED), steps
    assert steps["after_allowed"] in (ZEROING, FAILED), steps


def test_providers_without_a_sender_address_refuse_the_key(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("lcm:\n  url: memq://\n  command_sources: [127.0.0.1]\n")
    r = subprocess.run([program("LOADIDD_EXE"), "--config", str(cfg)], capture_output=True,
                       text=True, timeout=30)
    assert r.returncode == 1, r.stderr
    assert r.stderr == "loadidd: lcm.command_sources needs a udpm:// lcm.url, not memq://\n"
