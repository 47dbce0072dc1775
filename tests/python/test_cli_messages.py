"""What the programs say when the setup is wrong: each message names what
is wrong and what to do about it.
"""

from __future__ import annotations

import subprocess

from recordings import program


def run(*args, timeout=60):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)


def test_misspelt_key_is_an_error_with_a_suggestion(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("lcm:\n  url: memq://\nestimation:\n  metods: [RLS]\n")
    for args in ((program("LOADIDD_EXE"), "--config", cfg, "--offline", tmp_path),
                 (program("LOADID_CLI_EXE"), "--config", cfg, "status")):
        r = run(*args)
        assert r.returncode == 1, r
        assert f"{cfg}:4: estimation.metods: unknown key (did you mean 'methods'?)" in r.stderr
    cfg.write_text("lcm:\n  url: memq://\nestimaton:\n  methods: [RLS]\n")
    r = run(program("LOADID_CLI_EXE"), "--config", cfg, "status")
    assert r.returncode == 1
    assert f"{cfg}:3: estimaton: unknown section (did you mean 'estimation'?)" in r.stderr


def test_another_programs_section_is_a_warning(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("lcm:\n  url: memq://\ndashboard:\n  port: 8080\n")
    r = run(program("LOADID_CLI_EXE"), "--config", cfg, "--timeout", "0.2", "status")
    # the configuration loads (the warning), then no daemon answers on memq://
    assert f"loadid: warning: {cfg}:3: dashboard: not a loadid section, ignored" in r.stderr
    assert "status: no answer" in r.stderr and r.returncode == 1, r


def test_missing_urdf_names_the_key_the_file_and_the_line(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("# a robot that is not there\nrobot:\n  urdf: robots/none.urdf\n")
    expected = (f"{cfg}:3: robot.urdf: {tmp_path}/robots/none.urdf: cannot read: "
                "No such file or directory")
    for args in ((program("LOADIDD_EXE"), "--config", cfg, "--offline", tmp_path),
                 (program("LOADID_KAPPA_EXE"), "--config", cfg, tmp_path)):
        r = run(*args)
        assert r.returncode == 1, r
        assert expected in r.stderr, r.stderr


def test_no_socketcan_says_what_to_do(tmp_path):
    """The daemon on a CAN interface it cannot open: with SocketCAN absent
    (this test machine's kernel, as CI's) the modules to load; with
    SocketCAN present, the interface to create; and the ways without a
    CAN bus either way."""
    cfg = tmp_path / "c.yaml"
    cfg.write_text("lcm:\n  url: memq://\ncan:\n  interface: loadidnone0\n")
    r = run(program("LOADIDD_EXE"), "--config", cfg, timeout=30)
    assert r.returncode == 1, r
    if "Address family not supported" in r.stderr:
        assert "no CAN socket" in r.stderr
        assert "'modprobe can_raw'" in r.stderr and "'modprobe vcan'" in r.stderr, r.stderr
    else:
        assert "no such interface" in r.stderr, r.stderr
        assert "'ip link add dev loadidnone0 type vcan" in r.stderr, r.stderr
    assert "--can-file CAN.LOG" in r.stderr and "--offline DIR" in r.stderr, r.stderr
    assert len(r.stderr.splitlines()) == 1, r.stderr


def test_sim_does_not_overwrite_a_recording(tmp_path, trajectory):
    sim = program("LOADID_SIM_EXE")
    traj = trajectory / "traj.yaml"
    empty = tmp_path / "empty"
    empty.mkdir()
    r = run(sim, "--trajectory", traj, "--out", empty)  # an empty folder will do
    assert r.returncode == 0, r.stderr
    can = (empty / "can.log").read_bytes()

    r = run(sim, "--trajectory", traj, "--out", empty, "--seed", "7")
    assert r.returncode == 1, r
    assert f"loadid-sim: --out {empty}: not empty" in r.stderr
    assert "--force" in r.stderr
    assert (empty / "can.log").read_bytes() == can  # untouched

    r = run(sim, "--trajectory", traj, "--out", empty, "--seed", "7", "--force")
    assert r.returncode == 0, r.stderr
    assert (empty / "can.log").read_bytes() != can  # another seed, written over

    (tmp_path / "file").write_text("x")
    r = run(sim, "--trajectory", traj, "--out", tmp_path / "file", "--force")
    assert r.returncode == 1 and "not a directory" in r.stderr, r


def test_demo_does_not_overwrite_a_kept_recording(tmp_path):
    demo = program("LOADID_DEMO_EXE")
    (tmp_path / "can.log").write_text("x")
    r = run(demo, "--keep", tmp_path)  # refused before anything is designed
    assert r.returncode == 1, r
    assert f"loadid-demo: --keep {tmp_path}: not empty (it holds can.log)" in r.stderr
    assert (tmp_path / "can.log").read_text() == "x"
    r = run(demo, "--force")
    assert r.returncode == 2 and "--force needs --keep" in r.stderr, r
