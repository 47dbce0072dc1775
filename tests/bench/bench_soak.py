"""bench_soak: one live loadidd for a long time (default an hour) on a
recording replayed over and over in real time, one estimation session after
another (a benchmark: prints figures, exits 0 unless it cannot set up).

    bench_soak.py LOADIDD RECORDING_DIR LCM_PYTHON_DIR [--seconds N] [--realtime]
                  [--rows N] [--keep DIR]

tests/python/soak_session.py runs it in a private network namespace: the
recording's JR3 frames through a FIFO into `loadidd --can-file` (its times
and sequence numbers continued pass after pass), its joint states and
commands on LCM at the same times, ZERO and START every pass. Prints the
daemon's resident memory over time and its growth after the first two
sessions (target 0), status_t's loop times (p50, worst p99 and max), the
samples handled more than 1 ms after they arrived (target 0) and the worst
lateness, and every session's estimates against the truth and against
`loadidd --offline` on one pass. --realtime: SCHED_FIFO 50 and mlockall.
--keep DIR keeps the daemon's log, results and the JSON (a new or empty
folder). Needs root (unshare).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
import tempfile
import time

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "python"))

import soak_run  # noqa: E402  (tests/python)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("loadidd")
    ap.add_argument("recording")
    ap.add_argument("lcm_python_dir")
    ap.add_argument("--seconds", type=float, default=3600, help="input to replay (default 3600)")
    ap.add_argument("--realtime", action="store_true", help="SCHED_FIFO 50 and mlockall")
    ap.add_argument("--rows", type=int, default=30, help="rows of each table (default 30)")
    ap.add_argument("--keep", type=pathlib.Path, help="keep the log, results and JSON here")
    a = ap.parse_args()
    if a.keep and a.keep.exists() and any(a.keep.iterdir()):
        print(f"bench_soak: --keep {a.keep}: not empty", file=sys.stderr)
        return 2
    with tempfile.TemporaryDirectory(prefix="loadid-soak-") as tmp:
        work = a.keep or pathlib.Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        offline = soak_run.offline_reference(a.loadidd, a.recording, work)
        t0 = time.time()
        try:
            out = soak_run.run_soak(a.loadidd, a.recording, a.lcm_python_dir, a.seconds, work,
                                    a.realtime)
        except (RuntimeError, OSError) as e:
            print(f"bench_soak: {e}", file=sys.stderr)
            return 1
        wall = time.time() - t0
        s = soak_run.summarize(out, a.recording, offline)
        if a.keep:
            (work / "soak.json").write_text(json.dumps(out))
    print(f"bench_soak: {a.recording}, {a.seconds:.0f} s asked: {s['passes']} passes of "
          f"{s['pass_s']:.3f} s, one session each, {wall:.0f} s of wall time; "
          f"{'SCHED_FIFO 50 + mlockall' if a.realtime else 'normal scheduling'}")
    for line in soak_run.report(s, a.rows):
        print(line)
    return 0


if __name__ == "__main__":
    sys.exit(main())
