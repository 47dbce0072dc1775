"""REFINED's smoother bandwidth under coarse encoders (the study's
paper_enc14 cell: 2^14 counts a turn), against the study's independent
reference (tools/study/loadid_study.py: a numpy batch TLS on the encoders
smoothed by a local polynomial, Pinocchio's kinematics, the true noise
levels).

The UR5 with the hollow load at 2^14 counts a turn (the study's
paper_enc14 cell): the smoother's noise fills the residual but averages
out of phi, its blunting does not. Chosen by the whole residual, REFINED
took a tenth of the jerk PSD and its inertia about the COM came out 1.7-3.7
times the reference's error (seeds 1-4); by the residual in the motion's
band it took the PSD of 1, and 0.67-1.37 times (median 1.1); with half a
decade beside the best it takes 3.2 in three of the four, 0.67-1.16
(median 0.76)."""

from __future__ import annotations

import numpy as np

from study_cell import run_cell, st


def test_refined_bandwidth_under_coarse_encoders_matches_the_reference(tmp_path):
    """The UR5, hollow load, seeds 1-4: REFINED's inertia error over the
    reference's."""
    runs = run_cell(tmp_path, "ur5", "hollow", range(1, 5))
    ratios = [err["REFINED"]["inertia_pct"] / err["REF"]["inertia_pct"] for err, _ in runs]
    psds = [refined["refined"]["jerk_psd"] for _, refined in runs]
    print("REFINED / REF inertia", np.round(ratios, 2), "jerk PSD", psds)
    # Seen 0.67-1.16 (median 0.76); 1.7-3.7 (median 2.9) by the whole residual.
    assert np.median(ratios) < 1.3 and max(ratios) < 1.6, (ratios, psds)


def test_refined_bandwidth_between_the_decades(tmp_path):
    """The RX60, hollow load (5 kg), seeds 1-4: a decade apart, the jerk
    PSDs pull the mass opposite ways (1: +0.09 %, the motion blunted; 10:
    -0.06 %, the columns' noise), and REFINED, on the decade grid alone,
    took 1 and was 0.104 % above the reference's mass in every seed (the
    two share the noise draw: 0.001 % apart from seed to seed). Half a
    decade towards the better neighbour takes 3.2 in three of these
    seeds: 0.041 % above it there."""
    runs = run_cell(tmp_path, "rx60", "hollow", range(1, 5))
    mass = st.load_phi("hollow")[0]
    above = [(err["REFINED"]["phi0"] - err["REF"]["phi0"]) / mass * 100 for err, _ in runs]
    psds = [refined["refined"]["jerk_psd"] for _, refined in runs]
    print("REFINED's mass over REF's [%]", np.round(above, 3), "jerk PSD", psds)
    assert np.median(above) < 0.08, (above, psds)
