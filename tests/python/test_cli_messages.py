"""What the programs say when the setup is wrong: each message names what
is wrong and what to do about it.
"""

from __future__ import annotations

import subprocess

from recordings import program


def run(*args, timeout=60):
    return subprocess.run([str(a) for a in args], capture_output=True, text=True,
                          timeout=timeout, stdin=subprocess.DEVNULL)


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
