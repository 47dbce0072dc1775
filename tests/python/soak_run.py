"""The soak's harness, shared by tests/bench/bench_soak.py (an hour) and
test_soak.py (CI's minute): the configuration, soak_session.py in a private
network namespace, --offline's estimate of one pass for reference, and the
figures made of what came back (summarize) and printed (report)."""

from __future__ import annotations

import json
import math
import pathlib
import re
import statistics
import subprocess
import sys

HERE = pathlib.Path(__file__).resolve().parent
METHODS = {1: "RLS", 2: "RIV", 3: "RTLS", 6: "REFINED"}
WARMUP_SESSIONS = 2  # memory is compared from the end of the second session on

# --verbose's summary at exit (live.c).
SUMMARY = re.compile(r"^loadidd: samples ok (\d+), used (\d+), frames bad (\d+), incomplete (\d+), "
                     r"saturated (\d+), faulty (\d+), gaps (\d+), joint msgs bad (\d+), "
                     r"stale (\d+),", re.M)
LATE = re.compile(r"^loadidd: samples late (\d+) \(handled more than 1 ms after arrival\), "
                  r"worst lateness (\d+) us$", re.M)


def write_config(work: pathlib.Path, realtime: bool) -> pathlib.Path:
    """Loopback LCM, the on-line methods and REFINED (on the worker), results
    saved in work/results; realtime: SCHED_FIFO 50 and mlockall."""
    cfg = work / "soak.yaml"
    text = ("lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\n"
            "estimation:\n  methods: [RTLS, RIV, RLS, REFINED]\n"
            f"results:\n  directory: {work / 'results'}\n")
    if realtime:
        text += "realtime:\n  priority: 50\n  lock_memory: true\n"
    cfg.write_text(text)
    return cfg


def run_soak(loadidd, rec, pydir, seconds, work: pathlib.Path, realtime: bool, timeout=None):
    """soak_session.py in `unshare -n` (needs root); its JSON, with the
    configuration's path and the daemon's log text added."""
    cfg = write_config(work, realtime)
    limit = timeout or float(seconds) * 1.5 + 120
    r = subprocess.run(["unshare", "-n", sys.executable, str(HERE / "soak_session.py"),
                        str(loadidd), str(cfg), str(rec), str(pydir), str(seconds), str(work)],
                       capture_output=True, text=True, timeout=limit)
    if r.returncode != 0:
        raise RuntimeError(f"soak_session.py failed ({r.returncode}): {r.stderr[-3000:]}")
    out = json.loads(r.stdout)
    out["config"] = str(cfg)
    out["log_text"] = pathlib.Path(out["log"]).read_text()
    return out


def offline_reference(loadidd, rec, work: pathlib.Path):
    """--offline's final estimate of the recording (one pass), per method
    name, with the soak's methods (no results directory, no real time)."""
    cfg = work / "offline.yaml"
    cfg.write_text("estimation:\n  methods: [RTLS, RIV, RLS, REFINED]\n")
    r = subprocess.run([str(loadidd), "--config", str(cfg), "--offline", str(rec)],
                       capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        raise RuntimeError(f"loadidd --offline: {r.stderr}")
    return {o["method"]: o for o in json.loads(r.stdout)}


def read_truth_load(rec):
    """truth.yaml's load mass [kg] and COM [m] (flat lines under `load:`)."""
    text = pathlib.Path(rec, "truth.yaml").read_text()
    block = text.split("\nload:\n", 1)[1]
    mass = float(re.search(r"^  mass: (\S+)", block, re.M).group(1))
    com = [float(x) for x in re.search(r"^  com: \[([^\]]*)\]", block, re.M).group(1).split(",")]
    return mass, com


def summarize(out, rec, offline=None):
    """The soak's figures: sessions and their estimates, memory after
    warm-up, loop times, deadlines, the daemon's counters."""
    mass_true, com_true = read_truth_load(rec)
    passes = out["passes"]
    sessions = []
    for k in range(passes):
        name = f"soak{k}"
        fin = out["final"].get(name, {})
        est = {METHODS[int(m)]: e for m, e in fin.items()}
        w = out["wrench"]["by_pass"].get(str(k))
        s = {"pass": k, "t": k * out["pass_us"] / 1e6, "methods": sorted(est),
             "samples": sorted({e["samples"] for e in est.values()}),
             "model": name in out["models"],
             "saved": sum(n.startswith(name + "-") for n in out["saved"]),
             "wrench_n": w[0] if w else 0,
             "wrench_f_rms": math.sqrt(w[1] / w[0]) if w and w[0] else float("nan"),
             "wrench_t_rms": math.sqrt(w[2] / w[0]) if w and w[0] else float("nan")}
        for m, e in est.items():
            s[m] = {"mass": e["mass"], "mass_err": e["mass"] / mass_true - 1,
                    "com_err_mm": 1e3 * math.dist(e["com"], com_true), "phi": e["phi"]}
            if offline and m in offline:
                ref = offline[m]["phi"]
                s[m]["offline_rel"] = max(abs(a - b) for a, b in zip(e["phi"], ref)) / \
                    max(abs(x) for x in ref)
        s["complete"] = (set(s["methods"]) == set(METHODS.values()) and s["samples"] == [1500]
                         and s["model"] and s["saved"] == 1)
        sessions.append(s)

    mem = out["memory_kb"]
    warm = next((m for m in mem if m["sessions"] >= WARMUP_SESSIONS), None)
    after = [m for m in mem if warm and m["t"] >= warm["t"]]
    memory = {"samples": len(mem), "warm": warm, "end": mem[-1] if mem else None,
              "peak_hwm_kb": max((m.get("VmHWM", 0) for m in mem), default=0)}
    if warm:
        for key in ("VmRSS", "RssAnon", "RssFile"):
            memory[key + "_growth_kb"] = after[-1][key] - warm[key]
            memory[key + "_max_above_kb"] = max(m[key] for m in after) - warm[key]
            memory[key + "_min_below_kb"] = warm[key] - min(m[key] for m in after)

    f = out["status_fields"]
    status = [dict(zip(f, s)) for s in out["status"]]
    timed = [s for s in status if s["loop_us_max"] > 0]
    loop = {"reports": len(timed),
            "p50_median_us": statistics.median(s["loop_us_p50"] for s in timed) if timed else 0,
            "p99_worst_us": max((s["loop_us_p99"] for s in timed), default=0),
            "max_worst_us": max((s["loop_us_max"] for s in timed), default=0)}

    log = out["log_text"]
    m = SUMMARY.search(log)
    counters = dict(zip(("samples_ok", "used", "frames_bad", "incomplete", "saturated", "faulty",
                         "gaps", "joint_msgs_bad", "stale"), map(int, m.groups()))) if m else None
    m = LATE.search(log)
    late = {"count": int(m.group(1)), "worst_us": int(m.group(2))} if m else None
    return {"passes": passes, "pass_s": out["pass_us"] / 1e6, "sessions": sessions,
            "completed": sum(s["complete"] for s in sessions), "memory": memory,
            "memory_series": mem, "loop": loop, "late": late, "machine": out.get("machine"),
            "publisher": out.get("publisher"),
            "counters": counters, "returncode": out["returncode"],
            "wrench_nonfinite": out["wrench"]["nonfinite"], "wrench_n": out["wrench"]["n"]}


def _every(items, rows):
    """At most about `rows` of items, evenly, with the first and the last."""
    if len(items) <= rows:
        return items
    step = math.ceil(len(items) / rows)
    picked = items[::step]
    return picked if picked[-1] is items[-1] else picked + [items[-1]]


def report(s, rows=30):
    """The figures as text lines."""
    L = []
    mem = s["memory"]
    L.append(f"memory over time (/proc/PID/status; warm-up: the first {WARMUP_SESSIONS} "
             f"sessions, to t = {mem['warm']['t']:.1f} s)" if mem["warm"] else
             "memory over time (warm-up never ended: fewer than 2 sessions)")
    L.append(f"  {'t [s]':>8} {'sessions':>8} {'VmRSS kB':>9} {'RssAnon':>8} {'RssFile':>8} "
             f"{'VmLck kB':>9} {'late':>6} {'worst us':>8} {'clock ms':>8}")
    for m in _every(s["memory_series"], rows):
        L.append(f"  {m['t']:>8.1f} {m['sessions']:>8} {m['VmRSS']:>9} {m['RssAnon']:>8} "
                 f"{m['RssFile']:>8} {m.get('VmLck', 0):>9} {m['late']:>6} "
                 f"{m['late_worst_us']:>8.0f} {m['clock_ms']:>8.1f}")
    steps = [m for m in s["memory_series"] if abs(m["clock_ms"]) > 50]
    if steps:
        L.append(f"  the wall clock stepped {steps[0]['clock_ms']:+.0f} ms against the monotonic "
                 f"one by t = {steps[0]['t']:.0f} s (a VM snapshot restored?): --can-file keeps "
                 f"the wall time of its start, so the sessions after it find no joint states "
                 f"near their samples")
    if mem["warm"]:
        L.append(f"  VmRSS after warm-up {mem['warm']['VmRSS']} kB, at the end "
                 f"{mem['end']['VmRSS']} kB: growth {mem['VmRSS_growth_kb']:+d} kB (target 0; "
                 f"at most {mem['VmRSS_max_above_kb']:+d} kB above, "
                 f"{-mem['VmRSS_min_below_kb']:+d} below on the way); RssAnon "
                 f"{mem['RssAnon_growth_kb']:+d} kB, RssFile {mem['RssFile_growth_kb']:+d} kB; "
                 f"peak VmHWM {mem['peak_hwm_kb']} kB")
    ses = s["sessions"]
    L.append(f"sessions: {s['completed']} of {s['passes']} completed (4 methods' final estimates "
             f"of 1500 samples, the load model, the saved result)")
    missing = [x["pass"] for x in ses if not x["complete"]]
    if missing:
        L.append(f"  not completed: passes {missing} (the daemon's log says why)")
    off = {x["pass"]: max((x[m].get("offline_rel", -1) for m in METHODS.values() if m in x),
                          default=-1) for x in ses}
    apart = [k for k, v in off.items() if v > 1e-9]
    if apart:
        L.append(f"  {len(apart)} sessions differ from --offline's estimate by more than 1e-9 "
                 f"(passes {apart[:20]}{' ...' if len(apart) > 20 else ''}); the daemon's "
                 f"counters below say what it refused")
    L.append(f"  {'pass':>5} {'t [s]':>7} {'RTLS mass':>10} {'err %':>7} {'COM mm':>7} "
             f"{'REFINED':>9} {'err %':>7} {'COM mm':>7} {'vs offline':>10} {'wrench':>6} "
             f"{'|F| rms N':>9}")
    odd = set(missing + apart[:10])  # shown besides the even sample of rows
    for x in sorted(_every(ses, rows) + [x for x in ses if x["pass"] in odd],
                    key=lambda x: x["pass"]):
        r, f = x.get("RTLS"), x.get("REFINED")
        L.append(f"  {x['pass']:>5} {x['t']:>7.1f} "
                 + (f"{r['mass']:>10.5f} {100 * r['mass_err']:>+7.3f} {r['com_err_mm']:>7.2f} "
                    if r else f"{'-':>10} {'-':>7} {'-':>7} ")
                 + (f"{f['mass']:>9.5f} {100 * f['mass_err']:>+7.3f} {f['com_err_mm']:>7.2f} "
                    if f else f"{'-':>9} {'-':>7} {'-':>7} ")
                 + (f"{off[x['pass']]:>10.1e}" if off[x["pass"]] >= 0 else f"{'-':>10}")
                 + f" {x['wrench_n']:>6} {x['wrench_f_rms']:>9.3f}")
    for m in ("RTLS", "REFINED", "RIV", "RLS"):
        errs = [x[m]["mass_err"] for x in ses if m in x]
        coms = [x[m]["com_err_mm"] for x in ses if m in x]
        offs = [x[m]["offline_rel"] for x in ses if m in x and "offline_rel" in x]
        if errs:
            L.append(f"  {m:>7}: mass error {100 * min(errs):+.3f} to {100 * max(errs):+.3f} %, "
                     f"COM error up to {max(coms):.2f} mm"
                     + (f", phi vs --offline's up to {max(offs):.1e} (relative)" if offs else ""))
    lp = s["loop"]
    L.append(f"loop time per event (status_t, {lp['reports']} reports): p50 median "
             f"{lp['p50_median_us']:.1f} us, worst p99 {lp['p99_worst_us']:.1f} us, worst max "
             f"{lp['max_worst_us']:.1f} us")
    late = s["late"]
    L.append(f"deadlines: {late['count']} samples handled more than 1 ms after arrival, worst "
             f"lateness {late['worst_us']} us" if late else
             "deadlines: no figure (the daemon's summary lacks it)")
    pub = s["publisher"]
    if pub:
        L.append(f"the publisher of the joint states: at worst {pub['worst_late_ms']:.1f} ms late "
                 f"(pass {pub['worst_pass']})")
    mc = s["machine"]
    if mc:
        L.append(f"the machine meanwhile: a bare 1 ms timer at "
                 f"{'SCHED_FIFO ' + str(mc['priority']) if mc['priority'] else 'normal scheduling'}"
                 f" (Python) handled {mc['late']} of {mc['periods']} periods more than 1 ms late, "
                 f"worst {mc['worst_us']:.0f} us")
    c = s["counters"]
    L.append(f"daemon: exit status {s['returncode']}; " + (
        f"samples ok {c['samples_ok']}, frames bad {c['frames_bad']}, incomplete "
        f"{c['incomplete']}, gaps {c['gaps']}, joint msgs bad {c['joint_msgs_bad']}, stale "
        f"{c['stale']}" if c else "no summary") +
        f"; wrench_t {s['wrench_n']} ({s['wrench_nonfinite']} not finite)")
    return L

