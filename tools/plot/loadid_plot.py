"""loadid plot's drawing (host/src/cli_plot.c runs it with the build's venv,
or LOADID_PYTHON, or python3): PNG figures of loadidd --offline --trace
CSVs (docs/INTERFACE.md), with matplotlib's Agg backend.

    loadid_plot.py [--out DIR] [--truth TRUTH.yaml] PATH...

PATH is a trace CSV, or a directory: every trace CSV in it (a file whose
first line is the trace's header) and a loadid-demo runs.csv. Per trace
STEM.csv it writes
  STEM-estimates.png  every method's mass [kg], COM [mm] and inertia about
                      the COM [1e-3 kg m^2] over the window (on-line methods
                      as lines, +-2 phi_std on the mass; every final estimate
                      as a marker at the window's end; the truth dashed when
                      known: --truth, or truth.yaml beside the trace)
  STEM-residual.png   the residual wrench of every on-line method over the
                      window: the newest sample's measured wrench minus
                      A(t) phi_hat of the estimate at that moment (the
                      trace's res_* columns), force [N] and torque [N m]
  STEM-residual.csv   per method the RMS residual, per axis: "online" (the
                      res_* columns of its on-line rows) and "final" (every
                      traced sample's wrench minus A(t) of its final
                      estimate, computed here from the rows' wrench and
                      motion by the paper's eqs. (1)-(2))
and prints the same numbers; for runs.csv, errors.png: eq. (37) per
parameter and method, the median over the seeds, whiskers from the best to
the worst seed, per signal source, the paper's marks with the JR3 signals.
"""

from __future__ import annotations

import argparse
import csv
import math
import pathlib
import re
import sys

TRACE_HEAD = "t_s,method,valid,samples,"
FORCE = ["res_fx", "res_fy", "res_fz"]
TORQUE = ["res_tx", "res_ty", "res_tz"]
ONLINE = ["RLS", "RIV", "RTLS"]
COLORS = {"RLS": "#d62728", "RIV": "#ff7f0e", "RTLS": "#1f77b4", "LS_BATCH": "#8c564b",
          "TLS_BATCH": "#17becf", "REFINED": "#2ca02c"}
MARKERS = {"LS_BATCH": "s", "TLS_BATCH": "D", "REFINED": "*", "RLS": "o", "RIV": "o", "RTLS": "o"}
PANELS = [("mass", "mass [kg]", 1.0), ("com_x", "COM x [mm]", 1e3), ("com_y", "COM y [mm]", 1e3),
          ("com_z", "COM z [mm]", 1e3), ("ixx", r"$I_{xx}$ [$10^{-3}$ kg m$^2$]", 1e3),
          ("ixy", r"$I_{xy}$ [$10^{-3}$ kg m$^2$]", 1e3), ("ixz", r"$I_{xz}$ [$10^{-3}$ kg m$^2$]", 1e3),
          ("iyy", r"$I_{yy}$ [$10^{-3}$ kg m$^2$]", 1e3), ("iyz", r"$I_{yz}$ [$10^{-3}$ kg m$^2$]", 1e3),
          ("izz", r"$I_{zz}$ [$10^{-3}$ kg m$^2$]", 1e3)]
# What the paper's Fig. 6 shows (o1, tr2, JR3 accelerations), eq. (37) [%].
PAPER = dict(rtls_mass_below=1.0, rtls_ixx=21.0, rls_ixx=39.0)


def is_trace(path: pathlib.Path) -> bool:
    try:
        with open(path) as f:
            return f.readline().startswith(TRACE_HEAD)
    except (OSError, UnicodeDecodeError):
        return False


def read_trace(path):
    """{method: [row dict of floats (method kept as text)]}, in file order."""
    rows = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            row = {k: (v if k == "method" else float(v)) for k, v in r.items()}
            rows.setdefault(r["method"], []).append(row)
    return rows


def read_truth(path):
    """mass, com and inertia_com of truth.yaml's load (loadid-sim's
    format, flat lines under `load:`), or None."""
    if not path or not path.is_file():
        return None
    load, section = {}, None
    for line in path.read_text().splitlines():
        m = re.match(r"^(\w[\w-]*):", line)
        if m:
            section = m.group(1)
            continue
        m = re.match(r"^  (mass|com|inertia_com):\s*(.*)$", line)
        if m and section == "load":
            load[m.group(1)] = [float(x) for x in m.group(2).strip("[] ").split(",")]
    if set(load) != {"mass", "com", "inertia_com"}:
        return None
    return dict(mass=load["mass"][0], com_x=load["com"][0], com_y=load["com"][1],
                com_z=load["com"][2], **dict(zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
                                                 load["inertia_com"])))


def predicted_wrench(np, phi, spec, omega, alpha):
    """The paper's eqs. (1)-(2) for rows of motion (n x 3 each) and one phi
    (inertia about the origin of S): f = m a + alpha x mc + omega x (omega x
    mc), tau = I alpha + omega x (I omega) + mc x a, a the specific force."""
    m, mc = phi[0], np.asarray(phi[1:4])
    i = phi[4:10]
    inertia = np.array([[i[0], i[1], i[2]], [i[1], i[3], i[4]], [i[2], i[4], i[5]]])
    f = m * spec + np.cross(alpha, mc) + np.cross(omega, np.cross(omega, mc))
    tau = alpha @ inertia.T + np.cross(omega, omega @ inertia.T) + np.cross(mc, spec)
    return np.hstack([f, tau])


def cols(np, rows, names):
    return np.array([[r[n] for n in names] for r in rows], float)


WRENCH = ["fx", "fy", "fz", "tx", "ty", "tz"]
SPEC, OMEGA, ALPHA = ["spec_x", "spec_y", "spec_z"], ["omega_x", "omega_y", "omega_z"], \
    ["alpha_x", "alpha_y", "alpha_z"]
G_INIT = ["g_init_x", "g_init_y", "g_init_z"]


def residuals(np, trace):
    """Per method (online rows, final row, {"online": rms (6,), "final":
    rms (6,), n_online, n_final}). The on-line rows are all but a method's
    last (the trace ends with every method's final estimate)."""
    # Every traced sample once (the rows of one publication share it).
    samples = {}
    for rows in trace.values():
        for r in rows:
            if not math.isnan(r["fx"]):
                samples.setdefault(r["t_s"], r)
    ss = [samples[t] for t in sorted(samples)]
    out = {}
    for m, rows in trace.items():
        online, final = rows[:-1], rows[-1]
        res = {}
        valid = [r for r in online if r["valid"] == 1 and not math.isnan(r["res_fx"])]
        res["n_online"] = len(valid)
        res["online"] = (np.sqrt(np.mean(cols(np, valid, FORCE + TORQUE) ** 2, axis=0))
                         if valid else np.full(6, np.nan))
        if final["valid"] == 1 and ss:
            phi = [final[f"phi{i}"] for i in range(10)]
            off = np.array([final[f"offset{i}"] for i in range(6)])
            spec = cols(np, ss, SPEC) + cols(np, ss, G_INIT)
            pred = predicted_wrench(np, phi, spec, cols(np, ss, OMEGA), cols(np, ss, ALPHA))
            r = cols(np, ss, WRENCH) - pred - off
            res["final"] = np.sqrt(np.mean(r ** 2, axis=0))
            res["n_final"] = len(ss)
        else:
            res["final"], res["n_final"] = np.full(6, np.nan), 0
        out[m] = (online, final, res)
    return out


def _limits(values, truth=None, pad_frac=0.35):
    v = [x for x in values if math.isfinite(x)]
    if truth is not None and math.isfinite(truth):
        v.append(truth)
    if not v:
        return None
    lo, hi = min(v), max(v)
    pad = max(pad_frac * (hi - lo), 0.05 * max(abs(lo), abs(hi)), 1e-12)
    return lo - pad, hi + pad


def plot_estimates(plt, np, trace, res, truth, title, path):
    fig, axes = plt.subplots(2, 5, figsize=(17, 7), sharex=True)
    t_end = max(r["t_s"] for rows in trace.values() for r in rows)
    first = min((r["t_s"] for m in ONLINE if m in trace for r in trace[m] if r["valid"] == 1),
                default=0.0)
    for ax, (key, label, k) in zip(axes.ravel(), PANELS):
        late = []
        for m, (online, final, _) in res.items():
            if m in ONLINE and online:
                t = np.array([r["t_s"] for r in online])
                y = np.array([r[key] for r in online]) * k
                ax.plot(t, y, color=COLORS.get(m, "k"), lw=1.1, label=m)
                late.extend(y[t >= t_end / 3])
                if key == "mass":
                    s = np.array([r["phi_std0"] for r in online])
                    ok = np.isfinite(s) & np.isfinite(y)
                    ax.fill_between(t[ok], (y - 2 * s)[ok], (y + 2 * s)[ok],
                                    color=COLORS.get(m, "k"), alpha=0.15, lw=0)
            if final["valid"] == 1:
                # side by side at the window's end: finals often coincide
                dx = 0.012 * t_end * list(res).index(m)
                ax.plot([final["t_s"] + dx], [final[key] * k], marker=MARKERS.get(m, "o"), ms=6,
                        color=COLORS.get(m, "k"), mec="black", mew=0.5, ls="none",
                        label=f"{m} final")
                late.append(final[key] * k)
        tv = truth[key] * k if truth else None
        if tv is not None:
            ax.axhline(tv, color="black", ls="--", lw=1, label="truth")
        lim = _limits(late, tv)
        if lim:
            ax.set_ylim(*lim)
        ax.axvspan(0.0, first, color="#eeeeee", lw=0)
        ax.set_xlim(-0.02 * t_end, 1.1 * t_end)
        ax.set_title(label, fontsize=10)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("t after START [s]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=min(len(labels), 10), fontsize=8)
    fig.suptitle(f"{title}: the estimates over the window (mass band: +-2 phi_std; grey: no "
                 f"estimate yet, before {first:.2f} s{'; dashed: the truth' if truth else ''})",
                 fontsize=11)
    fig.tight_layout(rect=(0, 0.05, 1, 1))
    fig.savefig(path, dpi=100)
    plt.close(fig)


def plot_residual(plt, np, res, title, path):
    fig, axes = plt.subplots(2, 3, figsize=(15, 7), sharex=True)
    t_end = max((r["t_s"] for online, final, _ in res.values() for r in online + [final]),
                default=1.0)
    first = min((x["t_s"] for m, (online, _, _) in res.items() if m in ONLINE
                 for x in online if x["valid"] == 1), default=0.0)
    names = [("res_fx", r"$f_x$ [N]"), ("res_fy", r"$f_y$ [N]"), ("res_fz", r"$f_z$ [N]"),
             ("res_tx", r"$\tau_x$ [N m]"), ("res_ty", r"$\tau_y$ [N m]"),
             ("res_tz", r"$\tau_z$ [N m]")]
    for j, (ax, (key, label)) in enumerate(zip(axes.ravel(), names)):
        late, t_all = [], []
        for m, (online, _, r) in res.items():
            if m not in ONLINE:
                continue
            rows = [x for x in online if x["valid"] == 1]
            if not rows:
                continue
            t = np.array([x["t_s"] for x in rows])
            y = np.array([x[key] for x in rows])
            t_all.extend(t)
            ax.plot(t, y, color=COLORS[m], lw=0.9, alpha=0.85,
                    label=f"{m} (final estimate's RMS {r['final'][j]:.3g})")
            late.extend(y[t >= max(t) / 3])
        lim = _limits(late, None, 0.15)
        if lim:
            ax.set_ylim(*lim)
        ax.axhline(0, color="black", lw=0.6)
        ax.axvspan(0.0, first, color="#eeeeee", lw=0)
        ax.set_xlim(-0.02 * t_end, 1.02 * t_end)
        ax.set_title(f"residual {label}", fontsize=10)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    for ax in axes[1]:
        ax.set_xlabel("t after START [s]")
    fig.suptitle(f"{title}: the residual wrench, measured minus A(t) phi_hat of the estimate at "
                 "that moment, on each row's newest sample\n(grey: no estimate yet; the y range "
                 "fits the last two thirds of the window; in the legend the RMS over every traced "
                 "sample with the final estimate)", fontsize=11)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def write_residual_csv(path, res):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["method", "kind", "samples", "rms_fx", "rms_fy", "rms_fz", "rms_tx",
                    "rms_ty", "rms_tz"])
        for m, (_, _, r) in res.items():
            for kind in ("online", "final"):
                w.writerow([m, kind, r[f"n_{kind}"]] + [f"{x:.9g}" for x in r[kind]])


def print_residual(res, name, noise):
    said = f"; the simulated noise: f {noise[0]:.3g} N, tau {noise[1]:.3g} N m" if noise else ""
    print(f"   {name}: the residual wrench's RMS per axis x y z, with the final estimate over "
          f"every traced sample, and as it went (each on-line row's own estimate){said}")
    for m, (_, _, r) in res.items():
        line = []
        for kind in ("final", "online"):
            if r[f"n_{kind}"]:
                f, t = r[kind][:3], r[kind][3:]
                line.append(f"{'final' if kind == 'final' else 'as it went'} f "
                            f"[{' '.join(f'{x:.3g}' for x in f)}] N, tau "
                            f"[{' '.join(f'{x:.3g}' for x in t)}] N m")
        print(f"     {m:<9} {'; '.join(line)}")


def read_noise(path):
    """noise.force and noise.torque of truth.yaml, or None."""
    if not path or not path.is_file():
        return None
    got, section = {}, None
    for line in path.read_text().splitlines():
        m = re.match(r"^(\w[\w-]*):", line)
        if m:
            section = m.group(1)
            continue
        m = re.match(r"^  (force|torque):\s*([-+.\deE]+)\s*$", line)
        if m and section == "noise":
            got[m.group(1)] = float(m.group(2))
    return (got["force"], got["torque"]) if len(got) == 2 else None


def plot_trace(plt, np, path: pathlib.Path, out: pathlib.Path, truth_path):
    trace = read_trace(path)
    if not trace:
        print(f"   {path}: no rows", file=sys.stderr)
        return []
    res = residuals(np, trace)
    truth_path = truth_path if truth_path else path.parent / "truth.yaml"
    truth = read_truth(truth_path)
    stem = path.stem
    title = f"{path.name}"
    written = []
    for suffix, fn in (("estimates.png", lambda p: plot_estimates(plt, np, trace, res, truth,
                                                                   title, p)),
                       ("residual.png", lambda p: plot_residual(plt, np, res, title, p))):
        p = out / f"{stem}-{suffix}"
        fn(p)
        written.append(p)
    p = out / f"{stem}-residual.csv"
    write_residual_csv(p, res)
    written.append(p)
    print_residual(res, path.name, read_noise(truth_path))
    return written


def plot_runs(plt, np, path: pathlib.Path, out: pathlib.Path):
    """loadid-demo's runs.csv: eq. (37) per parameter and method, median
    over the seeds, whiskers from the best to the worst, per source."""
    rows = list(csv.DictReader(open(path, newline="")))
    sources = list(dict.fromkeys(r["signals"] for r in rows))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    labels = [r"$m$", r"$mc_x$", r"$mc_y$", r"$mc_z$", r"$I_{xx}$", r"$I_{xy}$", r"$I_{xz}$",
              r"$I_{yy}$", r"$I_{yz}$", r"$I_{zz}$"]
    fig, axes = plt.subplots(len(sources), 1, figsize=(12, 4.2 * len(sources)), squeeze=False)
    x = np.arange(10)
    width = 0.8 / len(methods)
    seeds = len({r["seed"] for r in rows})
    for ax, src in zip(axes[:, 0], sources):
        for k, m in enumerate(methods):
            e = np.array([[float(r[f"err{i}"]) for i in range(10)] for r in rows
                          if r["signals"] == src and r["method"] == m and r["valid"] == "1"])
            if not len(e):
                continue
            med, lo, hi = np.median(e, 0), e.min(0), e.max(0)
            xs = x - 0.4 + width * (k + 0.5)
            ax.bar(xs, med, width, color=COLORS.get(m, "grey"), label=m, zorder=2)
            ax.errorbar(xs, med, yerr=[med - lo, hi - med], fmt="none", ecolor="black",
                        elinewidth=0.7, capsize=1.5, zorder=3)
        if src == "sensor":
            kr, kl = methods.index("RTLS"), methods.index("RLS")
            ax.plot([x[4] - 0.4 + width * (kr + 0.5)], [PAPER["rtls_ixx"]], marker="*", ms=11,
                    color=COLORS["RTLS"], mec="black", ls="none", zorder=4,
                    label="paper (Fig. 6): RTLS, RLS")
            ax.plot([x[4] - 0.4 + width * (kl + 0.5)], [PAPER["rls_ixx"]], marker="*", ms=11,
                    color=COLORS["RLS"], mec="black", ls="none", zorder=4)
            ax.hlines(PAPER["rtls_mass_below"], x[0] - 0.45, x[0] + 0.45, colors="black",
                      linestyles="--", zorder=4, label="paper: RTLS's mass < 1 %")
        ax.set_yscale("log")
        ax.set_xticks(x, labels)
        ax.set_ylabel("eq. (37) error [%]")
        ax.grid(axis="y", alpha=0.4, zorder=0)
        ax.set_title(f"signals {src}: median over {seeds} seeds, whiskers from the best to the "
                     "worst seed", fontsize=10)
        ax.legend(fontsize=7.5, ncol=4, loc="upper left")
    fig.suptitle("loadid-demo: o1 on the simulated RX60, relative errors |x - x_true| / |x_true| "
                 "(eq. 37)", fontsize=11)
    fig.tight_layout()
    p = out / "errors.png"
    fig.savefig(p, dpi=100)
    plt.close(fig)
    return [p]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(
        prog="loadid_plot.py",
        description="PNG figures of loadidd --offline --trace CSVs (and of loadid-demo's "
                    "runs.csv): the estimates over time and the residual wrench.")
    ap.add_argument("paths", nargs="+", metavar="PATH",
                    help="a trace CSV, or a directory: its trace CSVs and runs.csv")
    ap.add_argument("--out", help="the figures' folder (default: beside each input)")
    ap.add_argument("--truth", help="truth.yaml of the recording (default: beside the trace)")
    a = ap.parse_args(argv)
    # Imported after the arguments: --help works without them.
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import numpy as np
    except ImportError as err:
        print(f"loadid plot: needs numpy and matplotlib ({err}); `bash tools/setup.sh demo` "
              "installs them into build/venv, or set LOADID_PYTHON", file=sys.stderr)
        return 1
    traces, runs = [], []
    for p in map(pathlib.Path, a.paths):
        if p.is_dir():
            traces += [q for q in sorted(p.glob("*.csv")) if is_trace(q)]
            if (p / "runs.csv").is_file():
                runs.append(p / "runs.csv")
        elif is_trace(p):
            traces.append(p)
        else:
            print(f"loadid plot: {p}: not a trace CSV (loadidd --offline --trace) nor a folder",
                  file=sys.stderr)
            return 1
    if not traces and not runs:
        print(f"loadid plot: nothing to plot in {', '.join(a.paths)} (no trace CSV)",
              file=sys.stderr)
        return 1
    written = []
    for t in traces:
        out = pathlib.Path(a.out) if a.out else t.parent
        out.mkdir(parents=True, exist_ok=True)
        written += plot_trace(plt, np, t, out, pathlib.Path(a.truth) if a.truth else None)
    for r in runs:
        out = pathlib.Path(a.out) if a.out else r.parent
        out.mkdir(parents=True, exist_ok=True)
        written += plot_runs(plt, np, r, out)
    for w in written:
        print(f"   wrote {w}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
