"""One cell of loadid-study (tools/study/loadid_study.py) run from a test,
through the study's own code: its recordings, loadidd --offline on them,
and its independent reference (a numpy batch TLS on the encoders smoothed
by a local polynomial, Pinocchio's kinematics, the true noise levels)."""

from __future__ import annotations

import json
import os
import pathlib
import sys

from recordings import program, run_tool

STUDY = pathlib.Path(__file__).resolve().parents[2] / "tools" / "study"
sys.path.insert(0, str(STUDY))
import loadid_study as st  # noqa: E402

__all__ = ["run_cell", "st"]


def run_cell(tmp_path, robot, load, seeds, cell="paper_enc14", methods=("REFINED",)):
    """Recordings of the study's cell through its own run_recording
    (simulation, loadidd --offline, the reference), on its trajectory
    design: per seed the study's rows by method and the first method's
    result."""
    build = pathlib.Path(os.environ["LOADIDD_EXE"]).resolve().parents[1]
    traj_cfg = tmp_path / "traj-config.yaml"
    traj_cfg.write_text(st.robot_yaml(robot))
    traj = tmp_path / "traj.yaml"
    run_tool([program("LOADID_TRAJ_EXE"), "--config", traj_cfg, *st.TRAJ_BUDGET, "--quiet",
              "--out", traj])
    sim_cfg, est_cfg = tmp_path / "sim.yaml", tmp_path / "est.yaml"
    sim_cfg.write_text(st.sim_config(robot, load, cell))
    est_cfg.write_text(st.est_config(robot, cell, list(methods)))
    out = []
    for seed in seeds:
        name = f"{robot}-{load}-s{seed}"
        rows = st.run_recording(dict(
            build=str(build), workdir=str(tmp_path), rec_name=name, robot=robot, load=load,
            seed=seed, sim_seed=st.sim_seed(robot, load, cell, seed), sim_config=sim_cfg,
            trajectory=traj, cells=[dict(noise=cell, est_config=est_cfg)],
            methods=list(methods), keep=False))
        err = {r["method"]: r for r in rows}
        assert all(err[m]["ok"] for m in (*methods, "REF")), rows
        result = json.loads((tmp_path / "results" / f"{name}-{cell}.json").read_text())
        out.append((err, result[0]))
    return out
