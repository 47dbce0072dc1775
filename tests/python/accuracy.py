"""How far an estimate is from the truth, in the figures the end-to-end
tests bound (and tests/tools/error_survey.py measures over many seeds):
mass in %, COM in mm, and each principal moment of the inertia about the
COM in % of the true one. Computed here with numpy (parallel-axis
theorem, eigenvalues), not by loadid."""

from __future__ import annotations

import math

import numpy as np


# Accuracy bounds of the end-to-end tests: 2.5 times the worst method's
# maximum over 20 simulator seeds of the same scenario, measured by
# tests/tools/error_survey.py (mass %, COM mm, worst principal moment of
# the inertia about the COM %). Rerun it when the method changes.
BOUNDS = {
    # max 0.37 %, 0.35 mm, 3.9 % (RTLS, RIV, RLS, TLS_BATCH, REFINED alike)
    "default": dict(mass_pct=0.92, com_mm=0.87, moment_pct=9.7),
    # max 0.39 %, 0.36 mm, 3.9 %
    "distal": dict(mass_pct=0.98, com_mm=0.89, moment_pct=9.6),
    # max 0.30 %, 0.26 mm, 3.4 %
    "offset": dict(mass_pct=0.74, com_mm=0.66, moment_pct=8.6),
    # JR3 accelerometers: its alpha at 5 rad/s^2 of noise; max 2.7 %, 1.2 mm, 27 %
    "signals-sensor": dict(mass_pct=6.7, com_mm=3.1, moment_pct=67.0),
    "signals-kf": dict(mass_pct=0.92, com_mm=0.87, moment_pct=9.7),  # as default
    # max 0.63 %, 0.44 mm, 4.9 %
    "signals-setpoint": dict(mass_pct=1.6, com_mm=1.1, moment_pct=12.2),
    # max 1.9 %, 1.1 mm, 12 %
    "signals-mixed": dict(mass_pct=4.7, com_mm=2.9, moment_pct=29.0),
    # saturate, fault, skip-samples 2 %: max 0.34 %, 0.36 mm, 3.9 %
    "damage": dict(mass_pct=0.85, com_mm=0.91, moment_pct=9.7),
    # drop-frames 1 %: max 0.33 %, 0.36 mm, 4.9 %
    "damage-drop-frames": dict(mass_pct=0.81, com_mm=0.89, moment_pct=12.3),
    # the vcan VM's live daemon: default, the JR3 frames VCAN_LAG_US late;
    # max 0.34 %, 0.34 mm, 3.9 % (RTLS, RIV, RLS, REFINED; with 80 us:
    # 0.33 %, 0.35 mm, 3.9 %)
    "vcan": dict(mass_pct=0.86, com_mm=0.86, moment_pct=9.9),
    # test_live_modbus.py's live session (the serial sensor polled at 500 Hz,
    # signals kf, the sensor lost and found, faults), run live per seed,
    # 80 seeds (--seeds 60, then 20): max 0.78 %, 0.55 mm, 7.7 % (RTLS, RIV,
    # RLS alike). A live session polls another half of the samples each
    # run, so it draws its noise anew: one 20-seed survey's max had been
    # 0.41 %, and the mass bound from it was crossed once (RIV 1.53 %).
    "modbus": dict(mass_pct=2.0, com_mm=1.4, moment_pct=19.2),
}

# The vcan VM (tests/vm/run_vcan_vm.sh) replays a recording in real time:
# its JR3 frames carry the kernel's receive times, later than the replay's
# schedule, which the joint states' utimes keep (test_vcan_vm.py measures
# it: about 58 us at the median, 79-82 us at the 99th percentile);
# error_survey's "vcan" scenario delays every frame by this much [us],
# twice what the VM shows, so that its p99 has room under this bound.
VCAN_LAG_US = 160


def physical(phi):
    """Mass, COM and the 3x3 inertia about the COM of phi (eq. 5 order:
    m, m c, Ixx, Ixy, Ixz, Iyy, Iyz, Izz about the sensor frame's origin)."""
    phi = np.asarray(phi, float)
    m, c = phi[0], phi[1:4] / phi[0]
    i = phi[4:]
    I = np.array([[i[0], i[1], i[2]], [i[1], i[3], i[4]], [i[2], i[4], i[5]]])
    return m, c, I - m * (c @ c * np.eye(3) - np.outer(c, c))


def load_errors(phi, truth) -> dict:
    """mass_pct, com_mm, moments_pct (3, ascending principal moments) and
    moment_pct (their worst); NaN where phi is not finite."""
    phi = np.asarray(phi, float)
    if not np.all(np.isfinite(phi)) or not phi[0] > 0:
        return dict(mass_pct=math.nan, com_mm=math.nan, moments_pct=[math.nan] * 3,
                    moment_pct=math.nan)
    m, c, ic = physical(phi)
    mt, ct, ict = physical(truth)
    lam, lam_t = np.linalg.eigvalsh(ic), np.linalg.eigvalsh(ict)
    mom = np.abs(lam - lam_t) / lam_t * 100
    return dict(mass_pct=abs(m - mt) / mt * 100, com_mm=float(np.linalg.norm(c - ct) * 1e3),
                moments_pct=mom.tolist(), moment_pct=float(mom.max()))


def assert_accuracy(est: dict, truth, mass_pct: float, com_mm: float, moment_pct: float):
    """The estimate (a result JSON entry, or a phi) is finite and within
    the bounds; the message says the figures."""
    phi = est["phi"] if isinstance(est, dict) else est
    assert phi is not None and all(x is not None for x in phi), est
    e = load_errors(phi, truth)
    what = (f"mass {e['mass_pct']:.3f} % (bound {mass_pct}), COM {e['com_mm']:.3f} mm "
            f"(bound {com_mm}), principal moments {np.round(e['moments_pct'], 2)} % "
            f"(bound {moment_pct})")
    assert all(math.isfinite(x) for x in (e["mass_pct"], e["com_mm"], e["moment_pct"])), what
    assert e["mass_pct"] <= mass_pct and e["com_mm"] <= com_mm and \
        e["moment_pct"] <= moment_pct, what
    return e
