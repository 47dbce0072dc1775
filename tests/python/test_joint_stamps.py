"""loadidd --offline with the joint stamps off the wrench's clock: late by
a fixed delay (REFINED fits it), stamped on arrival after a transport's
delay, held and delivered in bursts, jittered; the wrench lagging the
joints behind the sensor's low-pass filter; and the delay's fit on slow
motion, where it is told weakly (docs/INTERFACE.md, `refined`).
"""

from __future__ import annotations

import math
import re
import shutil
import subprocess

import numpy as np
import pytest

from offline_run import (assert_close_to_truth, lcm_events, offline, real_data_like, truth_phi,
                         write_config, SLOW, UR5)
from recordings import program, simulate


def test_refined_does_not_take_the_drift_for_a_joint_delay(tmp_path):
    """RX60, seed 8 of the real-data-like case (no delay simulated; the
    offset drifts): REFINED's bandwidth and delay fits left the drift out
    and took it for a joint delay (16.5 ms at 6 standard errors here; a
    UR5 draw 7.2 ms, another RX60 draw with zeroing 23 ms, mass 4.7 % off).
    With the drift's columns in those fits the delay is the one fitted on
    the same draw without the drift: seen 4.79 and 4.41 ms, std 4.67 ms
    both (fitted on the narrowest smoothing; 6.13 ms at 4.58 on the one
    picked at delay 0); neither is used. Mass 2.8 % off, z 1.7."""
    (tmp_path / "drift").mkdir()
    (tmp_path / "none").mkdir()
    rec, result = real_data_like(tmp_path / "drift", "", 8)
    _, still = real_data_like(tmp_path / "none", "", 8, "[0, 0, 0, 0, 0, 0]")
    refined, fit, fit_still = result[3], result[3]["refined"], still[3]["refined"]
    assert refined["method"] == "REFINED"
    print("delay", fit["joint_delay_s"], "std", fit["joint_delay_std_s"], fit["joint_delay_used"],
          "without the drift", fit_still["joint_delay_s"], fit_still["joint_delay_std_s"])
    assert abs(fit["joint_delay_s"] - fit_still["joint_delay_s"]) < 0.5 * min(
        fit["joint_delay_std_s"], fit_still["joint_delay_std_s"]), (fit, fit_still)
    phi, _ = truth_phi(rec)
    m_t = phi[0]
    assert abs(refined["mass"] - m_t) / m_t < 0.05, refined["mass"]
    assert abs(refined["mass"] - m_t) <= 3 * refined["phi_std"][0], (refined["mass"],
                                                                      refined["phi_std"])


def test_joint_stamps_late_by_5_ms_are_fitted_by_refined(recording, tmp_path, lcmtypes):
    """Every joint state stamped 5 ms late (a transport or clock offset):
    the on-line methods carry it as misfit (RLS's moments about the COM
    outside the default bounds), REFINED fits the delay (5.35 ms: the
    misfit's phase adds a few tenths), uses it and
    finds the load within the bounds, and the warning's kalman.joint_delay_s
    brings the on-line methods within them too. On the recording as it is
    the fitted delay stays under 1 ms and is not used."""
    rec = restamp_joints(recording, tmp_path / "late-joints", lcmtypes, lambda u: u + 5000)
    phi, _ = truth_phi(recording)
    cfg = write_config(tmp_path / "c.yaml", "estimation:\n  methods: [RLS, REFINED]\n")
    (rls, refined), err = offline(cfg, rec, "--verbose")
    delay = refined["refined"]["joint_delay_s"]
    delay_std = refined["refined"]["joint_delay_std_s"]
    assert abs(delay - 0.005) < 0.001 and refined["refined"]["joint_delay_used"] is True, delay
    # Its standard error (0.31 ms): far below the delay, so it is used,
    # and the fit within 3 of the delay made.
    assert 1e-5 < delay_std < 0.8e-3 and abs(delay - 0.005) < 3 * delay_std + 1e-4, delay_std
    assert_close_to_truth(refined, phi)
    with pytest.raises(AssertionError):
        assert_close_to_truth(rls, phi)
    m = re.search(r"warning: joints: their stamps are ([-0-9.]+) ms behind the wrench's \(REFINED's "
                  r"fit, std ([0-9.]+) ms, which used it\); the on-line methods carry that as misfit: "
                  r"kalman.joint_delay_s: ([-0-9.]+) \(with what is set now\) corrects them", err)
    assert m and abs(float(m.group(1)) - delay * 1e3) < 0.01, err
    assert abs(float(m.group(2)) - delay_std * 1e3) < 0.01, err
    fixed = write_config(tmp_path / "d.yaml", "estimation:\n  methods: [RLS, REFINED]\n"
                         f"kalman:\n  joint_delay_s: {m.group(3)}\n")
    (rls, refined), err = offline(fixed, rec, "--verbose")
    assert_close_to_truth(rls, phi)
    assert_close_to_truth(refined, phi)
    assert "warning: joints: their stamps" not in err
    (_, clean), _ = offline(cfg, recording)
    assert abs(clean["refined"]["joint_delay_s"]) < 0.001
    assert clean["refined"]["joint_delay_used"] is False


def test_wrench_low_pass_filtered_at_31_hz_is_fitted_as_a_joint_delay(recording, tmp_path):
    """The F/T sensor's own low-pass filter set to 31 Hz (a JR3 filter
    setting; here first order, the simulated force and moment filtered
    with their noise, the accelerometer not): below its corner the filter
    is a delay of (1 - a) / a samples (4.65 ms, computed here), so the
    joints lead the wrench. REFINED fits that as a negative joint delay
    (seen -4.60 ms, std 0.09), uses it and finds the load; the on-line
    methods carry it as misfit (RLS's mass 1.4 % off) until the warning's
    kalman.joint_delay_s is set, which brings them within the bounds."""
    fc, period = 31.0, 1e-3
    a = 1 - math.exp(-2 * math.pi * fc * period)
    lead_s = (1 - a) / a * period
    values = np.genfromtxt(recording / "values.csv", delimiter=",", names=True)
    wrench = ["fx", "fy", "fz", "tx", "ty", "tz"]
    y = np.array([values[k][0] for k in wrench])
    lines = []
    for row in values:
        y = y + a * (np.array([row[k] for k in wrench]) - y)
        rest = [row[k] for k in ("ax", "ay", "az", "alx", "aly", "alz")]
        lines.append(f"S {row['t_us']:.0f} {row['sequence']:.0f} 0 "
                     + " ".join(repr(float(v)) for v in [*y, *rest]))
    frames = subprocess.run([program("LOADID_JR3_ENCODE_LOG")], input="\n".join(lines) + "\n",
                            capture_output=True, text=True, check=True).stdout.splitlines()
    rec = tmp_path / "filtered"
    rec.mkdir()
    for name in ("lcm.log", "truth.yaml"):
        shutil.copy(recording / name, rec / name)
    # The recording's lines with the filtered frames' data: its time
    # stamps and its full-scale (base+4) frames as they are.
    encoded = iter(f.split(" ")[2] for f in frames)
    out = []
    for line in (recording / "can.log").read_text().splitlines():
        stamp, iface, frame = line.split(" ")
        if not frame.startswith("1A4#"):
            new = next(encoded)
            assert new[:4] == frame[:4], (new, frame)
            frame = new
        out.append(f"{stamp} {iface} {frame}")
    assert next(encoded, None) is None
    (rec / "can.log").write_text("\n".join(out) + "\n")

    phi, _ = truth_phi(recording)
    cfg = write_config(tmp_path / "c.yaml", "estimation:\n  methods: [RLS, REFINED]\n")
    (rls, refined), err = offline(cfg, rec)
    delay = refined["refined"]["joint_delay_s"]
    assert abs(delay + lead_s) < 0.5e-3 and refined["refined"]["joint_delay_used"] is True, delay
    assert_close_to_truth(refined, phi)
    with pytest.raises(AssertionError):
        assert_close_to_truth(rls, phi)
    m = re.search(r"kalman.joint_delay_s: ([-0-9.]+) \(with what is set now\) corrects them", err)
    assert m and float(m.group(1)) < 0, err
    fixed = write_config(tmp_path / "d.yaml", "estimation:\n  methods: [RLS]\n"
                         f"kalman:\n  joint_delay_s: {m.group(1)}\n")
    (rls,), _ = offline(fixed, rec)
    assert_close_to_truth(rls, phi)


def restamp_joints(recording, dest, lcmtypes, utime_of):
    """The recording with every joint state's utime u made utime_of(u), in
    order; everything else as it is."""
    import struct
    dest.mkdir()
    for name in ("can.log", "truth.yaml"):
        shutil.copy(recording / name, dest / name)
    b = (recording / "lcm.log").read_bytes()
    with open(dest / "lcm.log", "wb") as f:
        for off, t, ch, d, n in lcm_events(recording / "lcm.log"):
            data = b[d:d + n]
            if ch == "LOADID_JOINTS":
                m = lcmtypes.joint_state_t.decode(data)
                m.utime = utime_of(m.utime)
                data = m.encode()
            number = struct.unpack(">q", b[off + 4:off + 12])[0]
            f.write(struct.pack(">IqqII", 0xEDA1DA01, number, t, len(ch), len(data)) + ch.encode()
                    + data)
    return dest


def stamped_on_arrival(recording, dest, lcmtypes, mean_us, seed=1):
    """The recording with every joint state's utime moved later by an
    exponential transport delay of mean mean_us (kept increasing): a
    stream stamped on arrival, not at sampling."""
    rng = np.random.default_rng(seed)
    last = [-1]

    def arrival(u):
        last[0] = max(u + int(rng.exponential(mean_us)), last[0] + 1)
        return last[0]
    return restamp_joints(recording, dest, lcmtypes, arrival)


def stalled_in_bursts(recording, dest, lcmtypes, stall_us, every_us):
    """The recording with the joint states of every stall_us in every_us
    held until its end and then stamped at once (1 us apart): a transport
    that stalls and then delivers what it held."""
    last = [-1]

    def arrival(u):
        phase = u % every_us
        held = every_us // 2 <= phase < every_us // 2 + stall_us
        last[0] = max(u - phase + every_us // 2 + stall_us if held else u, last[0] + 1)
        return last[0]
    return restamp_joints(recording, dest, lcmtypes, arrival)


def bunched_start(recording, dest, lcmtypes, count):
    """The recording with its first count joint states held until the
    count-th and then stamped at once (1 us apart): a stream that starts
    with a burst."""
    seen = []

    def arrival(u):
        seen.append(u)
        return u if len(seen) > count else u + (count - len(seen)) * 999
    return restamp_joints(recording, dest, lcmtypes, arrival)


def test_joint_stamps_delayed_in_transport(recording, tmp_path, lcmtypes):
    """Joint states stamped on arrival (joint_state_t.utime should be the
    sample time). After an exponential transport delay of 80 or 300 us
    mean at 1 kHz, or held 5 ms in every 50 and then delivered at once, the
    stamp clock counts each late stamp by the stamps after it and never
    restarts (nor after a start in a burst: the period probe dates it
    back), and RTLS, RIV and REFINED find the load within the bounds and
    claim it (counted from each stamp alone, a stamp 0.75-1.25 periods late
    passed for a lost message: 300 us restarted the clock 19 times in the
    window, REFINED was 2.9 % off in mass and the others 82 %, nothing
    claimed). Uniform jitter of 650 or 950 us (kept in order), over half a
    period: the clock takes every stamp one period on (at 950 us it
    restarts once, before START), and every method finds and claims the
    load within the bounds and 3 phi_std (the line that left the outliers
    out while it acquired restarted at 650 us and voided every claim). A
    clock stepped 3.3 ms forward in the window (the host's time set) fits
    no count: it restarts, the log warns, and no method claims anything."""
    phi, _ = truth_phi(recording)
    cfg = write_config(tmp_path / "c.yaml", "estimation:\n  methods: [RTLS, RIV, REFINED]\n")
    for name, rec in (("80 us", stamped_on_arrival(recording, tmp_path / "d80", lcmtypes, 80)),
                      ("300 us", stamped_on_arrival(recording, tmp_path / "d300", lcmtypes, 300)),
                      ("stalls", stalled_in_bursts(recording, tmp_path / "b", lcmtypes, 5000,
                                                   50000)),
                      ("burst", bunched_start(recording, tmp_path / "s", lcmtypes, 6))):
        result, err = offline(cfg, rec, "--verbose")
        assert "joint stamp restarts 0" in err and "joint msgs bad 0," in err, (name, err)
        assert "stamps lost" not in err, name
        for est in result:
            assert_close_to_truth(est, phi)
            assert est["identified"] == ["mass", "com", "inertia"], (name, est["method"])
    for jitter in (650, 950):
        rng = np.random.default_rng(3)
        last = [-1]

        def jittered(u):
            last[0] = max(u + int(rng.integers(-jitter, jitter + 1)), last[0] + 1)
            return last[0]
        result, err = offline(cfg, restamp_joints(recording, tmp_path / f"j{jitter}", lcmtypes,
                                                  jittered), "--verbose")
        assert "stamps lost" not in err, (jitter, err)
        assert jitter > 650 or "joint stamp restarts 0" in err, err  # at 950 one, before START
        for est in result:
            assert_close_to_truth(est, phi)
            assert est["identified"] == ["mass", "com", "inertia"], (jitter, est["method"])
            assert abs(est["mass"] - phi[0]) <= 3 * est["phi_std"][0], (jitter, est["method"])
    first = []

    def stepped(u):
        first.append(u)
        return u + 3300 if u - first[0] >= 1700000 else u  # START at 1 s, DONE at 2.5 s
    result, err = offline(cfg, restamp_joints(recording, tmp_path / "step", lcmtypes, stepped),
                          "--verbose")
    said = re.search(r"warning: joints: their stamps lost the stream's rate (\d+) times in the "
                     r"window .* no method claims anything", err)
    assert said and int(said.group(1)) >= 1, err
    for est in result:
        assert est["identified"] == [], (est["method"], est["identified"])
        assert est["not_identified"]["mass"].startswith(
            f"the joint stamps lost the stream's rate {said.group(1)} times"), est


@pytest.mark.parametrize("jitter_us,seed", [(450, 2), (550, 2), (550, 3)])
def test_stamp_jitter_near_and_over_half_a_period(trajectory, tmp_path, jitter_us, seed):
    """Both streams' stamps jittered by up to 450 or 550 us at 1 kHz
    (uniform, kept in order by loadid-sim). At 450 us the stamp clock's line
    had taken each outlier off itself while it had under 8 stamps, so
    three in a row restarted it again and again and RTLS and RLS were 3.8 %
    off in mass, claimed; counted one apart on the line there, they came
    within the bounds, but one restart before START voided the claims. Over
    half a period early stamps are outliers at random (5 % at 550 us), and
    three in a row restarted the clock again and again, the filters on raw
    jittered stamps: the on-line methods 10.7 and 15.6 % off in mass on the
    550 us draws (flagged). With the run that restarts it grown with the
    stream's outlier rate every method is within the bounds (seen 0.11 %
    at most) and claims its mass, within 3 phi_std."""
    rec = simulate(tmp_path / "rec", trajectory, "--seed", str(seed), "--config",
                   write_config(tmp_path / "sim.yaml", f"simulation:\n  jitter_us: {jitter_us}\n"))
    phi, _ = truth_phi(rec)
    cfg = write_config(tmp_path / "c.yaml", "estimation:\n  methods: [RTLS, RIV, RLS, REFINED]\n")
    result, _ = offline(cfg, rec)
    for est in result:
        print(est["method"], est["mass"] / phi[0] - 1, est["identified"])
        assert_close_to_truth(est, phi)
        assert "mass" in est["identified"], (est["method"], est["not_identified"])
        assert abs(est["mass"] - phi[0]) <= 3 * est["phi_std"][0], est["method"]


def test_joint_delay_standard_error_matches_its_error_over_seeds(trajectory, tmp_path):
    """The delay's standard error against the fit's own error over twelve
    noise draws of one trajectory, simulated without a delay (the CAN
    samples stamped at their motion's time): the misfit (servo lag,
    backlash) biases the fit alike in every draw (the seeds' spread 0.08
    ms against an RMS error of 0.10 here), and the standard error, from
    the scores of stretches of the window and never below white rows',
    must see it too. Measured: 1.56 times the RMS error; a wrong Jacobian
    or a lost scale would be far off. None is used (under 1 ms)."""
    cfg = write_config(tmp_path / "c.yaml", "estimation:\n  methods: [REFINED]\n")
    delays, stds = [], []
    for seed in range(1, 13):
        rec = simulate(tmp_path / f"s{seed}", trajectory, "--seed", str(seed))
        (refined,), _ = offline(cfg, rec)
        delays.append(refined["refined"]["joint_delay_s"])
        stds.append(refined["refined"]["joint_delay_std_s"])
        assert refined["refined"]["joint_delay_used"] is False, refined["refined"]
    error, said = np.sqrt(np.mean(np.square(delays))), np.sqrt(np.mean(np.square(stds)))
    assert 0.5 * error < said < 3 * error, (delays, stds)
    assert all(abs(d) < 3 * s for d, s in zip(delays, stds)), (delays, stds)


def slow_ur5_draws(tmp_path, seeds=range(100, 140)):
    """The UR5's slow trajectory of the real-data-like case's seed 7 and a
    REFINED configuration for it (offset estimated): yields (config,
    recording) for each noise draw of seeds, the recording removed after."""
    ur5 = f"robot:\n  urdf: {UR5}\n"
    first = tmp_path / "seed7"
    first.mkdir()
    real_data_like(first, ur5, 7)
    cfg = write_config(tmp_path / "c.yaml", ur5 + SLOW + "estimation:\n  offset_model: estimate\n"
                       "  methods: [REFINED]\n")
    for seed in seeds:
        rec = simulate(tmp_path / f"s{seed}", first / "traj", "--config", first / "sim.yaml",
                       "--seed", str(seed))
        yield cfg, rec
        shutil.rmtree(rec)


def test_slow_motion_joint_delay_standard_error_matches_its_error_over_seeds(tmp_path):
    """The UR5's slow trajectory of the real-data-like case's seed 7 (1.5 s
    of |omega| 0.37 rad/s RMS), forty noise draws, no delay simulated. The
    delay is weakly told there (std 2-7 ms), and the ten stretches' scores,
    which the offset's and the drift's columns tie together, said about
    half of the fit's spread: on seed 7 itself a 13.9 ms delay at 5.3
    standard errors was used (mass 3.6 % off). The standard error is now
    never below white rows' at the residual's scale. Measured over these
    draws: RMS of delay / std 1.31, none used (1.49 with c differenced
    over one sample; the scores alone: three used and failed here; white
    force noise alone gave 1.28)."""
    z, used = [], 0
    for cfg, rec in slow_ur5_draws(tmp_path):
        (refined,), _ = offline(cfg, rec)
        fit = refined["refined"]
        z.append(fit["joint_delay_s"] / fit["joint_delay_std_s"])
        used += fit["joint_delay_used"]
    print("delay / std", np.round(z, 2).tolist())
    assert np.sqrt(np.mean(np.square(z))) < 1.7 and used <= 2, (z, used)


def late_slow_draws(tmp_path, lcmtypes, delay_s, seeds):
    """REFINED on slow_ur5_draws' draws of seeds with every joint state
    stamped delay_s late: the draws that used the delay, the delay's
    error / its standard error and REFINED's |mass error| / phi_std per
    draw (both printed)."""
    z, zd, used = [], [], 0
    for cfg, rec in slow_ur5_draws(tmp_path, seeds):
        phi, _ = truth_phi(rec)
        late = restamp_joints(rec, tmp_path / "late", lcmtypes,
                              lambda u: u + round(delay_s * 1e6))
        (refined,), _ = offline(cfg, late)
        fit = refined["refined"]
        used += fit["joint_delay_used"]
        zd.append((fit["joint_delay_s"] - delay_s) / fit["joint_delay_std_s"])
        z.append(abs(refined["mass"] - phi[0]) / refined["phi_std"][0])
        shutil.rmtree(late)
    print("used", used, "delay error / std", np.round(zd, 2).tolist())
    print("mass |error| / phi_std", np.round(z, 2).tolist())
    return used, np.array(zd), np.array(z)


def test_slow_motion_joint_delay_left_out_widens_phi_std(tmp_path, lcmtypes):
    """The same slow trajectory, forty noise draws, every joint state
    stamped 10 ms late. The delay is weakly told there (std 3-6 ms) and
    used only where it stands out: in the other draws REFINED keeps phi at
    delay 0, 2-4.5 % off in mass, and its phi_std must say so (the delay's
    error b D, D about N(d, std^2), in its variance). Measured: mass
    within 2 phi_std in 92.5 % of the draws (65 % when only a used delay
    counted), RMS of error / phi_std 1.18 (1.90); the delay used in 9. The
    delay's own fit is 1.43 of its standard error in RMS (2.89 with c
    differenced over one sample: the fits fell short where the joints were
    least smoothed)."""
    used, zd, z = late_slow_draws(tmp_path, lcmtypes, 0.010, range(100, 140))
    assert 5 <= used <= 20, used  # the case this test is about: most left out
    assert np.sqrt(np.mean(zd**2)) < 1.8, zd
    assert np.mean(z <= 2) >= 0.75 and np.sqrt(np.mean(z**2)) < 1.6, z


def test_slow_motion_joint_delay_of_20_ms_is_fitted_on_the_narrowest_smoothing(tmp_path, lcmtypes):
    """The same slow trajectory, twenty noise draws, every joint state
    stamped 20 ms late. Fitted on the smoothing picked at delay 0 (PSDs
    from 0.001 to 1 there), the delay was 1.9 of its standard error off in
    RMS, two fits ended near 0 (-2.3 and 2.9 ms) though the residual did
    not prefer them, and REFINED's mass was within 2 phi_std in 85 % of
    the draws. Fitted on the narrowest smoothing first: 1.18 in RMS, mean
    0.03, used in 18 of 20, mass within 2 phi_std in 90 %."""
    used, zd, z = late_slow_draws(tmp_path, lcmtypes, 0.020, range(100, 120))
    assert np.sqrt(np.mean(zd**2)) < 1.5 and abs(np.mean(zd)) < 0.6, zd
    assert used >= 15, used
    assert np.mean(z <= 2) >= 0.85 and np.sqrt(np.mean(z**2)) < 1.5, z
