"""The systemd unit (host/systemd/loadidd.service) does not break the daemon,
checked as far as it can be without systemd as PID 1 (CI has none):

- its exposure (`systemd-analyze security --offline=true`) stays at the
  figure docs/SECURITY.md gives;
- a live session (live_session.py: LCM in a private network namespace, the
  recording's CAN frames from the file) runs with the daemon as an
  unprivileged user holding only the unit's capabilities
  (AmbientCapabilities=, CapabilityBoundingSet=) and no new privileges,
  with SCHED_FIFO and mlockall configured (loadidd exits when either
  fails), under strace; every system call it made must be in the unit's
  SystemCallFilter= (expanded by systemd-analyze), every socket family in
  RestrictAddressFamilies=, no mapping writable and executable
  (MemoryDenyWriteExecute=), and every file it opened for writing in its
  results folder (ProtectSystem=strict with the state directory);
- the same trace, thread by thread: from its first epoll_wait on, the
  loop's thread makes no file-system call (saving the result is the save
  worker's, host/src/daemon/save_worker.c), while another thread of the daemon
  did save it (open, write, fsync, rename);
- without the capabilities the same daemon fails to start (so the session
  above shows the capabilities are what it needs, and enough).
"""

from __future__ import annotations

import os
import pathlib
import re
import shutil
import stat
import subprocess
import sys
import tempfile

import pytest

from recordings import program
from test_live_lcm import run_in_netns

HERE = pathlib.Path(__file__).resolve().parent
UNIT = HERE.parent.parent / "host" / "systemd" / "loadidd.service"
EXPOSURE_MAX = 2.1   # docs/SECURITY.md (systemd 252)
NOBODY = 65534


def unit_text_lines():
    """The [Service] section's lines, stripped."""
    lines, section = [], None
    for line in UNIT.read_text().splitlines():
        line = line.strip()
        if line.startswith("["):
            section = line
        elif section == "[Service]":
            lines.append(line)
    return lines


def unit_values(key):
    """Every value of key in the unit's [Service] section, split on spaces
    (systemd's lists add up over repeated lines)."""
    values = []
    for line in unit_text_lines():
        if line.startswith(key + "="):
            values += line.split("=", 1)[1].split()
    return values


def need(tool):
    if not shutil.which(tool):
        pytest.fail(f"{tool} is missing: tools/setup.sh installs it")


def test_exposure_stays_low():
    need("systemd-analyze")
    r = subprocess.run(["systemd-analyze", "security", "--offline=true", str(UNIT)],
                       capture_output=True, text=True, timeout=120)
    m = re.search(r"Overall exposure level for \S+: (\d+\.\d+)", r.stdout)
    assert m, r.stdout + r.stderr
    assert float(m.group(1)) <= EXPOSURE_MAX, r.stdout


def syscall_group(name, groups, seen=None):
    """The system calls of a systemd group (@name), nested groups expanded."""
    seen = seen if seen is not None else set()
    calls = set()
    for item in groups.get(name, []):
        if item.startswith("@"):
            if item not in seen:
                seen.add(item)
                calls |= syscall_group(item, groups, seen)
        else:
            calls.add(item)
    return calls


def syscall_groups():
    """Every group systemd-analyze knows, as name -> members."""
    r = subprocess.run(["systemd-analyze", "syscall-filter"], capture_output=True, text=True,
                       timeout=60)
    groups, current = {}, None
    for line in r.stdout.splitlines():
        if line.startswith("@"):
            current = groups.setdefault(line.strip(), [])
        elif current is not None and line.startswith("    ") and not line.strip().startswith("#"):
            current.append(line.strip())
    assert "@system-service" in groups, r.stdout[:500] + r.stderr
    return groups


def allowed_syscalls():
    """SystemCallFilter= of the unit: an allow list of groups and names
    (the first line), less what the lines with ~ deny."""
    groups = syscall_groups()
    allowed, denied = set(), set()
    lines = [line for line in unit_text_lines() if line.startswith("SystemCallFilter=")]
    assert lines and not lines[0].split("=", 1)[1].startswith("~"), "an allow list first"
    for line in lines:
        value = line.split("=", 1)[1]
        into = denied if value.startswith("~") else allowed
        for item in value.removeprefix("~").split():
            into |= syscall_group(item, groups) if item.startswith("@") else {item}
    return allowed - denied


WRAPPER = """#!{python}
# loadidd as nobody with only the unit's capabilities (under strace: then
# SIGTERM and SIGINT go on to the daemon, strace's child, for strace itself
# would only detach).
import os, signal, subprocess, sys
tracer = subprocess.Popen({args!r} + sys.argv[1:])
def forward(sig, frame):
    with open(f"/proc/{{tracer.pid}}/task/{{tracer.pid}}/children") as f:
        children = [int(c) for c in f.read().split()]
    for child in children if {traced!r} else [tracer.pid]:
        os.kill(child, sig)
signal.signal(signal.SIGTERM, forward)
signal.signal(signal.SIGINT, forward)
sys.exit(tracer.wait())
"""


def privileged(tmp, daemon, caps, trace=None):
    """A wrapper that runs the daemon as nobody with only caps (the unit's
    AmbientCapabilities=), no new privileges, under strace when trace is a
    path. Returns its path."""
    caps_arg = ",".join("+" + c.lower().removeprefix("cap_") for c in caps)
    args = ["setpriv", f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups",
            "--no-new-privs",
            "--inh-caps=-all" + ("," + caps_arg if caps else ""),
            "--bounding-set=-all" + ("," + caps_arg if caps else "")]
    if caps:
        args.append("--ambient-caps=" + caps_arg)
    if trace:
        # -f: the worker threads too; -y: descriptors with their paths;
        # -e signal=none: no signal lines.
        args += ["strace", "-f", "-y", "-qq", "-e", "signal=none", "-o", str(trace)]
    wrapper = tmp / ("loadidd-traced" if trace else "loadidd-as-unit")
    wrapper.write_text(WRAPPER.format(python=sys.executable, args=args + [str(daemon)],
                                      traced=bool(trace)))
    wrapper.chmod(0o755)
    return wrapper


@pytest.fixture(scope="module")
def unit_session(recording):
    """The live session with the daemon as the unit would run it. Its files
    in a folder nobody can read (not pytest's, which is root's alone)."""
    need("setpriv")
    need("strace")
    tmp = pathlib.Path(tempfile.mkdtemp(prefix="loadid-unit-"))
    try:
        yield unit_run(tmp, recording)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def unit_run(tmp, recording):
    tmp.chmod(0o755)
    rec = tmp / "rec"
    rec.mkdir()
    for f in ("can.log", "lcm.log"):
        shutil.copy(pathlib.Path(recording) / f, rec / f)
    results = tmp / "results"
    results.mkdir()
    os.chown(results, NOBODY, NOBODY)  # StateDirectory= gives it to the service's user
    cfg = tmp / "c.yaml"
    cfg.write_text("lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\n"
                   f"results:\n  directory: {results}\n"
                   "realtime:\n  priority: 10\n  lock_memory: true\n")
    for p in tmp.rglob("*"):
        p.chmod(p.stat().st_mode | stat.S_IROTH | (stat.S_IXOTH if p.is_dir() else 0))
    trace = tmp / "trace"
    trace.touch()
    os.chown(trace, NOBODY, NOBODY)  # strace runs as the service's user
    caps = unit_values("AmbientCapabilities")
    assert sorted(caps) == sorted(unit_values("CapabilityBoundingSet")), caps
    wrapper = privileged(tmp, program("LOADIDD_EXE"), caps, trace=trace)
    out = run_in_netns("live_session.py", wrapper, cfg, rec,
                       os.environ["LOADID_LCM_PYTHON_DIR"], program("LOADID_CLI_EXE"))
    out["trace"] = trace.read_text()
    out["tmp"], out["results"], out["cfg"] = tmp, results, cfg
    return out


def test_daemon_runs_a_session_with_only_the_units_privileges(unit_session):
    s = unit_session
    assert s["returncode"] == 0, s["stderr"]
    assert "saved" in s["stderr"], s["stderr"]  # into its results folder, as nobody
    assert any(e["state"] == 3 for e in s["estimate"]), s["stderr"]
    assert s["trace"], "no strace output"


def thread_calls(trace):
    """(thread id, name, arguments, result) of every completed system call
    in an strace -f log, in the order they began (resumed calls joined)."""
    calls, pending = [], {}
    for line in trace.splitlines():
        m = re.match(r"^(\d+)\s+(.*)$", line)
        if not m:
            continue
        tid, rest = m.groups()
        if rest.endswith("<unfinished ...>"):
            pending[tid] = (len(calls), rest[: -len("<unfinished ...>")])
            calls.append(None)  # its place, filled when it resumes
            continue
        at = len(calls)
        r = re.match(r"^<\.\.\. (\w+) resumed>(.*)$", rest)
        if r:
            at, begun = pending.pop(tid, (at, r.group(1) + "("))
            rest = begun + r.group(2)
        if at == len(calls):
            calls.append(None)
        c = re.match(r"^(\w+)\((.*)\)\s+=\s+(.*)$", rest)
        if c:
            calls[at] = (int(tid),) + c.groups()
    return [c for c in calls if c]


def traced_calls(trace):
    """(name, arguments, result) of every completed system call in an
    strace -f log."""
    return [c[1:] for c in thread_calls(trace)]


def test_every_system_call_is_in_the_units_filter(unit_session):
    calls = traced_calls(unit_session["trace"])
    assert len(calls) > 1000, unit_session["trace"][:2000]
    names = {c[0] for c in calls}
    assert {"mlockall", "sched_setscheduler", "epoll_wait"} <= names, sorted(names)
    outside = names - allowed_syscalls()
    assert not outside, f"not in SystemCallFilter=: {sorted(outside)}"


def test_every_socket_family_is_allowed(unit_session):
    families = {re.match(r"(\w+),", args).group(1)
                for name, args, _ in traced_calls(unit_session["trace"]) if name == "socket"}
    assert "AF_INET" in families and "AF_UNIX" in families, families  # LCM, sd_notify
    allowed = set(unit_values("RestrictAddressFamilies"))
    assert families <= allowed, f"{sorted(families - allowed)} not in RestrictAddressFamilies="


def test_no_memory_is_writable_and_executable(unit_session):
    for name, args, _ in traced_calls(unit_session["trace"]):
        if name in ("mmap", "mprotect", "pkey_mprotect"):
            assert not ("PROT_WRITE" in args and "PROT_EXEC" in args), (name, args)


def test_files_are_written_only_where_the_unit_allows(unit_session):
    results = str(unit_session["results"])
    for name, args, result in traced_calls(unit_session["trace"]):
        if name not in ("open", "openat", "creat", "rename", "renameat", "renameat2",
                        "unlink", "unlinkat", "mkdir", "mkdirat"):
            continue
        if name in ("open", "openat") and not re.search(r"O_WRONLY|O_RDWR|O_CREAT", args):
            continue
        if result.startswith("-1"):
            continue
        for path in re.findall(r'"([^"]*)"', args):
            assert path.startswith(results + "/") or path.startswith("/dev/"), (name, args)


# What touches the file system: opening, creating, renaming, removing,
# syncing, truncating, changing modes or owners, and writing to a regular
# file (-y names it: a path outside /dev; stderr is a pipe here). Reading
# is not in it: --can-file's frames are read from a file by design.
FS_CALLS = {"open", "openat", "openat2", "creat", "rename", "renameat", "renameat2", "unlink",
            "unlinkat", "mkdir", "mkdirat", "rmdir", "link", "linkat", "symlink", "symlinkat",
            "truncate", "ftruncate", "fallocate", "fsync", "fdatasync", "sync", "syncfs",
            "sync_file_range", "chmod", "fchmod", "fchmodat", "chown", "fchown", "fchownat",
            "lchown"}
WRITES = {"write", "pwrite64", "writev", "pwritev", "pwritev2"}


def file_system_call(name, args):
    if name in FS_CALLS:
        return True
    fd = re.match(r"\d+<([^>]*)>", args)
    return name in WRITES and bool(fd) and fd.group(1).startswith("/") \
        and not fd.group(1).startswith("/dev/")


def test_the_loop_thread_makes_no_file_system_call(unit_session):
    """Nothing blocks the loop. A disk that stalls (fsync of the
    saved result on a busy disk takes tens of ms) must not stall the 1 kHz
    loop, so from its first epoll_wait (start-up over) to its exit the
    loop's thread, the daemon's first, makes no file-system call; the
    control: in the same session another thread of the daemon saved the
    result (opened, wrote, synced and renamed it into results/)."""
    calls = thread_calls(unit_session["trace"])
    loop = calls[0][0]
    assert calls[0][1] == "execve" and "loadidd" in calls[0][2], calls[0]
    start = next(i for i, c in enumerate(calls)
                 if c[0] == loop and c[1] in ("epoll_wait", "epoll_pwait"))
    in_loop = [c for c in calls[start:] if c[0] == loop and file_system_call(c[1], c[2])]
    assert not in_loop, "file-system calls on the loop's thread:\n" + "\n".join(map(str, in_loop))
    results = str(unit_session["results"]) + "/"
    saver = {c[0] for c in calls[start:] if c[1].startswith("rename") and results in c[2]
             and c[3] == "0"}
    assert len(saver) == 1 and loop not in saver, saver
    done = {c[1] for c in calls[start:] if c[0] in saver and file_system_call(c[1], c[2])}
    assert {"openat", "write", "fsync", "rename"} <= done, done
    assert (unit_session["results"] / "latest.yaml").exists()


@pytest.mark.parametrize("key, limit, reason", [
    ("priority: 10", "--rtprio=0", "realtime.priority 10: SCHED_FIFO: Operation not permitted"),
    ("lock_memory: true", "--memlock=0",
     "realtime.lock_memory: mlockall: Operation not permitted"),
])
def test_without_the_capabilities_the_daemon_does_not_start(unit_session, key, limit, reason):
    """The control: as nobody without the capabilities, with the limit that
    would otherwise allow it at 0 (RLIMIT_RTPRIO is 0 by default), each of
    SCHED_FIFO and mlockall is refused and the daemon exits 1."""
    tmp = unit_session["tmp"]
    cfg = tmp / "control.yaml"
    cfg.write_text(f"lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\nrealtime:\n  {key}\n")
    cfg.chmod(0o644)
    wrapper = privileged(tmp, program("LOADIDD_EXE"), [])
    # In a network namespace of its own with LCM's loopback route, so that
    # it gets as far as the real-time set-up.
    script = ("ip link set lo up && ip route add 224.0.0.0/4 dev lo && exec prlimit "
              f"{limit} {wrapper} --config {cfg} --can-file {tmp / 'rec' / 'can.log'}")
    r = subprocess.run(["unshare", "-n", "sh", "-c", script], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 1, r.stderr
    assert reason in r.stderr, r.stderr
