"""The figures of loadid-study --paper (paper_study.py), as PNG with
matplotlib's Agg backend, from its summary (eq. (37) medians and 90th
percentiles per load, trajectory, signal source, method and parameter) and
the loadidd traces of one run:

  table1.png           Table I: kappa_set, kappa_sens (and kappa_kf) per
                       trajectory and load, beside the paper's
  fig6_o1_tr2_sensor.png, fig7_o1_tr2_mixed.png
                       Fig. 6/7: eq. (37) per parameter and method, bars the
                       median, whiskers up to the 90th percentile (log scale)
  fig8_o2_tr2_sensor.png
                       Fig. 8: every parameter's estimate over the 1.5 s
                       window, RLS, RIV and RTLS, with the truth and the
                       +-2 sigma band of the trace's phi_std
  fig9_o1_tr2_sources.png
                       Fig. 9: RTLS's eq. (37) per parameter and signal source
  rtls_ratios.png      where RTLS beats RLS and RIV: the ratio of RTLS's
                       median error to theirs, every cell of the grid
"""

from __future__ import annotations

import csv
import math
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

LABELS = [r"$m$", r"$mc_x$", r"$mc_y$", r"$mc_z$", r"$I_{xx}$", r"$I_{xy}$", r"$I_{xz}$",
          r"$I_{yy}$", r"$I_{yz}$", r"$I_{zz}$"]
PARAMS = ["m", "mcx", "mcy", "mcz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"]
# Display units of phi's groups: kg; kg mm; 1e-3 kg m^2.
UNIT_SCALE = [1.0, 1e3, 1e3, 1e3, 1e3, 1e3, 1e3, 1e3, 1e3, 1e3]
UNITS = ["kg", "kg mm", "kg mm", "kg mm"] + [r"$10^{-3}$ kg m$^2$"] * 6
COLORS = {"RLS": "#d62728", "RIV": "#ff7f0e", "RTLS": "#1f77b4", "TLS_BATCH": "#17becf",
          "REFINED": "#2ca02c", "REF_ACC": "#7f7f7f", "REF": "#bcbd22",
          "sensor": "#9467bd", "mixed": "#1f77b4", "kf": "#2ca02c", "setpoint": "#8c564b"}
BAR_METHODS = ["RLS", "RIV", "RTLS", "REFINED", "REF_ACC"]
SOURCE_NAMES = {"sensor": "sensor (JR3 a, alpha)", "mixed": "mixed (JR3 a, joints' alpha)",
                "kf": "kf (encoders)", "setpoint": "setpoint (commanded)"}
# What the brief reads off the paper's Fig. 6/7 (eq. (37), o1, tr2).
PAPER_MARKS = dict(mass_rtls_below=1.0, ixx_rtls=21.0, ixx_rls=39.0)


def cell(summary, load, traj, signals, method):
    sig = "" if method in ("REF", "REF_ACC") else signals
    for c in summary["cells"]:
        if (c["load"], c["trajectory"], c["signals"], c["method"]) == (load, traj, sig, method):
            return c
    return None


def _stat(c, p, key):
    v = c["params"][p][key] if c else None
    return math.nan if v is None else v


def grouped_bars(ax, series, colors, labels, annotate=None):
    """series: {name: (medians (10,), p90 (10,))}; bars the median, a whisker
    up to the 90th percentile; log scale."""
    names = list(series)
    width = 0.8 / len(names)
    x = np.arange(len(PARAMS))
    for k, name in enumerate(names):
        med, p90 = (np.asarray(v, float) for v in series[name])
        xs = x - 0.4 + width * (k + 0.5)
        ax.bar(xs, med, width, color=colors[name], label=labels[name], zorder=2)
        ax.errorbar(xs, med, yerr=[np.zeros_like(med), np.clip(p90 - med, 0, None)], fmt="none",
                    ecolor="black", elinewidth=0.8, capsize=1.5, zorder=3)
    ax.set_yscale("log")
    ax.set_xticks(x, LABELS)
    ax.set_ylabel("eq. (37) error [%]")
    ax.grid(axis="y", which="major", alpha=0.4, zorder=0)
    finite = [v for s in series.values() for arr in s for v in arr if math.isfinite(v) and v > 0]
    if finite:
        ax.set_ylim(max(min(finite) / 2, 1e-3), max(finite) * 4)
    if annotate in names:      # its medians' values, at the foot of its bars
        k = names.index(annotate)
        bottom = ax.get_ylim()[0]
        for xi, m in zip(x - 0.4 + width * (k + 0.5), series[annotate][0]):
            if math.isfinite(m) and m > bottom * 1.6:
                ax.text(xi, bottom * 1.1, f"{m:.2g}", ha="center", va="bottom", fontsize=7,
                        color="white", fontweight="bold", rotation=90, zorder=4)
    return x, width, names


def fig_errors(out, summary, meta, load, traj, signals, title, paper):
    seeds = meta["seeds"]
    series, labels = {}, {}
    for m in BAR_METHODS:
        c = cell(summary, load, traj, signals, m)
        series[m] = ([_stat(c, p, "median") for p in PARAMS], [_stat(c, p, "p90") for p in PARAMS])
        labels[m] = m if m != "REF_ACC" else "REF_ACC (batch TLS, true weights)"
    fig, ax = plt.subplots(figsize=(11, 4.8))
    x, width, names = grouped_bars(ax, series, COLORS, labels, annotate="RTLS")
    if paper:
        k_rtls, k_rls = names.index("RTLS"), names.index("RLS")
        xr = x[4] - 0.4 + width * (k_rtls + 0.5)
        xl = x[4] - 0.4 + width * (k_rls + 0.5)
        ax.plot([xr], [PAPER_MARKS["ixx_rtls"]], marker="*", ms=11, color=COLORS["RTLS"],
                mec="black", ls="none", label="paper (Fig. 6/7), RTLS / RLS", zorder=4)
        ax.plot([xl], [PAPER_MARKS["ixx_rls"]], marker="*", ms=11, color=COLORS["RLS"],
                mec="black", ls="none", zorder=4)
        ax.hlines(PAPER_MARKS["mass_rtls_below"], x[0] - 0.45, x[0] + 0.45, colors="black",
                  linestyles="--", zorder=4, label="paper: RTLS's mass error < 1 %")
    ax.set_title(f"{title}\n{load}, {traj}, signals {SOURCE_NAMES[signals]}; median over "
                 f"{seeds} seeds, whisker to the 90th percentile", fontsize=10)
    ax.legend(fontsize=7.5, ncol=3, loc="upper left")
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def fig_sources(out, summary, meta, load, traj):
    series, labels = {}, {}
    for s in meta["signals"]:
        c = cell(summary, load, traj, s, "RTLS")
        series[s] = ([_stat(c, p, "median") for p in PARAMS], [_stat(c, p, "p90") for p in PARAMS])
        labels[s] = SOURCE_NAMES[s]
    fig, ax = plt.subplots(figsize=(11, 4.5))
    grouped_bars(ax, series, COLORS, labels)
    ax.set_title(f"Fig. 9: RTLS's relative errors by signal source\n{load}, {traj}; median over "
                 f"{meta['seeds']} seeds, whisker to the 90th percentile", fontsize=10)
    ax.legend(fontsize=8, ncol=4, loc="upper left")
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    plt.close(fig)


def read_trace(path) -> dict:
    """loadidd --trace: per method the on-line rows (t_s, phi (10,),
    phi_std (10,)), the final row (same t_s as the last on-line one) left out."""
    series = {}
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            if r["valid"] != "1":
                continue
            phi = np.array([float(r[f"phi{i}"]) for i in range(10)])
            std = np.array([float(r[f"phi_std{i}"]) for i in range(10)])
            series.setdefault(r["method"], []).append((float(r["t_s"]), phi, std))
    out = {}
    for m, rows in series.items():
        if len(rows) > 1 and rows[-1][0] == rows[-2][0]:
            rows = rows[:-1]
        out[m] = (np.array([r[0] for r in rows]), np.array([r[1] for r in rows]),
                  np.array([r[2] for r in rows]))
    return out


def fig_evolution(out, trace_path, truth, title):
    series = read_trace(trace_path)
    first = min((series[m][0][0] for m in ("RLS", "RIV", "RTLS") if m in series), default=0.0)
    fig, axes = plt.subplots(2, 5, figsize=(17, 7), sharex=True)
    for i, ax in enumerate(axes.ravel()):
        k = UNIT_SCALE[i]
        late = []
        for m in ("RLS", "RIV", "RTLS"):
            if m not in series:
                continue
            t, phi, std = series[m]
            y, s = phi[:, i] * k, std[:, i] * k
            ok = np.isfinite(s)
            ax.fill_between(t[ok], (y - 2 * s)[ok], (y + 2 * s)[ok], color=COLORS[m], alpha=0.18,
                            lw=0)
            ax.plot(t, y, color=COLORS[m], lw=1.1, label=m)
            late.extend(y[t >= 0.5])
        ax.axhline(truth[i] * k, color="black", ls="--", lw=1, label="truth")
        if late:
            # Keep the late part of every estimate and the truth in view;
            # the first tenths of a second (few samples) may leave it.
            lo, hi = min(min(late), truth[i] * k), max(max(late), truth[i] * k)
            pad = max(0.35 * (hi - lo), 0.05 * abs(truth[i] * k))
            ax.set_ylim(lo - pad, hi + pad)
        ax.set_title(f"{LABELS[i]} [{UNITS[i]}]", fontsize=10)
        ax.set_xlim(0.0, 1.5)
        ax.axvspan(0.0, first, color="#eeeeee", lw=0)
        ax.grid(alpha=0.3)
        if i >= 5:
            ax.set_xlabel("t after START [s]")
    axes[0, 0].legend(fontsize=8, loc="best")
    fig.suptitle(f"{title}\ngrey: no estimate yet (before {first:.2f} s the data do not pass "
                 "the excitation gate)", fontsize=11)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def fig_ratios(out, summary, meta):
    rows, labels = [], []
    for load in meta["loads"]:
        for traj in meta["trajectories"]:
            for s in meta["signals"]:
                rtls = cell(summary, load, traj, s, "RTLS")
                r = []
                for other in ("RLS", "RIV"):
                    o = cell(summary, load, traj, s, other)
                    r.append([_stat(rtls, p, "median") / _stat(o, p, "median") for p in PARAMS])
                rows.append(r)
                labels.append(f"{load} {traj} {s}")
    R = np.array(rows)                                   # (cells, 2, 10)
    fig, axes = plt.subplots(1, 2, figsize=(15, 0.32 * len(labels) + 2.2), sharey=True)
    for k, (ax, other) in enumerate(zip(axes, ("RLS", "RIV"))):
        v = np.log10(np.clip(R[:, k, :], 1e-3, 1e3))
        im = ax.imshow(v, cmap="RdBu_r", vmin=-1.5, vmax=1.5, aspect="auto")
        for (i, j), val in np.ndenumerate(R[:, k, :]):
            if math.isfinite(val):
                ax.text(j, i, f"{val:.2g}", ha="center", va="center", fontsize=6.5,
                        color="white" if abs(math.log10(max(val, 1e-3))) > 0.9 else "black")
        ax.set_xticks(range(len(PARAMS)), LABELS)
        ax.set_yticks(range(len(labels)), labels, fontsize=7.5)
        wins = int(np.sum(R[:, k, :] < 1))
        ax.set_title(f"RTLS / {other}: median eq. (37) error ratio\n(blue < 1: RTLS better; "
                     f"{wins} of {R[:, k, :].size} cells)", fontsize=10)
    fig.colorbar(im, ax=axes, shrink=0.6, label="log10(ratio)")
    fig.suptitle(f"Where RTLS beats RLS and RIV ({meta['seeds']} seeds per cell)", fontsize=11)
    fig.savefig(out, dpi=110, bbox_inches="tight")
    plt.close(fig)


def _f2(x):
    return "-" if x is None else f"{x:.2f}"


def fig_table1(out, summary, meta, paper_table):
    head = ["trajectory", "load", "kappa_set", "kappa_sens\nmedian [min, max]",
            "kappa_kf\nmedian", "kappa_design", "paper\nkappa_set", "paper\nkappa_sens"]
    body = []
    for k in summary["kappa"]:
        p = paper_table.get((k["trajectory"], k["load"]))
        ks = k["kappa_sens"]
        body.append([k["trajectory"], k["load"], _f2(k["kappa_set"]["median"]),
                     f"{_f2(ks['median'])} [{_f2(ks['min'])}, {_f2(ks['max'])}]",
                     _f2(k["kappa_kf"]["median"]),
                     f"{meta['trajectories'][k['trajectory']].get('kappa_design', math.nan):.3f}",
                     f"{p[0]:.2f}" if p else "-", f"{p[1]:.2f}" if p else "-"])
    fig, ax = plt.subplots(figsize=(10, 0.4 * len(body) + 0.9))
    ax.axis("off")
    t = ax.table(cellText=body, colLabels=head, loc="center", cellLoc="center",
                 colWidths=[0.1, 0.07, 0.1, 0.21, 0.1, 0.12, 0.1, 0.1])
    t.auto_set_font_size(False)
    t.set_fontsize(9)
    t.scale(1, 1.6)
    for j in range(len(head)):
        t[0, j].set_facecolor("#dddddd")
        t[0, j].set_height(t[0, j].get_height() * 1.5)
    ax.set_title(f"Table I: condition numbers of A (loadid-kappa), {meta['seeds']} seeds; "
                 "kappa_design: loadid-traj's weighted criterion", fontsize=10)
    fig.savefig(out, dpi=130, bbox_inches="tight")
    plt.close(fig)


def make_all(out_dir, summary, meta) -> dict:
    """Every figure into out_dir; returns {file name: what it shows}."""
    from paper_study import PAPER_TABLE1
    out_dir = pathlib.Path(out_dir)
    figs = {}
    fig_table1(out_dir / "table1.png", summary, meta, PAPER_TABLE1)
    figs["table1.png"] = "Table I: kappa_set and kappa_sens per trajectory and load"
    f6 = "fig6_o1_tr2_sensor.png"
    fig_errors(out_dir / f6, summary, meta, "o1", "tr2", "sensor",
               "Fig. 6: relative errors of the estimation methods, accelerations from the JR3",
               paper=True)
    figs[f6] = "Fig. 6: eq. (37) per parameter and method, o1, tr2, JR3 accelerations"
    f7 = "fig7_o1_tr2_mixed.png"
    fig_errors(out_dir / f7, summary, meta, "o1", "tr2", "mixed",
               "Fig. 7: relative errors, linear accelerations from the JR3, angular from the "
               "joints", paper=True)
    figs[f7] = "Fig. 7: the same with alpha from the joints (mixed)"
    f8 = meta["fig8"]
    trace = (out_dir / "traces" /
             f"{f8['load']}-{f8['trajectory']}-s{f8['seed']}-{f8['signals']}.csv")
    if trace.is_file():
        name = f"fig8_{f8['load']}_{f8['trajectory']}_{f8['signals']}.png"
        fig_evolution(out_dir / name, trace, np.array(meta["loads_phi"][f8["load"]]),
                      f"Fig. 8: the estimates over the window, {f8['load']}, {f8['trajectory']}, "
                      f"seed {f8['seed']}, signals {SOURCE_NAMES[f8['signals']]}; shaded "
                      "\u00b12 phi_std, dashed the truth")
        figs[name] = "Fig. 8: every parameter's estimate over the 1.5 s with +-2 sigma"
    f9 = "fig9_o1_tr2_sources.png"
    fig_sources(out_dir / f9, summary, meta, "o1", "tr2")
    figs[f9] = "Fig. 9: RTLS's eq. (37) per parameter and signal source, o1, tr2"
    fig_ratios(out_dir / "rtls_ratios.png", summary, meta)
    figs["rtls_ratios.png"] = "RTLS's median error over RLS's and RIV's, every cell"
    return figs
