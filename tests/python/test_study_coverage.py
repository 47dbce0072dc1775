"""loadid-study's phi_std coverage statistics (tools/study/loadid_study.py):
the Wilson interval against published values and its defining equation, the
simulator seeds (one random stream per recording, so that pooled runs are
independent draws), and the pooled table's counting (a recording two cells
share counts once; the verdicts against the 90-98 % band), the claims
table's counting (identified groups, the wrong ones). Also the
program's own --self-test (geometry, regressor, smoother, TLS, JR3 frames)."""

from __future__ import annotations

import itertools
import pathlib
import subprocess
import sys

import pytest

STUDY = pathlib.Path(__file__).resolve().parents[2] / "tools" / "study"
sys.path.insert(0, str(STUDY))
import loadid_study as st  # noqa: E402


@pytest.mark.parametrize("hits,n,lo,hi", [
    # Wilson score intervals, 95 %, as tabulated by Newcombe (Stat. Med.
    # 1998, 17:857, Table I: 81/263, 15/148, 0/20, 1/29).
    (81, 263, 0.2553, 0.3662),
    (15, 148, 0.0624, 0.1605),
    (0, 20, 0.0, 0.1611),
    (1, 29, 0.0061, 0.1718),
])
def test_wilson_interval_against_published_values(hits, n, lo, hi):
    got = st.wilson(hits, n)
    assert got[0] == pytest.approx(lo, abs=6e-5) and got[1] == pytest.approx(hi, abs=6e-5)


def test_wilson_bounds_solve_the_score_equation():
    # Each bound p solves (hits/n - p)^2 = z^2 p (1 - p) / n.
    for hits, n in ((470, 480), (431, 480), (3, 7)):
        for p in st.wilson(hits, n):
            lhs = (hits / n - p) ** 2
            rhs = 1.96 ** 2 * p * (1 - p) / n
            assert lhs == pytest.approx(rhs, rel=1e-9, abs=1e-15)


def test_every_recording_of_the_default_grid_has_its_own_seed():
    grid = list(itertools.product(st.ROBOTS, st.LOADS, st.NOISE_CELLS, range(1, 101)))
    seeds = {st.sim_seed(*g) for g in grid}
    assert len(seeds) == len(grid)
    assert all(0 <= s < 2 ** 31 for s in seeds)
    assert st.sim_seed("rx60", "o1", "paper", 3) == st.sim_seed("rx60", "o1", "paper", 3)


def _row(robot, noise, seed, covered, method="RTLS"):
    return dict(robot=robot, load="o1", noise=noise, seed=seed, method=method, ok=True,
                **{f"cov{i}": int(c) for i, c in enumerate(covered)})


def test_pooled_coverage_counts_each_recording_once_and_judges_the_band():
    rows = []
    for seed in range(200):
        # m always covered (above the band), mcx 170/200 (below), mcy
        # 188/200 (94 %: in band), the rest 196/200 (98 %: in band).
        cov = [True, seed < 170, seed < 188] + [seed < 196] * 7
        rows.append(_row("rx60", "paper", seed, cov))
        # wrong3x estimates paper's recordings: not new draws, never covered
        rows.append(_row("rx60", "wrong3x", seed, [False] * 10))
        rows.append(_row("rx60", "paper", seed, [False] * 10, method="REF"))
    pooled = st.pooled_coverage(rows, ["RTLS"], ["paper", "wrong3x"])
    per = pooled["rx60"]["RTLS"]
    assert per["m"]["n"] == 200 and per["m"]["coverage"] == 1.0
    assert per["m"]["verdict"] == "above"
    assert per["mcx"]["coverage"] == pytest.approx(0.85) and per["mcx"]["verdict"] == "below"
    assert per["mcy"]["verdict"] == "in band" and per["Izz"]["verdict"] == "in band"
    lo, hi = per["mcx"]["ci95"]
    assert lo < 0.85 < hi < 0.90
    text = st.coverage_table(pooled)
    assert "100.0>" in text and "85.0<" in text and "(200 recordings)" in text


def test_self_test_passes():
    r = subprocess.run([sys.executable, str(STUDY / "loadid_study.py"), "--self-test"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    assert "self-test: all passed" in r.stdout


def _runs(method, errors):
    return [dict(method=method, seed=k, ok=True, mass_pct=e) for k, e in enumerate(errors)]


def test_ratio_interval_is_paired():
    # Errors spread over two decades, the method's 1.02-1.04 times REF's on
    # each seed: resampling the seeds in pairs gives a ratio near 1.03 with a
    # narrow interval; unpaired resampling would scatter it by the spread.
    ref = [0.01 * 1.27 ** k for k in range(20)]
    meth = [e * (1.02 + 0.02 * (k % 2)) for k, e in enumerate(ref)]
    lo, hi = st.median_ratio_ci(_runs("RTLS", meth) + _runs("REF", ref), "RTLS", "REF", "mass_pct")
    assert 1.0 <= lo <= hi <= 1.05
    exact = st.median_ratio_ci(_runs("RTLS", [2 * e for e in ref]) + _runs("REF", ref),
                               "RTLS", "REF", "mass_pct")
    assert exact == pytest.approx([2.0, 2.0], rel=1e-12)


def test_ratio_interval_needs_two_paired_seeds():
    assert st.median_ratio_ci(_runs("RTLS", [1.0]) + _runs("REF", [1.0]),
                              "RTLS", "REF", "mass_pct") is None


def _cell(name, refined, ref, ci):
    med = lambda v: dict(median=v, p90=v)  # noqa: E731
    return dict(robot="rx60", load=name, noise="paper", methods={
        "REFINED": dict(mass_pct=med(refined), com_mm=med(1.0), inertia_pct=med(1.0),
                        ratio_ci90={"REF": dict(mass_pct=ci)}),
        "REF": dict(mass_pct=med(ref), com_mm=med(1.0), inertia_pct=med(1.0))})


def test_targets_tell_noise_from_a_real_excess():
    summary = [_cell("a", 1.3, 1.0, [0.95, 1.6]),   # over, but the interval reaches 1.1
               _cell("b", 1.3, 1.0, [1.2, 1.4]),    # over beyond the interval
               _cell("c", 1.05, 1.0, [0.9, 1.2])]   # met
    (t,) = [t for t in st.target_checks(summary) if t["method"] == "REFINED"
            and t["base"] == "REF"]
    assert t["checked"] == 9
    assert [i["cell"] for i in t["over_in_noise"]] == ["rx60/a/paper"]
    assert [i["cell"] for i in t["over"]] == ["rx60/b/paper"]
    text = st.targets_text([t])
    assert "met in 7 of 9; over within the interval 1; over beyond it 1" in text
    assert "OVER rx60/b/paper mass_pct: 1.300 [1.20, 1.40]" in text


def test_targets_give_the_rms_error_ratio_beside_the_medians():
    # A median ratio over the target where the RMS errors are alike (the
    # base's middle seed fell low) against one where they are not.
    summary = [_cell("a", 1.3, 1.0, [0.95, 1.6]), _cell("b", 1.3, 1.0, [0.95, 1.6])]
    summary[0]["methods"]["REFINED"]["mass_pct"]["rms"] = 2.02
    summary[0]["methods"]["REF"]["mass_pct"]["rms"] = 2.0
    summary[1]["methods"]["REFINED"]["mass_pct"]["rms"] = 3.0
    summary[1]["methods"]["REF"]["mass_pct"]["rms"] = 2.0
    (t,) = [t for t in st.target_checks(summary) if t["method"] == "REFINED"
            and t["base"] == "REF"]
    assert [i["rms_ratio"] for i in t["over_in_noise"]] == pytest.approx([1.01, 1.5])
    text = st.targets_text([t])
    assert "over rx60/a/paper mass_pct: 1.300 [0.95, 1.60], RMS error ratio 1.01" in text
    assert "over rx60/b/paper mass_pct: 1.300 [0.95, 1.60], RMS error ratio 1.50" in text
    settled = st.targets_text([t], dict(seeds=200, cells=["rx60/a/paper", "rx60/b/paper"]))
    assert "settled: the 2 cells over a target only within their interval, with seeds 1..200" \
        in settled


def test_settling_runs_a_cells_own_recordings_with_more_seeds(tmp_path):
    # --settle's recordings of wrong3x are paper's (one simulation), named
    # and seeded as the main run's, whichever of the two is settled.
    (tmp_path / "traj").mkdir()
    (tmp_path / "configs").mkdir()
    for seed in (21, 22):  # cached: nothing is designed
        (tmp_path / "traj" / f"rx60-mc300-c1-e800-s{seed}.yaml").write_text("")
    study = dict(build=tmp_path, work=tmp_path, methods=["RTLS", "REFINED"],
                 noises=["low", "paper", "wrong3x"], per_seed=True, keep=False, jobs=1,
                 log=lambda msg: None, est=dict(signals=None, lag=None, jerk_psd=None,
                                                offset_model=None))
    tasks = st.plan_tasks(study, [("rx60", "o1", "wrong3x")], range(21, 23))
    assert [t["rec_name"] for t in tasks] == ["rx60-o1-paper-s21", "rx60-o1-paper-s22"]
    assert [t["sim_seed"] for t in tasks] == [st.sim_seed("rx60", "o1", "paper", s)
                                              for s in (21, 22)]
    assert [[c["noise"] for c in t["cells"]] for t in tasks] == [["wrong3x"], ["wrong3x"]]
    both = st.plan_tasks(study, [("rx60", "o1", "paper"), ("rx60", "o1", "wrong3x"),
                                 ("rx60", "o1", "low")], range(21, 22))
    assert sorted((t["rec_name"], tuple(c["noise"] for c in t["cells"])) for t in both) == [
        ("rx60-o1-low-s21", ("low",)), ("rx60-o1-paper-s21", ("paper", "wrong3x"))]
    assert all(t["trajectory"].endswith("-s21.yaml") for t in both)


def _rls_cell(name, share, ci):
    med = lambda v: dict(median=v, p90=v)  # noqa: E731
    why = "phi_std R times its bound"
    return dict(robot="rx60", load=name, noise="vibration", methods={
        "RTLS": dict(mass_pct=med(1.0), com_mm=med(1.0), inertia_pct=med(3.0),
                     ratio_ci90={"RLS": dict(inertia_pct=ci)},
                     unidentified={"inertia": dict(share=share, why=why)}),
        "RLS": dict(mass_pct=med(1.0), com_mm=med(1.0), inertia_pct=med(1.0))})


def test_targets_against_rls_take_what_identified_says():
    # The issue: no TLS variant worse than RLS by 2x "unless identified
    # says why". An inertia 3 times RLS's that RTLS identified in no run is
    # said; one it identified in half of them is over.
    summary = [_rls_cell("a", 1.0, [2.5, 3.5]), _rls_cell("b", 0.5, [2.5, 3.5])]
    (t,) = [t for t in st.target_checks(summary) if t["method"] == "RTLS"
            and t["base"] == "RLS"]
    assert [i["cell"] for i in t["flagged"]] == ["rx60/a/vibration"]
    assert [i["cell"] for i in t["over"]] == ["rx60/b/vibration"]
    text = st.targets_text([t])
    assert ("met in 4 of 6; over but said (the group identified in no run) 1; "
            "over within the interval 0; over beyond it 1") in text, text
    assert "said: inertia not identified (phi_std R times its bound) in 1 cell-metric(s)" in text
    # Against REF nothing is excused.
    ref = dict(_rls_cell("c", 1.0, [2.5, 3.5]))
    ref["methods"] = {"RTLS": dict(ref["methods"]["RTLS"], ratio_ci90={}),
                      "REF": ref["methods"]["RLS"]}
    (t,) = [t for t in st.target_checks([ref]) if t["method"] == "RTLS" and t["base"] == "REF"]
    assert not t["flagged"] and [i["metric"] for i in t["over"]] == ["inertia_pct"]


def test_unidentified_summary_reads_loadidds_reasons():
    rows = [dict(identified="mass+com", not_identified="inertia: phi_std 5.32 times its bound"),
            dict(identified="mass+com", not_identified="inertia: phi_std 11.3 times its bound"),
            dict(identified="mass", not_identified="com: phi_std 1.2 times its bound; "
                                                   "inertia: needs the com"),
            dict(identified="mass+com+inertia", not_identified="")]
    u = st.unidentified_summary(rows)
    assert u["mass"] == dict(share=0.0, why=None)
    assert u["com"] == dict(share=0.25, why="phi_std R times its bound")
    assert u["inertia"] == dict(share=0.75, why="phi_std R times its bound")
    # A prerequisite's reason is followed to its root.
    chain = {"mass": "phi_std 19.5 times its bound", "com": "needs the mass",
             "inertia": "needs the com"}
    assert st.root_reason(chain, "inertia") == "via mass: phi_std R times its bound"
    assert st.root_reason(chain, "com") == "via mass: phi_std R times its bound"
    assert st.root_reason(chain, "mass") == "phi_std R times its bound"
    assert st.root_reason({"mass": "no estimate"}, "com") is None


def test_rigid_cells_simulate_their_own_recordings_without_backlash():
    # The rigid cells turn the gears' backlash off in loadid-sim's
    # configuration, and so may not share the backlash cells' recordings.
    def simulation(cell):
        text = st.sim_config("rx60", "o1", cell)
        return text[text.index("simulation:\n"):]
    for cell, base in (("paper_rigid", "paper"), ("low_rigid", "low")):
        assert "\n  backlash: 0.0\n" in simulation(cell)
        assert "backlash" not in simulation(base)
        assert st.sim_key(cell) != st.sim_key(base)
        assert simulation(cell).replace("  backlash: 0.0\n", "") == simulation(base)
    assert st.sim_key("wrong3x") == st.sim_key("paper")


def test_claims_count_the_identified_groups_and_the_wrong_ones():
    """claims(): per noise cell and method, the runs that identify a group
    and, of those, the ones whose load model misses it beyond CLAIM_WRONG
    (counted here by hand); a failed run and another method's row do not
    count, a claim without the model's error counts as wrong."""
    def row(noise, method, ident, mass, com, inertia, ok=True):
        return dict(noise=noise, method=method, ok=ok, identified="+".join(ident),
                    model_mass_pct=mass, model_com_mm=com, model_inertia_pct=inertia)
    rows = [row("paper", "RLS", ["mass", "com"], 1.0, 3.0, 50.0),        # both right
            row("paper", "RLS", ["mass"], 7.0, 30.0, 10.0),               # mass wrong
            row("paper", "RLS", ["mass", "com", "inertia"], 4.9, 15.1, 29.0),  # com wrong
            row("paper", "RLS", ["inertia"], 1.0, 1.0, ""),               # no model: wrong
            row("paper", "RLS", ["mass"], 90.0, 0.0, 0.0, ok=False),      # no estimate
            row("paper", "RTLS", ["mass"], 90.0, 0.0, 0.0),               # another method
            row("high", "RLS", [], 90.0, 90.0, 90.0)]                     # claims nothing
    c = st.claims(rows, ["RLS", "RTLS"], ["paper", "high"])
    assert c["paper"]["RLS"] == dict(runs=4, mass=dict(claimed=3, wrong=1),
                                     com=dict(claimed=2, wrong=1),
                                     inertia=dict(claimed=2, wrong=1))
    assert c["paper"]["RTLS"]["mass"] == dict(claimed=1, wrong=1)
    assert c["high"]["RLS"] == dict(runs=1, mass=dict(claimed=0, wrong=0),
                                    com=dict(claimed=0, wrong=0), inertia=dict(claimed=0, wrong=0))
    text = st.claims_table(c)
    assert "1/3" in text and "0/0" in text
