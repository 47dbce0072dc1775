"""Every program of the project answers --help and -h with its usage on
stdout and exit status 0: the executables the build makes (the list
tests/CMakeLists.txt writes once the whole build is configured, named by
LOADID_PROGRAMS_LIST; the unit tests are not on it) and the executable
scripts of tools/ (found here). A program added without --help fails.
"""

from __future__ import annotations

import os
import pathlib
import subprocess

import pytest

FLAGS = ("--help", "-h")


def built_programs():
    """(name, path) of every program on the build's list; [] when the
    variable is not set (test_the_list_is_the_build_s fails then)."""
    path = os.environ.get("LOADID_PROGRAMS_LIST")
    if not path or not os.path.isfile(path):
        return []
    rows = [line.split(" ", 1) for line in pathlib.Path(path).read_text().splitlines() if line]
    return [(name, exe) for name, exe in rows]


def tool_scripts():
    """(name, path) of the executable files of tools/ that are not built
    (shell and Python launchers)."""
    src = os.environ.get("LOADID_SOURCE_DIR")
    if not src:
        return []
    tools = pathlib.Path(src) / "tools"
    return [(p.name, str(p)) for p in sorted(tools.rglob("*"))
            if p.is_file() and os.access(p, os.X_OK) and "__pycache__" not in p.parts]


PROGRAMS = built_programs() + tool_scripts()


def test_the_list_is_the_build_s():
    """The list holds the programs (the service, the tools, the test and
    benchmark helpers) and none of the unit tests, so that the
    parametrised test below cannot pass on an empty or wrong list."""
    names = {name for name, _ in PROGRAMS}
    for must in ("loadidd", "loadid", "loadid-sim", "loadid-traj", "loadid-kappa",
                 "loadid-modbus-sim", "loadid-replay", "loadid-record", "loadid-demo",
                 "bench_core", "bench_signals", "bench_pipeline", "estimate_watch", "can_flood",
                 "jr3_encode_log", "jr3_decode_log", "lcm_encode_samples", "loadid-spy",
                 "loadid-study", "setup.sh"):
        assert must in names, f"{must} is not on the list: {sorted(names)}"
    assert not {"test_config", "test_estimators", "test_lcm_wire"} & names
    for _, exe in PROGRAMS:
        assert os.access(exe, os.X_OK), exe


@pytest.mark.parametrize("flag", FLAGS)
@pytest.mark.parametrize("name,exe", PROGRAMS, ids=[name for name, _ in PROGRAMS])
def test_program_answers_help(name, exe, flag):
    r = subprocess.run([exe, flag], capture_output=True, text=True, timeout=60,
                       stdin=subprocess.DEVNULL)
    assert r.returncode == 0, f"{name} {flag}: exit {r.returncode}\n{r.stdout}\n{r.stderr}"
    lines = r.stdout.splitlines()
    assert any(line.lower().startswith("usage") for line in lines), \
        f"{name} {flag}: no line starting with 'usage' on stdout:\n{r.stdout}\n{r.stderr}"
