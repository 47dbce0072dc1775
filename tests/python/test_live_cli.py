"""The CLI's commands wait for loadidd's acknowledgement, a status_t that
shows the command's effect, over real LCM (UDP multicast) in a private
network namespace: with no daemon a command fails within its --timeout
with a message that says so; with a daemon it succeeds as soon as the
state changes, and fails with the daemon's state when the daemon did not
act on it.
"""

from __future__ import annotations

import pytest

from recordings import program
from test_live_lcm import run_in_netns


@pytest.fixture(scope="module")
def session(tmp_path_factory):
    out = run_in_netns("cli_session.py", program("LOADIDD_EXE"), program("LOADID_CLI_EXE"),
                       tmp_path_factory.mktemp("cli"))
    out["by_name"] = {r["name"]: r for r in out["runs"]}
    return out


def test_no_daemon_fails_within_the_timeout(session):
    zero = session["by_name"]["no daemon: zero"]
    assert zero["rc"] == 1, zero
    assert "zero: no answer: no status_t on LOADID_STATUS" in zero["err"], zero
    assert "is loadidd running" in zero["err"]
    assert zero["out"] == ""
    assert 1.5 <= zero["seconds"] < 1.5 + 1.5, zero  # the timeout, not more
    status = session["by_name"]["no daemon: status"]
    assert status["rc"] == 1 and "status: no answer" in status["err"], status
    assert 1.0 <= status["seconds"] < 2.5, status


def test_commands_succeed_once_the_state_shows_them(session):
    for name, state in (("zero", "ZEROING"), ("reset", "IDLE"), ("start", "ESTIMATING"),
                        ("reset again", "IDLE")):
        r = session["by_name"][name]
        assert r["rc"] == 0, r
        assert r["out"] == f"state {state}\n" and r["err"] == "", r
        # at the state change, not at the next once-a-second status
        assert r["seconds"] < 1.0, r


def test_commands_the_daemon_does_not_act_on_fail_with_its_state(session):
    failed = session["by_name"]["start while FAILED"]
    assert failed["rc"] == 1, failed
    assert "start: loadidd is in state FAILED" in failed["err"], failed
    assert "'loadid reset' clears FAILED" in failed["err"]
    # FAILED is an answer (the next once-a-second status): no wait for the 3 s timeout
    assert failed["seconds"] < 2.5, failed
    stop = session["by_name"]["stop while IDLE"]
    assert stop["rc"] == 1, stop
    assert "stop: loadidd is running (state IDLE) but did not act on it within 1 s" in stop["err"]
    assert "STOP acts only while estimating" in stop["err"]
    again = session["by_name"]["start while estimating"]
    assert again["rc"] == 1 and "(state ESTIMATING)" in again["err"], again
    assert "it is estimating already" in again["err"]


def test_daemon_stops_cleanly(session):
    assert session["returncode"] == 0, session["stderr"]
