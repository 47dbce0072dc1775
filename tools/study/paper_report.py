"""The report of loadid-study --paper (paper_study.py): report.md, the
numbers beside the paper's, and report.json, the same numbers for programs
(the end-to-end test recomputes them from runs.csv).

Every number is a median (or 90th percentile) over the seeds of eq. (37),
|x - x_th| / |x_th| in %, of one cell (load, trajectory, signal source,
method) of the summary; what the paper reports is quoted from its sec. V
(Table I) and read off its Fig. 6/7 (mass under 1 % for RTLS, Ixx about
21 % for RTLS against 39 % for RLS).
"""

from __future__ import annotations

import json
import math
import pathlib

import numpy as np

from paper_figures import PARAMS, UNIT_SCALE, UNITS, cell, read_trace

PAPER = dict(mass_rtls_max=1.0, ixx_rtls=21.0, ixx_rls=39.0,
             kappa_set=dict(tr1=7.72, tr2=8.18), kappa_sens_range=(14.44, 23.42))
COMPARED = ["RLS", "RIV", "RTLS", "TLS_BATCH", "REFINED", "REF", "REF_ACC"]


def _num(x, digits=3):
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "-"
    return f"{x:.{digits}g}"


def _cell_stats(summary, load, traj, sig, method):
    c = cell(summary, load, traj, sig, method)
    if c is None:
        return None
    return {p: dict(median=c["params"][p]["median"], p90=c["params"][p]["p90"]) for p in PARAMS}


def figure_table(summary, load, traj, sig, methods) -> dict:
    return {m: _cell_stats(summary, load, traj, sig, m) for m in methods}


def wins(summary, meta) -> dict:
    """Per signal source: in how many (load, trajectory, parameter) cells
    RTLS's median error is below RLS's and below RIV's, and the cells where
    it is not by more than 10 % (ratio > 1.1)."""
    out = {}
    for s in meta["signals"]:
        w = dict(cells=0, beats_rls=0, beats_riv=0, beats_both=0, loses_to_rls=[], loses_to_riv=[])
        for load in meta["loads"]:
            for traj in meta["trajectories"]:
                r = _cell_stats(summary, load, traj, s, "RTLS")
                l = _cell_stats(summary, load, traj, s, "RLS")
                v = _cell_stats(summary, load, traj, s, "RIV")
                if not (r and l and v):
                    continue
                for p in PARAMS:
                    a, b, c = r[p]["median"], l[p]["median"], v[p]["median"]
                    if None in (a, b, c):
                        continue
                    w["cells"] += 1
                    w["beats_rls"] += a < b
                    w["beats_riv"] += a < c
                    w["beats_both"] += a < b and a < c
                    if a > 1.1 * b:
                        w["loses_to_rls"].append([load, traj, p, a, b])
                    if a > 1.1 * c:
                        w["loses_to_riv"].append([load, traj, p, a, c])
        out[s] = w
    return out


def numbers(summary, meta) -> dict:
    """Everything report.md states, as numbers."""
    fig6 = figure_table(summary, "o1", "tr2", "sensor", COMPARED)
    fig7 = figure_table(summary, "o1", "tr2", "mixed", COMPARED)
    fig9 = {s: _cell_stats(summary, "o1", "tr2", s, "RTLS") for s in meta["signals"]}
    rtls_mass = {f"{c['load']} {c['trajectory']} {c['signals']}": c["params"]["m"]["median"]
                 for c in summary["cells"] if c["method"] == "RTLS"}
    table1 = [dict(trajectory=k["trajectory"], load=k["load"],
                   kappa_set=k["kappa_set"]["median"], kappa_sens=k["kappa_sens"]["median"],
                   kappa_sens_min=k["kappa_sens"]["min"], kappa_sens_max=k["kappa_sens"]["max"],
                   kappa_kf=k["kappa_kf"]["median"]) for k in summary["kappa"]]
    head = dict(
        rtls_mass_fig6=fig6["RTLS"]["m"]["median"], rtls_mass_fig7=fig7["RTLS"]["m"]["median"],
        rtls_ixx_fig6=fig6["RTLS"]["Ixx"]["median"], rls_ixx_fig6=fig6["RLS"]["Ixx"]["median"],
        riv_ixx_fig6=fig6["RIV"]["Ixx"]["median"],
        rtls_ixx_fig7=fig7["RTLS"]["Ixx"]["median"], rls_ixx_fig7=fig7["RLS"]["Ixx"]["median"],
        riv_ixx_fig7=fig7["RIV"]["Ixx"]["median"],
        rtls_mass_worst_cell=max(rtls_mass.items(), key=lambda kv: kv[1] if kv[1] is not None
                                 else -1),
        kappa_set=[t["kappa_set"] for t in table1],
        kappa_sens_min=min((t["kappa_sens_min"] for t in table1
                            if t["kappa_sens_min"] is not None), default=None),
        kappa_sens_max=max((t["kappa_sens_max"] for t in table1
                            if t["kappa_sens_max"] is not None), default=None))
    return dict(seeds=meta["seeds"], headline=head, fig6=fig6, fig7=fig7, fig9=fig9,
                table1=table1, wins=wins(summary, meta), rtls_mass_median=rtls_mass)


def fig8_numbers(out_dir, meta):
    """The Fig. 8 run's last on-line estimates (t = 1.5 s): value, phi_std,
    and whether +-2 phi_std covers the truth; and the first estimate's time."""
    f8 = meta["fig8"]
    path = (pathlib.Path(out_dir) / "traces" /
            f"{f8['load']}-{f8['trajectory']}-s{f8['seed']}-{f8['signals']}.csv")
    if not path.is_file():
        return None
    series = read_trace(path)
    truth = np.array(meta["loads_phi"][f8["load"]])
    out = dict(run=f8, first_s=min(series[m][0][0] for m in series), truth=list(truth),
               methods={})
    for m in ("RLS", "RIV", "RTLS"):
        if m in series:
            t, phi, std = series[m]
            out["methods"][m] = dict(t_s=float(t[-1]), phi=list(map(float, phi[-1])),
                                     std=list(map(float, std[-1])),
                                     covered=[bool(abs(p - x) <= 2 * s)
                                              for p, x, s in zip(phi[-1], truth, std[-1])])
    return out


def _fig_table_md(t, methods) -> list:
    lines = ["| parameter | " + " | ".join(methods) + " |",
             "|---|" + "---:|" * len(methods)]
    for p in PARAMS:
        cells = []
        for m in methods:
            s = t.get(m)
            cells.append("-" if not s else f"{_num(s[p]['median'])} [{_num(s[p]['p90'])}]")
        lines.append(f"| {p} | " + " | ".join(cells) + " |")
    return lines


def write(out_dir, summary, meta, figures) -> dict:
    out_dir = pathlib.Path(out_dir)
    n = numbers(summary, meta)
    h = n["headline"]
    seeds = meta["seeds"]
    L = [f"# The paper's experiments in simulation (loadid-study --paper, {seeds} seeds)", "",
         "Kubus, Kroeger & Wahl, \"On-line estimation of inertial parameters using a recursive "
         "total least-squares approach\", IROS 2008, sec. V, repeated on the simulated RX60 "
         "through the shipped `loadidd --offline`. Errors are eq. (37), "
         "|x - x_th| / |x_th| in %, as median [90th percentile] over the seeds.", "",
         "## Setup", "",
         f"- Robot `{meta['robot']}`; noise cell `{meta['noise']['cell']}` (F/T "
         f"{meta['noise']['sim']['force']} N, {meta['noise']['sim']['torque']} N m; accelerometer "
         f"{meta['noise']['sim']['linear']} m/s^2, {meta['noise']['sim']['angular']} rad/s^2, and "
         "the simulator's structural vibration, servo and backlash).",
         "- Loads (phi about the sensor frame; o2 and o3 steel, 7850 kg/m^3, parallel-axis "
         "theorem):", ""]
    L += ["| load | what | m [kg] | c [mm] |", "|---|---|---:|---|"]
    for k, phi in meta["loads_phi"].items():
        what = "the paper's phi (sec. V.A)" if k == "o1" else meta["blocks"].get(k, "")
        c = [1000 * x / phi[0] for x in phi[1:4]]
        L.append(f"| {k} | {what} | {phi[0]:.3f} | {c[0]:.1f}, {c[1]:.1f}, {c[2]:.1f} |")
    L += ["", "- Trajectories: loadid-traj's search (Monte Carlo, then COBYLA) from two random "
          "seeds, the same optimisation from two starting points: "
          + "; ".join(f"{t} seed {d['seed']}, kappa_design {_num(d.get('kappa_design'), 4)}"
                      for t, d in meta["trajectories"].items()) + ".",
          f"- Signal sources: {', '.join(meta['signals'])}; methods: "
          f"{', '.join(meta['methods'])} (REF, REF_ACC: the study's batch TLS references).",
          f"- Wall time of the runs: {meta.get('seconds', math.nan):.0f} s with {meta['jobs']} "
          "jobs.", ""]

    L += ["## Headline: the paper's numbers and ours", "",
          "| | paper | here |", "|---|---|---|",
          f"| RTLS mass error, o1 tr2, JR3 accelerations (Fig. 6) | < {PAPER['mass_rtls_max']:g} % "
          f"| {_num(h['rtls_mass_fig6'])} % |",
          f"| RTLS mass error, o1 tr2, mixed (Fig. 7) | < {PAPER['mass_rtls_max']:g} % | "
          f"{_num(h['rtls_mass_fig7'])} % |",
          f"| Ixx error RTLS / RLS (/ RIV), Fig. 6 | {PAPER['ixx_rtls']:g} % / {PAPER['ixx_rls']:g} % "
          f"| {_num(h['rtls_ixx_fig6'])} % / {_num(h['rls_ixx_fig6'])} % / "
          f"{_num(h['riv_ixx_fig6'])} % |",
          f"| Ixx error RTLS / RLS (/ RIV), Fig. 7 | {PAPER['ixx_rtls']:g} % / {PAPER['ixx_rls']:g} % "
          f"| {_num(h['rtls_ixx_fig7'])} % / {_num(h['rls_ixx_fig7'])} % / "
          f"{_num(h['riv_ixx_fig7'])} % |",
          f"| kappa_set tr1, tr2 (Table I) | {PAPER['kappa_set']['tr1']} / "
          f"{PAPER['kappa_set']['tr2']} | "
          + " / ".join(_num(t["kappa_set"], 3) for t in n["table1"] if t["load"] == "o1") + " |",
          f"| kappa_sens, all rows (Table I) | {PAPER['kappa_sens_range'][0]} to "
          f"{PAPER['kappa_sens_range'][1]} | {_num(h['kappa_sens_min'])} to "
          f"{_num(h['kappa_sens_max'])} |",
          f"| worst RTLS median mass error, any cell | (all < 1 %) | "
          f"{_num(h['rtls_mass_worst_cell'][1])} % ({h['rtls_mass_worst_cell'][0]}) |", ""]

    L += ["## Where RTLS beats RIV and RLS, and where it does not", "",
          "Per signal source, over every load, trajectory and parameter (cells of medians):", "",
          "| signals | cells | RTLS < RLS | RTLS < RIV | RTLS < both | RTLS > 1.1 x RLS | "
          "RTLS > 1.1 x RIV |", "|---|---:|---:|---:|---:|---:|---:|"]
    for s, w in n["wins"].items():
        L.append(f"| {s} | {w['cells']} | {w['beats_rls']} | {w['beats_riv']} | "
                 f"{w['beats_both']} | {len(w['loses_to_rls'])} | {len(w['loses_to_riv'])} |")
    L += ["", "With `kf` and `setpoint` every column comes from the joints, whose noise the "
          "estimators weigh as the joint filter's, tiny beside the accelerometer's (README, "
          "\"How good an estimate is\"): TLS then has almost nothing to correct, and RTLS, RIV "
          "and RLS nearly coincide. The comparison the paper makes is the one with the JR3's "
          "accelerations, `sensor` and `mixed`.", ""]
    for s, w in n["wins"].items():
        worst = sorted(w["loses_to_riv"], key=lambda x: -x[3] / x[4])[:5]
        if worst:
            L.append(f"- {s}: RTLS's largest losses to RIV: " + "; ".join(
                f"{a} {b} {p} {_num(x)} % vs {_num(y)} %" for a, b, p, x, y in worst) + ".")
    L += ["", "`rtls_ratios.png` shows every ratio.", ""]

    for title, key, src in (("Fig. 6: o1, tr2, JR3 accelerations (`sensor`)", "fig6", "sensor"),
                            ("Fig. 7: o1, tr2, JR3 linear, joints' angular accelerations "
                             "(`mixed`)", "fig7", "mixed")):
        L += [f"## {title}", "", "eq. (37) median [90th percentile], %:", ""]
        L += _fig_table_md(n[key], COMPARED)
        L += [""]
    f8 = fig8_numbers(out_dir, meta)
    n["fig8"] = f8
    if f8:
        r = f8["run"]
        L += [f"## Fig. 8: {r['load']}, {r['trajectory']}, seed {r['seed']}, `{r['signals']}`", "",
              f"The first estimate comes at {f8['first_s']:.2f} s after START; at the window's "
              "end (value +- 2 phi_std; * where that band misses the truth):", "",
              "| parameter | unit | truth | " + " | ".join(f8["methods"]) + " |",
              "|---|---|---:|" + "---:|" * len(f8["methods"])]
        for i, p in enumerate(PARAMS):
            k = UNIT_SCALE[i]
            row = [f"{x['phi'][i] * k:.4g} +- {2 * x['std'][i] * k:.2g}"
                   + ("" if x["covered"][i] else " *") for x in f8["methods"].values()]
            L.append(f"| {p} | {UNITS[i].replace('$', '').replace('^{-3}', '^-3')} | "
                     f"{f8['truth'][i] * k:.4g} | " + " | ".join(row) + " |")
        cover = {m: sum(x["covered"]) for m, x in f8["methods"].items()}
        L += ["", "Parameters whose final +-2 sigma band holds the truth: "
              + ", ".join(f"{m} {c} of 10" for m, c in cover.items()) + ".", ""]
    L += ["## Fig. 9: RTLS by signal source, o1, tr2", ""]
    L += _fig_table_md(n["fig9"], meta["signals"])
    L += ["", "## Table I", "", "```", (out_dir / "table1.txt").read_text().rstrip(), "```", ""]
    o1 = {t["trajectory"]: t for t in n["table1"] if t["load"] == "o1"}
    if {"tr1", "tr2"} <= set(o1) and None not in (o1["tr1"]["kappa_sens"], o1["tr2"]["kappa_sens"]):
        a, b = o1["tr1"], o1["tr2"]
        same = (a["kappa_set"] < b["kappa_set"]) == (a["kappa_sens"] > b["kappa_sens"])
        L += ["The paper: the trajectory with the lower kappa_set has the higher kappa_sens "
              "(tr1 7.72 against 8.18, but 23.2 against 16.9 on o1), and kappa_sens is two to "
              f"three times kappa_set. Here, on o1: kappa_set {a['kappa_set']:.3g} (tr1) against "
              f"{b['kappa_set']:.3g} (tr2), kappa_sens {a['kappa_sens']:.3g} against "
              f"{b['kappa_sens']:.3g}: " + ("the same order" if same else "not that order")
              + f", and kappa_sens / kappa_set {a['kappa_sens'] / a['kappa_set']:.2f} and "
              f"{b['kappa_sens'] / b['kappa_set']:.2f}. In the simulation the accelerometer's "
              "noise is white and independent of the motion, and changes A's condition by a few "
              "per cent only; whatever raised the paper's kappa_sens (its Fig. 3: measured and commanded alpha "
              "differ strikingly) is not simulated.", ""]
    L += ["## Figures", ""] + [f"- `{k}`: {v}" for k, v in sorted(figures.items())]
    L += ["", "## What differs from the paper", "",
          "- The robot, the sensor and their noise are simulated (`loadid-sim`): white "
          "accelerometer noise, one structural vibration, a servo with backlash. The paper's "
          "real JR3 accelerations were disturbed in ways the simulator does not model.",
          "- kappa is of the unweighted A over the estimation window (`loadid-kappa`), as the "
          "paper's Table I; the trajectories minimise the weighted kappa_design instead.",
          "- The paper's Fig. 6/7 numbers are read off its bar charts (mass under 1 %, Ixx 21 % "
          "against 39 %); they are approximate.", ""]
    (out_dir / "report.md").write_text("\n".join(L))
    (out_dir / "report.json").write_text(json.dumps(n, indent=1))
    return n
