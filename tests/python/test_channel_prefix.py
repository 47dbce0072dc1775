"""lcm.channel_prefix: two daemons for two robots on one LCM network (a
private network namespace, real UDP multicast). R1 gets commands and
estimates; R2, with the same joint states and frames but no commands,
stays idle; commands on the unprefixed channels move neither; nothing is
published without a prefix. R1's final estimates are --offline's over the
same recording with the same configuration to 1e-9."""

from __future__ import annotations

import json
import os
import subprocess

import numpy as np
import pytest

from recordings import program
from test_live_lcm import run_in_netns

METHODS = "estimation:\n  methods: [RTLS, RIV, RLS]\n"


@pytest.fixture(scope="module")
def session(recording, tmp_path_factory):
    d = tmp_path_factory.mktemp("two")
    cfgs = []
    for prefix in ("R1_", "R2_"):
        c = d / f"{prefix}.yaml"
        c.write_text(f"lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\n  channel_prefix: {prefix}\n"
                     + METHODS)
        cfgs.append(c)
    out = run_in_netns("two_robots_session.py", program("LOADIDD_EXE"), *cfgs, recording,
                       os.environ["LOADID_LCM_PYTHON_DIR"])
    out["dir"] = d
    return out


def test_both_daemons_stop_cleanly(session):
    assert session["returncodes"] == [0, 0], session["stderr"]


def test_r1_estimates_and_equals_offline(session, recording):
    r1 = session["R1_"]
    assert 3 in r1["states"] and r1["wrench"] > 500, r1["states"]
    final = [e for e in r1["estimate"] if e["state"] == 3]
    assert sorted(e["method"] for e in final) == [1, 2, 3]
    cfg = session["dir"] / "offline.yaml"
    cfg.write_text(METHODS)
    r = subprocess.run([program("LOADIDD_EXE"), "--config", str(cfg), "--offline",
                        str(recording)], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    offline = {o["method"]: o for o in json.loads(r.stdout)}
    names = {1: "RLS", 2: "RIV", 3: "RTLS"}
    for e in final:
        o = offline[names[e["method"]]]
        assert e["samples"] == o["samples"] == 1500
        np.testing.assert_allclose(e["phi"], o["phi"], rtol=1e-9, atol=1e-12)


def test_r2_heard_no_command_and_stayed_idle(session):
    r2 = session["R2_"]
    assert len(r2["states"]) >= 2 and set(r2["states"]) == {0}, r2["states"]
    assert r2["estimate"] == [] and r2["wrench"] == 0 and r2["model"] == 0


def test_nothing_is_published_without_the_prefix(session):
    plain = session["plain"]
    assert plain == {"estimate": [], "states": [], "wrench": 0, "model": 0}, plain
