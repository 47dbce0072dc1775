"""bench_live: the live daemon's loop while a recording is replayed in real
time (a benchmark: prints figures, exits 0 unless it cannot set up).

    bench_live.py LOADIDD LOADID_CLI RECORDING_DIR LCM_PYTHON_DIR [--realtime]

Runs one session of tests/python/live_session.py (a private network
namespace, real LCM multicast, the recording's can.log replayed by the
daemon and its joint states and commands published in real time), and
prints the per-frame loop time the daemon reports in status_t (p50, p99,
max for each second, and the worst of them) and its resident memory.
--realtime adds SCHED_FIFO 50 and mlockall. Needs root (unshare).
"""

from __future__ import annotations

import json
import pathlib
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent


def main() -> int:
    if len(sys.argv) < 5:
        print(__doc__)
        return 2
    loadidd, cli, rec, pydir = sys.argv[1:5]
    realtime = "--realtime" in sys.argv[5:]
    with tempfile.TemporaryDirectory() as d:
        cfg = pathlib.Path(d) / "c.yaml"
        text = "lcm:\n  url: udpm://239.255.76.67:7667?ttl=0\n"
        if realtime:
            text += "realtime:\n  priority: 50\n  lock_memory: true\n"
        cfg.write_text(text)
        r = subprocess.run(["unshare", "-n", sys.executable,
                            str(HERE.parent / "python" / "live_session.py"), loadidd, str(cfg),
                            rec, pydir, cli], capture_output=True, text=True, timeout=120)
    if r.returncode != 0:
        print(r.stderr, file=sys.stderr)
        return 1
    out = json.loads(r.stdout)
    status = [s for s in out["status"] if s["max"] > 0]
    print(f"bench_live: {rec}, {'SCHED_FIFO 50 + mlockall' if realtime else 'normal scheduling'}")
    print(f"  {'second':>6} {'p50 [us]':>9} {'p99 [us]':>9} {'max [us]':>9}")
    for i, s in enumerate(status):
        print(f"  {i:>6} {s['p50']:>9.1f} {s['p99']:>9.1f} {s['max']:>9.1f}")
    if status:
        print(f"  worst p99 {max(s['p99'] for s in status):.1f} us, "
              f"worst max {max(s['max'] for s in status):.1f} us (budget 1000 us per sample)")
    mem = out.get("memory_kb", {})
    print(f"  resident memory: peak {mem.get('VmHWM', 0) / 1024:.1f} MB, now "
          f"{mem.get('VmRSS', 0) / 1024:.1f} MB, locked {mem.get('VmLck', 0) / 1024:.1f} MB "
          f"(target under 20 MB)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
