"""loadid-study --paper: the experiments of sec. V of Kubus, Kroeger & Wahl,
"On-line estimation of inertial parameters using a recursive total
least-squares approach" (IROS 2008), in simulation, through the shipped
programs (loadid-traj, loadid-sim, loadid-kappa, loadidd --offline).

The grid (the paper's names):
  robot        the RX60 of host/config/robots (the paper's Staeubli RX60)
  loads        o1 (the paper's phi, sec. V.A), o2 and o3 (loadid_study.BLOCKS:
               steel blocks off the sensor's axis, 1.6 and 1.3 kg)
  trajectories tr1, tr2: loadid-traj's search (Monte Carlo, then COBYLA on
               the best candidate; loadid_study.TRAJ_BUDGET) run twice, from
               the random seeds 1 and 2: the same optimisation from two
               starting points, as the paper's tr1 and tr2 are two results
               of its search (sec. III). tr1 is the study's own trajectory.
  noise        the study's "paper" cell (F/T and accelerometer noise, the
               simulator's structural vibration, servo and backlash)
  signals      every source of estimation.signals: sensor (the paper's
               Fig. 6: JR3 accelerations), mixed (Fig. 7: JR3 a - g, alpha
               from the joints), kf (encoders), setpoint (commanded joints)
  methods      RTLS, RIV, RLS, TLS_BATCH, REFINED (loadidd) and the study's
               batch references REF and REF_ACC (loadid_study.reference)
  seeds        1..N (default 20)
Per recording: loadid-sim, loadid-kappa (Table I: kappa_set, kappa_sens,
kappa_kf), the reference, and loadidd --offline --trace once per source.
The error of each parameter is eq. (37), |x - x_th| / |x_th| in %.

Writes into the output folder: runs.csv (a row per recording, source and
method), summary.json, table1.txt, report.md and report.json
(paper_report.py), the PNG figures (paper_figures.py) and traces/ (the
loadidd traces of the Fig. 8 run, every source).
"""

from __future__ import annotations

import concurrent.futures as futures
import csv
import json
import math
import pathlib
import shutil
import sys
import tempfile
import time

import numpy as np

import loadid_study as st

ROBOT = "rx60"
PAPER_LOADS = ["o1", "o2", "o3"]
# name: the loadid-traj seed (--seed, the Monte Carlo's random stream)
TRAJECTORIES = {"tr1": 1, "tr2": 2}
SIGNALS = ["sensor", "mixed", "kf", "setpoint"]
NOISE = "paper"
METHODS = list(st.DEFAULT_METHODS)           # RTLS, RIV, RLS, TLS_BATCH, REFINED
ALL_METHODS = METHODS + st.REF_METHODS       # and REF, REF_ACC
DEFAULT_SEEDS = 20
# The run whose traces Fig. 8 shows (the paper's: o2 on tr2).
FIG8 = dict(load="o2", trajectory="tr2", seed=1, signals="sensor")
PARAMS = st.PARAM_NAMES

CSV_FIELDS = (["load", "trajectory", "signals", "seed", "method", "ok", "error", "complete",
               "samples", "mass_pct", "com_mm", "inertia_pct"]
              + [f"err{i}" for i in range(10)] + [f"phi{i}" for i in range(10)]
              + [f"cov{i}" for i in range(10)] + [f"z{i}" for i in range(10)]
              + ["usable_s", "inertia_identified", "kappa_set", "kappa_sens", "kappa_kf",
                 "seconds", "sim_seconds"])


def eq37(phi, truth) -> np.ndarray:
    """Eq. (37) of every parameter, in %."""
    return 100.0 * np.abs((np.asarray(phi, float) - truth) / truth)


def trajectory_path(work: pathlib.Path, seed: int) -> pathlib.Path:
    """The cache file of a trajectory; seed 1's is the plain study's own."""
    budget = "mc300-c1-e800"
    return work / "traj" / (f"{ROBOT}-{budget}.yaml" if seed == 1
                            else f"{ROBOT}-{budget}-seed{seed}.yaml")


def design(task) -> dict:
    """Worker: one trajectory (cached), and what its file says of it."""
    build, path = pathlib.Path(task["build"]), pathlib.Path(task["path"])
    if not path.is_file():
        st.run(build, "traj", ["--config", task["config"], *st.TRAJ_BUDGET, "--seed",
                               task["seed"], "--out", path])
    info = {}
    for line in path.read_text().splitlines():
        key, _, val = line.partition(":")
        if key in ("kappa_design", "kappa_set", "kappa_monte_carlo"):
            info[key] = float(val)
    return dict(name=task["name"], seed=task["seed"], path=str(path), **info)


def kappa_of(build, rec) -> dict:
    """loadid-kappa's kappa_set, kappa_sens, kappa_kf of one recording (its
    last line: name, load, samples, then the three)."""
    r = st.run(build, "kappa", [rec])
    fields = r.stdout.strip().splitlines()[-1].split()
    return dict(zip(("kappa_set", "kappa_sens", "kappa_kf"), map(float, fields[-3:])))


def paper_recording(task: dict) -> list:
    """Worker: one (load, trajectory, seed): the study's run_recording with a
    cell per signal source, then loadid-kappa, eq. (37) per parameter; the
    Fig. 8 run's traces copied out."""
    build, work = pathlib.Path(task["build"]), pathlib.Path(task["workdir"])
    rows = st.run_recording(dict(task, keep=True))
    rec = work / "rec" / task["rec_name"]
    try:
        kappa = kappa_of(build, rec) if (rec / "can.log").is_file() else {}
    except Exception as err:  # noqa: BLE001  -- the rows say it
        kappa = dict(kappa_error=str(err))
    truth = st.load_phi(task["load"])
    out = []
    for r in rows:
        source = r.pop("noise")
        if r["method"] in st.REF_METHODS:
            if source != SIGNALS[0]:
                continue                    # the same reference for every source: once
            source = ""
        r.update(trajectory=task["traj_name"], signals=source, **kappa)
        if r.get("ok"):
            r.update({f"err{i}": float(e) for i, e in
                      enumerate(eq37([r[f"phi{i}"] for i in range(10)], truth))})
        out.append(r)
    results = work / "results"
    if task.get("fig8_traces"):
        dest = pathlib.Path(task["fig8_traces"])
        dest.mkdir(parents=True, exist_ok=True)
        for s in SIGNALS:
            t = results / f"{task['rec_name']}-{s}.trace.csv"
            if t.is_file():
                shutil.copy(t, dest / f"{task['load']}-{task['traj_name']}-s{task['seed']}-{s}.csv")
    if not task["keep_all"]:
        shutil.rmtree(rec, ignore_errors=True)
        for s in SIGNALS:
            (results / f"{task['rec_name']}-{s}.trace.csv").unlink(missing_ok=True)
    return out


def stats(values) -> dict:
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], float)
    if not len(v):
        return dict(n=0, median=None, p90=None, min=None, max=None)
    return dict(n=int(len(v)), median=float(np.median(v)), p90=float(np.percentile(v, 90)),
                min=float(v.min()), max=float(v.max()))


def summarise(rows, loads) -> dict:
    """Per (load, trajectory, signals, method): eq. (37) of every parameter,
    median and 90th percentile over the seeds, and the study's metrics; per
    (trajectory, load): the kappas over the seeds."""
    cells = {}
    for r in rows:
        cells.setdefault((r["load"], r["trajectory"], r["signals"], r["method"]), []).append(r)
    out = []
    for (load, traj, sig, m), rs in cells.items():
        ok = [r for r in rs if r.get("ok")]
        out.append(dict(load=load, trajectory=traj, signals=sig, method=m, runs=len(rs),
                        ok=len(ok), params={p: stats([r.get(f"err{i}") for r in ok])
                                            for i, p in enumerate(PARAMS)},
                        **{k: stats([r.get(k) for r in ok]) for k in st.METRICS},
                        errors=sorted({str(r.get("error")) for r in rs if not r.get("ok")})))
    kappa = []
    for traj in TRAJECTORIES:
        for load in loads:
            rs = {(r["seed"]): r for r in rows if r["trajectory"] == traj and r["load"] == load}
            kappa.append(dict(trajectory=traj, load=load,
                              **{k: stats([r.get(k) for r in rs.values()])
                                 for k in ("kappa_set", "kappa_sens", "kappa_kf")}))
    return dict(cells=out, kappa=kappa)


def cell(summary, load, traj, signals, method):
    """One cell of the summary (the references under signals "")."""
    sig = "" if method in st.REF_METHODS else signals
    for c in summary["cells"]:
        if (c["load"], c["trajectory"], c["signals"], c["method"]) == (load, traj, sig, method):
            return c
    return None


def table1_text(summary, trajectories) -> str:
    lines = ["Table I: condition numbers of the data matrix A (loadid-kappa), median over the "
             "seeds [min, max]",
             f"{'traj':<5} {'load':<5} {'kappa_set':>10} {'kappa_sens':>22} {'kappa_kf':>22}"
             f" {'kappa_design':>13} | paper: {'kappa_set':>9} {'kappa_sens':>10}"]
    for k in summary["kappa"]:
        paper = PAPER_TABLE1.get((k["trajectory"], k["load"]))

        def f(s):
            if s["median"] is None:
                return "-".rjust(22)
            return f"{s['median']:.2f} [{s['min']:.2f}, {s['max']:.2f}]".rjust(22)
        lines.append(f"{k['trajectory']:<5} {k['load']:<5} "
                     f"{(k['kappa_set']['median'] or math.nan):>10.2f} {f(k['kappa_sens'])} "
                     f"{f(k['kappa_kf'])} {trajectories[k['trajectory']].get('kappa_design', math.nan):>13.3f}"
                     f" | {'':7}"
                     + (f"{paper[0]:>9.2f} {paper[1]:>10.2f}" if paper else f"{'-':>9} {'-':>10}"))
    return "\n".join(lines)


# The paper's Table I: (trajectory, load) -> (kappa_set, kappa_sens).
PAPER_TABLE1 = {("tr1", "o1"): (7.72, 23.23), ("tr1", "o2"): (7.72, 23.42),
                ("tr2", "o1"): (8.18, 16.89), ("tr2", "o2"): (8.18, 14.44)}


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, CSV_FIELDS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else r.get(k)) for k in CSV_FIELDS})


def main(a) -> int:
    """a: loadid_study's parsed arguments (--seeds, --jobs, --build,
    --workdir, --out, --keep)."""
    import paper_figures
    import paper_report

    began = time.monotonic()
    seeds = a.seeds if a.seeds is not None else DEFAULT_SEEDS
    if seeds < 1 or a.jobs < 1:
        raise SystemExit("loadid-study: --seeds and --jobs must be >= 1")
    build = pathlib.Path(a.build).resolve() if a.build else st.REPO / "build" / "release"
    work = (pathlib.Path(a.workdir).resolve() if a.workdir
            else pathlib.Path(tempfile.mkdtemp(prefix="loadid-paper-")))
    out_dir = pathlib.Path(a.out).resolve() if a.out else work
    for d in (work, out_dir, work / "traj", work / "configs"):
        d.mkdir(parents=True, exist_ok=True)

    def log(msg):
        print(f"[{time.monotonic() - began:7.1f} s] {msg}", file=sys.stderr, flush=True)

    st.lcm_types(build)
    stamp = st.program_stamp(build)
    log(f"build {build}; work folder {work}; output {out_dir}")
    loads = PAPER_LOADS
    cfg = work / "configs" / f"traj-{ROBOT}.yaml"
    cfg.write_text(st.robot_yaml(ROBOT))
    est_cfgs = {}
    for s in SIGNALS:
        est_cfgs[s] = work / "configs" / f"est-{ROBOT}-{NOISE}-{s}.yaml"
        est_cfgs[s].write_text(st.est_config(ROBOT, NOISE, METHODS, signals=s))

    with futures.ProcessPoolExecutor(max_workers=a.jobs) as pool:
        designs = [pool.submit(design, dict(build=str(build), name=name, seed=seed,
                                            config=str(cfg),
                                            path=str(trajectory_path(work, seed))))
                   for name, seed in TRAJECTORIES.items()]
        trajectories = {d["name"]: d for d in (f.result() for f in designs)}
        for d in trajectories.values():
            log(f"trajectory {d['name']} (loadid-traj --seed {d['seed']}): kappa_design "
                f"{d.get('kappa_design', math.nan):.3f}, kappa_set {d.get('kappa_set', math.nan):.2f}"
                f" -> {d['path']}")
        tasks = []
        for load in loads:
            sp = work / "configs" / f"sim-{ROBOT}-{load}-{NOISE}.yaml"
            sp.write_text(st.sim_config(ROBOT, load, NOISE))
            for traj in TRAJECTORIES:
                for seed in range(1, seeds + 1):
                    fig8 = (load, traj, seed) == (FIG8["load"], FIG8["trajectory"], FIG8["seed"])
                    # run_recording's "trajectory" is the file
                    tasks.append(dict(build=str(build), workdir=str(work), robot=ROBOT, load=load,
                                      seed=seed, traj_name=traj,
                                      rec_name=f"{ROBOT}-{load}-{traj}-s{seed}",
                                      sim_config=str(sp), trajectory=trajectories[traj]["path"],
                                      methods=METHODS, keep_all=a.keep,
                                      fig8_traces=str(out_dir / "traces") if fig8 else None,
                                      cells=[dict(noise=s, est_config=str(est_cfgs[s]))
                                             for s in SIGNALS]))
        log(f"{len(loads)} loads x {len(TRAJECTORIES)} trajectories x {seeds} seeds: "
            f"{len(tasks)} recordings, {len(SIGNALS)} signal sources each, {a.jobs} jobs")
        rows, done = [], 0
        pending = {pool.submit(paper_recording, t): t for t in tasks}
        for fut in futures.as_completed(pending):
            t = pending[fut]
            try:
                rows.extend(fut.result())
            except Exception as err:  # noqa: BLE001  -- a dead worker: report, go on
                log(f"{t['rec_name']}: {err!r}")
                rows.extend(dict(load=t["load"], trajectory=t["traj_name"], seed=t["seed"],
                                 signals=s, method=m, ok=False, error=f"worker failed: {err!r}")
                            for s in SIGNALS for m in METHODS)
            done += 1
            if done % max(1, len(tasks) // 10) == 0 or done == len(tasks):
                log(f"{done}/{len(tasks)} recordings")
    order = {m: i for i, m in enumerate(ALL_METHODS)}
    rows.sort(key=lambda r: (loads.index(r["load"]), list(TRAJECTORIES).index(r["trajectory"]),
                             r["seed"], (SIGNALS.index(r["signals"]) if r["signals"] else -1),
                             order[r["method"]]))
    summary = summarise(rows, loads)
    write_csv(out_dir / "runs.csv", rows)
    (out_dir / "table1.txt").write_text(table1_text(summary, trajectories) + "\n")
    meta = dict(build=str(build), workdir=str(work), robot=ROBOT, loads=loads,
                loads_phi={k: list(map(float, st.load_phi(k))) for k in loads},
                blocks={k: st.BLOCKS[k][0] for k in loads if k in st.BLOCKS},
                trajectories=trajectories, noise=dict(cell=NOISE, **st.NOISE_CELLS[NOISE]),
                signals=SIGNALS, methods=ALL_METHODS, seeds=seeds, jobs=a.jobs, fig8=FIG8,
                programs_changed_during_run=st.program_stamp(build) != stamp)
    meta["seconds"] = time.monotonic() - began      # the runs; the figures add a few seconds
    (out_dir / "summary.json").write_text(json.dumps(dict(meta=meta, **summary), indent=1))
    log("figures and report")
    figures = paper_figures.make_all(out_dir, summary, meta)
    paper_report.write(out_dir, summary, meta, figures)
    print((out_dir / "table1.txt").read_text())
    bad = sum(1 for r in rows if not r.get("ok"))
    if bad:
        print(f"{bad} of {len(rows)} rows without an estimate (see runs.csv)")
    if meta["programs_changed_during_run"]:
        print("WARNING: the programs in the build tree changed during the run")
    print(f"report: {out_dir / 'report.md'}\nruns: {out_dir / 'runs.csv'}\n"
          f"figures: {', '.join(sorted(figures))}")
    print(f"time taken: {time.monotonic() - began:.1f} s ({len(tasks)} recordings, {len(rows)} rows)")
    return 0



def replot(a) -> int:
    """The figures and report again from --out's summary.json and traces/."""
    import paper_figures
    import paper_report
    if not a.out:
        raise SystemExit("loadid-study: --replot needs --out DIR (an earlier --paper's output)")
    out_dir = pathlib.Path(a.out).resolve()
    data = json.loads((out_dir / "summary.json").read_text())
    summary = dict(cells=data["cells"], kappa=data["kappa"])
    figures = paper_figures.make_all(out_dir, summary, data["meta"])
    paper_report.write(out_dir, summary, data["meta"], figures)
    print(f"report: {out_dir / 'report.md'}\nfigures: {', '.join(sorted(figures))}")
    return 0
