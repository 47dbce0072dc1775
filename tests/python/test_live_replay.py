"""loadidd --replay DIR (docs/INTERFACE.md, "Command line"): the daemon
replays a recording's JR3 frames, joint states and commands itself, in real
time, with no CAN and nothing else publishing, and its output goes out on
LCM as live (UDP multicast in a private network namespace). Its final
estimates are loadidd --offline's on the same recording to 1e-9, as the
other live sessions' are, and they arrive over LCM: estimate_t while
estimating and at DONE, load_model_t, status_t with the state changes,
wrench_t once DONE; and the loop allocates nothing meanwhile (release
build). With results.trace the session's every estimate is traced beside
its saved result, as --offline --trace traces the recording, and `loadid
plot RESULT_DIR` draws it. Plus the refusals of the command line, which
need no session, and a SIGTERM while REFINED runs (LCM on memq://): the
stop waits for it."""

from __future__ import annotations

import json
import os
import pathlib
import re
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

from alloc_report import counts, loop_sites
from recordings import program, simulate
from test_live_lcm import run_in_netns
from test_live_no_alloc import counted
import offline_run
from offline_run import write_config
from test_plot import png_size, read_rows

NAMES = {1: "RLS", 2: "RIV", 3: "RTLS", 6: "REFINED"}


@pytest.fixture(scope="module")
def config(tmp_path_factory):
    cfg = tmp_path_factory.mktemp("replay") / "c.yaml"
    cfg.write_text("lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\n"
                   "estimation:\n  methods: [RTLS, RIV, RLS, REFINED]\n")
    return cfg


@pytest.fixture(scope="module")
def session(config, recording, tmp_path_factory):
    """The session, its result saved and traced (results.trace: the trace
    writer's thread is inside the allocation count too); in the release
    build (not under the sanitizers, whose allocator it would meet) with
    the allocation counter preloaded into the daemon, as
    test_live_no_alloc.py runs the other sessions."""
    d = tmp_path_factory.mktemp("replay_traced")
    traced = d / "c.yaml"
    traced.write_text(config.read_text() + f"results:\n  directory: {d / 'results'}\n"
                      "  trace: true\n")

    def run():
        out = run_in_netns("replay_session.py", program("LOADIDD_EXE"), traced, recording,
                           os.environ["LOADID_LCM_PYTHON_DIR"])
        out["results"] = d / "results"
        return out
    if not os.environ.get("LOADID_ALLOC_COUNT_LIB"):
        return run()
    return counted(tmp_path_factory.mktemp("replay_alloc"), run)


def run_offline(config, recording):
    """loadidd --offline --verbose: its results by method, the samples it
    counted and its log."""
    result, err = offline_run.offline(config, recording, "--verbose")
    ok = re.search(r"^loadidd: samples ok (\d+),", err, re.M)
    return {"result": {o["method"]: o for o in result}, "samples_ok": int(ok.group(1)),
            "stderr": err}


@pytest.fixture(scope="module")
def offline(config, recording):
    return run_offline(config, recording)


def test_replay_runs_and_stops_cleanly(session):
    assert session["returncode"] == 0, session["stderr"]
    assert "replayed (" in session["stderr"], session["stderr"]  # to its end


def test_no_allocation_in_the_loop_while_replaying(session):
    """The replay's file reads and decoding allocate nothing after start-up
    either (release build: the counter's report; under the sanitizers there
    is none)."""
    if "report" not in session:
        assert not os.environ.get("LOADID_ALLOC_COUNT_LIB")
        return
    c = counts(session["report"])
    assert c["epoll_waits"] > 3000, session["report"]  # the whole replay in the window
    assert c["loop_allocations"] == 0, "allocations in the loop:\n" + "\n".join(
        loop_sites(session["report"], program("LOADIDD_EXE")))


def test_final_estimates_over_lcm_equal_offline(session, offline):
    finals = [e for e in session["estimate"] if e["state"] == 3]
    assert sorted(e["method"] for e in finals) == [1, 2, 3, 6], session["stderr"]
    for e in finals:
        o = offline["result"][NAMES[e["method"]]]
        assert e["samples"] == o["samples"] == 1500 and e["load_name"] == o["load_name"]
        np.testing.assert_allclose(e["phi"], o["phi"], rtol=1e-9, atol=1e-12)
    # Estimates while estimating (estimation.publish_every 1: every sample),
    # REFINED once; their times the recording's shifted to the daemon's now.
    running = [e for e in session["estimate"] if e["state"] == 2]
    assert len(running) >= 3 * 1400 and 6 not in {e["method"] for e in running}
    span_us = session["span_s"] * 1e6
    assert all(session["wall_start_us"] <= e["utime"] <= session["wall_start_us"] + span_us + 5e6
               for e in finals), finals


def test_model_status_and_wrench_over_lcm(session, offline):
    m = session["model"]
    assert len(m) == 1, m
    o = offline["result"][NAMES[m[0]["method"]]]
    np.testing.assert_allclose(m[0]["phi"], o["model_phi"], rtol=1e-9, atol=1e-12)
    st = session["status"]
    states = [s["state"] for s in st]
    # The recording's ZERO and START acted: every state change announced.
    for a, b in ((1, 0), (0, 2), (2, 3)):
        assert any(x == a and y == b for x, y in zip(states, states[1:])), states
    last = st[-1]
    assert last["state"] == 3 and last["samples_ok"] == offline["samples_ok"], last
    assert last["frames_bad"] == last["sequence_gaps"] == last["joint_msgs_bad"] == 0, last
    assert session["wrench"] > 500  # every sample after DONE (0.8 s of the recording)


def test_the_session_is_traced_beside_its_saved_result(session, offline, config, recording,
                                                      tmp_path):
    """results.trace: <stem>.trace.csv beside the saved <stem>.yaml, every
    estimate the session published (estimation.publish_every 1: a row per
    on-line method per sample while estimating, then each method's final,
    REFINED's last), each method's last row the final estimate_t's phi (to
    the CSV's 9 digits), and --offline --trace --publish-every 1 on the
    recording gives the same rows; `loadid plot RESULT_DIR` draws it."""
    saved = re.search(r"^loadidd: saved (\S+)\.yaml$", session["stderr"], re.M)
    traced = re.search(r"^loadidd: traced (\S+) \((\d+) rows\)$", session["stderr"], re.M)
    assert saved and traced, session["stderr"]
    path = pathlib.Path(traced.group(1))
    assert path == pathlib.Path(saved.group(1) + ".trace.csv") and path.parent == \
        session["results"], (saved.group(0), traced.group(0))
    assert not list(session["results"].glob(".*.tmp")), list(session["results"].iterdir())
    rows = read_rows(path)
    assert len(rows) == int(traced.group(2)) >= 3 * 1400 + 4, len(rows)
    phi = [f"phi{i}" for i in range(10)]
    last = {}
    for r in rows:
        last[r["method"]] = r
    assert sorted(last) == sorted(NAMES.values()) and rows[-1]["method"] == "REFINED", last
    # The CSV's %.9g holds 9 significant digits: equal to 5e-9.
    finals = {NAMES[e["method"]]: e for e in session["estimate"] if e["state"] == 3}
    for m, r in last.items():
        np.testing.assert_allclose([r[k] for k in phi], finals[m]["phi"], rtol=1e-8, atol=1e-12)
        np.testing.assert_allclose([r[k] for k in phi], offline["result"][m]["phi"], rtol=1e-8,
                                   atol=1e-12)
    # The recording traced offline: the same rows.
    off = tmp_path / "offline.csv"
    offline_run.offline(config, recording, "--trace", off, "--publish-every", "1")
    orows = read_rows(off)
    assert [(o["method"], o["samples"]) for o in orows] == \
        [(x["method"], x["samples"]) for x in rows]
    cols = [k for k in rows[0] if k != "method"]
    np.testing.assert_allclose([[x[k] for k in cols] for x in rows],
                               [[o[k] for k in cols] for o in orows], rtol=1e-9, atol=1e-9)
    r = subprocess.run([program("LOADID_CLI_EXE"), "plot", str(session["results"])],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    for suffix in ("estimates.png", "residual.png"):
        (w, h), size = png_size(path.parent / f"{path.stem}-{suffix}")
        assert 800 <= w <= 4000 and 400 <= h <= 3000 and size > 20_000, (suffix, w, h, size)


def test_replay_options_refused_where_they_do_not_apply(recording, tmp_path):
    """Usage errors exit 2; a folder that is no recording, and a Modbus
    sensor (a recording holds JR3 frames), exit 1 with the reason (LCM on
    memq://: nothing leaves the process)."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("lcm:\n  url: memq://\n")
    modbus = tmp_path / "m.yaml"
    modbus.write_text("lcm:\n  url: memq://\nsensor:\n  type: modbus\n")

    def run(c, *args):
        return subprocess.run([program("LOADIDD_EXE"), "--config", str(c), *map(str, args)],
                              capture_output=True, text=True, timeout=30)

    r = run(cfg, "--replay", recording, "--offline", recording)
    assert r.returncode == 2 and "--replay" in r.stderr and "--offline" in r.stderr, r.stderr
    r = run(cfg, "--replay", recording, "--can-file", recording / "can.log")
    assert r.returncode == 2 and "--can-file" in r.stderr, r.stderr
    r = run(cfg, "--replay-without-commands")
    assert r.returncode == 2 and "--replay-without-commands needs --replay" in r.stderr, r.stderr
    r = run(cfg, "--replay", tmp_path / "none")
    assert r.returncode == 1 and "none/can.log: cannot read" in r.stderr, r.stderr
    r = run(modbus, "--replay", recording)
    assert r.returncode == 1 and "--replay replays JR3 frames; sensor.type is modbus" in r.stderr, \
        r.stderr


def test_replay_without_commands_leaves_them_to_lcm(recording, tmp_path):
    """--replay-without-commands: the recording's ZERO (at 0.05 s) and START
    (at 1 s) are not replayed, so 1.3 s of it change no state; the joint
    states and frames still are (LCM on memq://: no network)."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("lcm:\n  url: memq://\n")
    daemon = subprocess.Popen([program("LOADIDD_EXE"), "--config", str(cfg), "--replay",
                               str(recording), "--replay-without-commands", "--verbose"],
                              stderr=subprocess.PIPE, text=True)
    time.sleep(1.3)
    daemon.send_signal(signal.SIGTERM)
    err = daemon.communicate(timeout=30)[1]
    assert daemon.returncode == 0, err
    assert "its commands not replayed" in err, err
    assert not re.search(r"^loadidd: \d+: (ZEROING|ESTIMATING)", err, re.M), err
    m = re.search(r"^loadidd: replay events (\d+), joint states (\d+) \(undecodable 0\), "
                  r"commands 0 ", err, re.M)
    assert m and int(m.group(2)) >= 1000, err  # a second of 1 kHz joint states went in
    ok = re.search(r"^loadidd: samples ok (\d+), used 0,", err, re.M)
    assert ok and int(ok.group(1)) >= 1000, err



def test_sigterm_while_refined_runs_waits_for_it(recording, offline, tmp_path):
    """SIGTERM as soon as the daemon says DONE, while REFINED runs on its
    worker (about 14 ms): the daemon waits for the run (live.c's
    finish_refined), logs it and saves the final estimate, REFINED's (the
    primary: ties go to it), before it exits 0; the saved phi is
    --offline's REFINED to 1e-9. Before, the stop lost both. A session
    whose SIGTERM came after the run had ended (a loaded machine) shows
    nothing: up to three (3 s each, LCM on memq://)."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("lcm:\n  url: memq://\nestimation:\n  methods: [RTLS, RIV, RLS, REFINED]\n"
                   f"results:\n  directory: {tmp_path / 'results'}\n")
    for _ in range(3):
        daemon = subprocess.Popen([program("LOADIDD_EXE"), "--config", str(cfg), "--replay",
                                   str(recording), "--verbose"], stderr=subprocess.PIPE, text=True)
        guard = threading.Timer(30, daemon.kill)
        guard.start()
        lines = []
        for line in daemon.stderr:
            lines.append(line)
            if re.match(r"^loadidd: \d+: DONE$", line):
                daemon.send_signal(signal.SIGTERM)
                break
        err = "".join(lines) + daemon.communicate(timeout=30)[1]
        guard.cancel()
        assert daemon.returncode == 0, err
        waited = err.find("loadidd: stopping: waiting for REFINED's run (at most 2000 ms)\n")
        if waited >= 0:
            break
    assert waited >= 0, err  # the stop came while REFINED ran, in one session of three
    after = err[waited:]
    assert re.search(r"^loadidd: REFINED: 1500 samples on the smoothed joints", after, re.M), err
    saved = re.search(r"^loadidd: saved (\S+)$", after, re.M)
    assert saved, err
    text = pathlib.Path(saved.group(1)).read_text()
    assert re.search(r"^method: REFINED$", text, re.M), text
    phi = json.loads(re.search(r"^phi: (\[.*\])$", text, re.M).group(1))
    np.testing.assert_allclose(phi, offline["result"]["REFINED"]["phi"], rtol=1e-9, atol=1e-12)


def test_coarse_encoders_retuned_live_as_offline(config, trajectory, tmp_path):
    """Encoders of 2^14 counts a turn (test_offline.py's
    test_coarse_encoders_retune_the_joint_filters), replayed live: the
    joint filters take the measured noise and the fixed-lag smoother a
    longer lag early in the window, as --offline does, and the final
    estimates equal --offline's to 1e-9. The live clock waits for the lag
    as it runs before it serves a sample (with the configured 50 ms it would
    have refused the samples the longer lag had not yet smoothed); the loop
    allocates nothing meanwhile (release build)."""
    rec = simulate(tmp_path / "rec", trajectory, "--seed", "3", "--config",
                   write_config(tmp_path / "sim.yaml", "simulation:\n  encoder_counts: 16384\n"))
    off = run_offline(config, rec)
    retuned = re.search(r"joints: their positions are [0-9.]+ times noisier .* the fixed-lag "
                        r"smoother (\d+) steps \(was 50\)", off["stderr"])
    assert retuned and int(retuned.group(1)) > 100, off["stderr"]
    offline = off["result"]

    def run():
        return run_in_netns("replay_session.py", program("LOADIDD_EXE"), config, rec,
                            os.environ["LOADID_LCM_PYTHON_DIR"])
    s = counted(tmp_path, run) if os.environ.get("LOADID_ALLOC_COUNT_LIB") else run()
    assert s["returncode"] == 0, s["stderr"]
    assert retuned.group(0) in s["stderr"], s["stderr"]
    finals = [e for e in s["estimate"] if e["state"] == 3]
    assert sorted(e["method"] for e in finals) == [1, 2, 3, 6], s["stderr"]
    for e in finals:
        o = offline[NAMES[e["method"]]]
        assert e["samples"] == o["samples"], (e["samples"], o["samples"])
        np.testing.assert_allclose(e["phi"], o["phi"], rtol=1e-9, atol=1e-12)
    if "report" in s:
        assert counts(s["report"])["loop_allocations"] == 0, "\n".join(
            loop_sites(s["report"], program("LOADIDD_EXE")))
