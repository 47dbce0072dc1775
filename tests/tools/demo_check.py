#!/usr/bin/env python3
"""The README's main job (loadid-demo) runs and every method's estimate of
o1 is close to the truth the demo prints: mass, COM and the principal
moments of the inertia about the COM (tests/python/accuracy.py, numpy),
from the table's phi columns.

    demo_check.py LOADID_DEMO [--seed N]          check one run (ctest)
    demo_check.py LOADID_DEMO --survey N          print the errors of seeds 1..N

BOUNDS are 2.5 times the worst method's maximum over 20 seeds (--survey 20).
"""

from __future__ import annotations

import math
import pathlib
import subprocess
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python"))
from accuracy import load_errors  # noqa: E402

PARAMS = ["m", "m*cx", "m*cy", "m*cz", "Ixx", "Ixy", "Ixz", "Iyy", "Iyz", "Izz"]
# --survey 20 (each seed its own optimised trajectory): max mass 0.23 %, COM
# 0.67 mm, principal moments (ascending) 40, 8.9 and 5.1 % (RIV's and RTLS's
# worst). The smallest moment (0.6e-3 kg m^2 of o1) is the least determined:
# seed 2's trajectory leaves Ixx and Ixz 16 % off for every method.
BOUNDS = dict(mass_pct=0.6, com_mm=1.7, moments_pct=(100.0, 22.0, 13.0))


def table(out: str):
    """{method: phi} and the truth, from the demo's parameter table."""
    lines = out.splitlines()
    head = next((k for k, l in enumerate(lines) if l.split()[:2] == ["param", "truth"]), None)
    if head is None:
        raise ValueError("no parameter table in the demo's output")
    cols = lines[head].split()
    methods = [c for c in cols[2:] if c != "e[%]"]
    rows = {}
    for l in lines[head + 1:head + 11]:
        f = l.split()
        rows[f[0]] = [float(x) for x in f[1:]]
    if list(rows) != PARAMS:
        raise ValueError(f"the table's rows are {list(rows)}")
    truth = np.array([rows[p][0] for p in PARAMS])
    est = {m: np.array([rows[p][1 + 2 * k] for p in PARAMS]) for k, m in enumerate(methods)}
    return est, truth


def run(demo: str, seed: int):
    r = subprocess.run([demo, "--seed", str(seed)], capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        raise RuntimeError(f"loadid-demo --seed {seed} exited {r.returncode}: {r.stderr}")
    return r.stdout


def main() -> int:
    if len(sys.argv) < 2:
        print(__doc__)
        return 2
    demo, args = sys.argv[1], sys.argv[2:]
    if args[:1] == ["--survey"]:
        worst = {}
        for seed in range(1, int(args[1]) + 1):
            est, truth = table(run(demo, seed))
            for m, phi in est.items():
                e = load_errors(phi, truth)
                w = worst.setdefault(m, np.zeros(5))
                w[:] = np.maximum(w, [e["mass_pct"], e["com_mm"], *e["moments_pct"]])
        for m, w in worst.items():
            print(f"{m:<10} max mass {w[0]:.3f} %, COM {w[1]:.3f} mm, principal moments "
                  f"(ascending) {w[2]:.1f} {w[3]:.1f} {w[4]:.1f} %")
        return 0
    seed = int(args[1]) if args[:1] == ["--seed"] else 3
    out = run(demo, seed)
    print(out)
    est, truth = table(out)
    bad = []
    for m, phi in est.items():
        e = load_errors(phi, truth)
        print(f"{m}: mass {e['mass_pct']:.3f} %, COM {e['com_mm']:.3f} mm, principal moments "
              f"{np.round(e['moments_pct'], 2)} %")
        figures = (e["mass_pct"], e["com_mm"], *e["moments_pct"])
        if not all(math.isfinite(x) for x in figures) or e["mass_pct"] > BOUNDS["mass_pct"] or \
                e["com_mm"] > BOUNDS["com_mm"] or \
                any(x > b for x, b in zip(e["moments_pct"], BOUNDS["moments_pct"])):
            bad.append(m)
    if bad:
        print(f"too far from o1 (bounds {BOUNDS}): {', '.join(bad)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
