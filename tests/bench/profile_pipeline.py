"""profile_pipeline: where bench_pipeline's time goes, stage by stage, in
microseconds per estimated sample (a tool for people: prints a table,
exits 0 unless it cannot run).

    profile_pipeline.py BENCH_PIPELINE CONFIG RECORDING_DIR [REPETITIONS]

BENCH_PIPELINE should be the debuginfo preset's (build/debuginfo/tests/
bench_pipeline: the release code with -g, so that perf sees inlined
functions). Runs it once as it is, for its medians (estimated samples per
second in memory and with --offline), then again under `perf record
--call-graph dwarf`; each perf sample goes to the first stage found
walking its call chain up from where it was taken (the table below), and
only samples of the two timed runs count (under feed_events: in memory;
under loadid_offline_run: --offline). A stage's share of a run's samples
times the run's time per estimated sample is its cost. Needs perf.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from collections import Counter

# (stage, regex on a frame's function); the first frame from the leaf up
# that matches one decides the sample's stage.
STAGES = [
    ("JR3 decoding", r"loadid_jr3_decoder_feed"),
    ("joint filter: Kalman update",
     r"loadid_jf_update|loadid_signals_push_joints|regularise|predict|correct|step_of|push_entry"),
    ("joint filter: fixed-lag smoother",
     r"loadid_jf_lagged|smoothed|add_terms|updates_after|current_entries|"
     r"loadid_signals_last_joint_time"),
    ("kinematics", r"loadid_kin_eval|apply_fixed|apply_revolute|apply_prismatic|axis_angle|sincos"),
    ("signal source", r"loadid_signals_at|kinematics_of|loadid_signals_kinematics_at"),
    ("regressor", r"loadid_regressor|data_matrix"),
    ("RTLS", r"Rtls|brand_jacobi"),
    ("RLS + RIV", r"RecursiveLs"),
    ("estimators: input checks", r"loadid_est_update"),
    ("zeroing and noise", r"loadid_noise_|finish_zeroing"),
    ("results (estimates, model, completeness)",
     r"estimate_at|publish_all|finish_estimation|check_complete|model_of|loadid_est_estimate|"
     r"choose_primary|check_row_scales"),
    ("parsing the recording",
     r"loadid_recording|loadid_candump|loadid_eventlog|loadid_lcm_decode|read_line|\bfeed\b|"
     r"_IO_|fread|fgets|__read|lseek"),
    ("pipeline (queue, commands; the bench's events)",
     r"on_sample|flush_pending|pop_pending|enqueue|cover|loadid_pipeline_|feed_one|advance|"
     r"run_command|end_stalled_piece"),
]
OTHER = "other (libc, kernel)"
COMPILED = [(name, re.compile(rx)) for name, rx in STAGES]


def medians(text: str) -> tuple[float, float]:
    mem = re.search(r"pipeline median\s+(\d+)", text)
    off = re.search(r"--offline median\s+(\d+)", text)
    if not mem or not off:
        raise SystemExit(f"profile_pipeline: no medians in bench_pipeline's output:\n{text}")
    return float(mem.group(1)), float(off.group(1))


def chains(script: str):
    """The call chains of `perf script -F comm,ip,sym`, leaf first."""
    chain: list[str] = []
    for line in script.splitlines():
        if not line.strip():
            if chain:
                yield chain
            chain = []
        elif line[0] in " \t":
            parts = line.split(None, 1)
            chain.append(parts[1] if len(parts) > 1 else "")
    if chain:
        yield chain


def main() -> int:
    if len(sys.argv) < 4 or sys.argv[1] in ("-h", "--help"):
        print(__doc__)
        return 0 if len(sys.argv) > 1 and sys.argv[1] in ("-h", "--help") else 2
    bench, config, rec = sys.argv[1:4]
    reps = sys.argv[4] if len(sys.argv) > 4 else "40"
    plain = subprocess.run([bench, config, rec, reps], capture_output=True, text=True, check=True)
    rate_mem, rate_off = medians(plain.stdout)
    with tempfile.TemporaryDirectory() as d:
        data = f"{d}/perf.data"
        subprocess.run(["perf", "record", "-q", "-F", "10000", "--call-graph", "dwarf,16384",
                        "-o", data, bench, config, rec, reps],
                       capture_output=True, text=True, check=True)
        script = subprocess.run(["perf", "script", "-i", data, "-F", "comm,ip,sym"],
                                capture_output=True, text=True, check=True).stdout
    counts = {"mem": Counter(), "off": Counter()}
    for chain in chains(script):
        if any("feed_events" in f for f in chain):
            run = "mem"
        elif any("loadid_offline_run" in f for f in chain):
            run = "off"
        else:
            continue
        stage = next((name for f in chain for name, rx in COMPILED if rx.search(f)), OTHER)
        counts[run][stage] += 1
    us = {"mem": 1e6 / rate_mem, "off": 1e6 / rate_off}
    total = {k: max(sum(c.values()), 1) for k, c in counts.items()}
    print(f"bench_pipeline: {rate_mem:.0f} estimated samples/s in memory, {rate_off:.0f} with "
          f"--offline ({reps} repetitions, without perf)")
    print(f"{'us per estimated sample':48s} {'in memory':>16s} {'--offline':>16s}")
    for name in [n for n, _ in STAGES] + [OTHER]:
        cells = "".join(f" {100 * counts[k][name] / total[k]:6.1f}% "
                        f"{us[k] * counts[k][name] / total[k]:8.2f}" for k in ("mem", "off"))
        print(f"{name:48s}{cells}")
    print(f"{'total (perf samples ' + str(total['mem']) + ', ' + str(total['off']) + ')':48s}"
          f" {100:6.1f}% {us['mem']:8.2f} {100:6.1f}% {us['off']:8.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
