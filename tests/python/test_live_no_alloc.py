"""The daemon's loop allocates nothing after start-up,
proved on the real loadidd in a whole live session over real LCM (UDP
multicast in a private network namespace, live_session.py): joint states
and commands over LCM, JR3 frames from --can-file, ZERO, 1.5 s of
estimation, DONE, REFINED on the worker thread, estimate_t, wrench_t and
status_t going out, the finished estimate saved to results.directory, the
CLI's status and reset, SIGTERM; again with signals sensor, where the
notch on the rows against the accelerometer's vibration runs per sample;
and the Modbus sensor's session.

The daemon runs with liballoc_count.so preloaded (tests/support/
alloc_count.c): it counts malloc, calloc, realloc, free, posix_memalign,
aligned_alloc, memalign, valloc and pvalloc in every thread (liblcm's
receive thread too) between the daemon's first epoll_wait (start-up over)
and the return of its last one (SIGTERM: shutdown), and writes the counts
and the allocating call sites at exit. Not under the sanitizers (their
allocator), as test_no_alloc.
"""

from __future__ import annotations

import os

import pytest

from alloc_report import counts, loop_sites
from recordings import program
from test_live_lcm import live_config, run_session
from test_live_modbus import run_modbus_session


def counted(d, run):
    """run() with the allocation counter preloaded into the daemon; its
    result with the counter's report."""
    lib = os.environ.get("LOADID_ALLOC_COUNT_LIB")
    if not lib or not os.path.isfile(lib):
        pytest.fail("LOADID_ALLOC_COUNT_LIB must name liballoc_count.so (ctest sets it)")
    report = d / "alloc.txt"
    os.environ["LOADID_DAEMON_PRELOAD"] = lib
    os.environ["LOADID_ALLOC_REPORT"] = str(report)
    try:
        out = run()
    finally:
        del os.environ["LOADID_DAEMON_PRELOAD"], os.environ["LOADID_ALLOC_REPORT"]
    out["report"] = report.read_text() if report.exists() else ""
    return out


@pytest.fixture(scope="module")
def session(recording, tmp_path_factory):
    d = tmp_path_factory.mktemp("live_no_alloc")
    cfg = live_config(d)
    out = counted(d, lambda: run_session(cfg, recording))
    out["results"] = d / "results"
    return out


@pytest.fixture(scope="module")
def modbus_session(recording, tmp_path_factory):
    """The serial sensor's session (test_live_modbus.py): the poller thread
    and its device lost and reopened are inside the window too."""
    d = tmp_path_factory.mktemp("live_no_alloc_modbus")
    return counted(d, lambda: run_modbus_session(recording, d))


@pytest.fixture(scope="module")
def notch_session(recording, tmp_path_factory):
    """signals sensor: the recording's vibration (about a tenth of a - g's
    noise at 28 Hz) puts a notch on the rows, which then filters every
    sample inside the counted window."""
    d = tmp_path_factory.mktemp("live_no_alloc_notch")
    cfg = live_config(d)
    cfg.write_text(cfg.read_text().replace("estimation:\n", "estimation:\n  signals: sensor\n"))
    out = counted(d, lambda: run_session(cfg, recording))
    return out


def test_session_went_through_every_path(session):
    """What the window covered: the daemon ran the whole session."""
    assert session["returncode"] == 0, session["stderr"]
    est = session["estimate"]
    # Four finals: the three on-line methods and REFINED, from the worker
    # thread (its run is inside the counted window).
    assert [e for e in est if e["state"] == 2] and len([e for e in est if e["state"] == 3]) == 4
    assert len(session["wrench"]) > 500
    assert len(session["status"]) >= 3 and session["status"][-1]["state"] == 0  # reset by the CLI
    assert "saved " in session["stderr"] and (session["results"] / "latest.yaml").exists()
    c = counts(session["report"])
    assert c["epoll_waits"] > 3000, session["report"]  # about one per joint state and frame batch
    # What the daemon published is byte for byte what lcm-gen makes of it.
    assert session["reencoded_differ"] == 0


def assert_no_loop_allocation(session):
    c = counts(session["report"])
    sites = loop_sites(session["report"], program("LOADIDD_EXE"))
    assert c["loop_allocations"] == 0, "allocations in the loop:\n" + "\n".join(sites)


def test_no_allocation_between_start_up_and_shutdown(session):
    assert_no_loop_allocation(session)


def test_no_allocation_with_the_modbus_sensor_either(modbus_session):
    assert modbus_session["returncode"] == 0, modbus_session["stderr"]
    assert [e for e in modbus_session["estimate"] if e["state"] == 3], modbus_session["stderr"]
    assert " lost: " in modbus_session["stderr"]  # the reopen path ran in the window
    assert counts(modbus_session["report"])["epoll_waits"] > 1000, modbus_session["report"]
    assert_no_loop_allocation(modbus_session)


def test_no_allocation_with_a_notch_on_the_rows(notch_session):
    assert notch_session["returncode"] == 0, notch_session["stderr"]
    assert "a notch there on the rows" in notch_session["stderr"], notch_session["stderr"]
    assert [e for e in notch_session["estimate"] if e["state"] == 3], notch_session["stderr"]
    assert_no_loop_allocation(notch_session)
