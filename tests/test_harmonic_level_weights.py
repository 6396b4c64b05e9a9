"""The drift test's per-harmonic weights ``noise_var / level`` are unbiased on few periods (session 46).

``data.harmonic_levels`` estimates each harmonic's noise level from the periods' spread about a quadratic
trend, pooled over a band of harmonics: on four one-period blocks that is 1 degree of freedom a period and
6 at the fundamental. The drift test weighs by the level's inverse, whose mean is ``nu / (nu - 2)`` times
the true inverse (1.5 at 6 dof): before session 46 the weights were that much too large and the drift-space
se too small (the Ds design of review 44). The noise here is an AR(1) of phi 0.3 (its spectrum flat within
0.3 % over the first harmonics of 256 samples a period), drawn by wiener_sim.ar1, not by the library.
"""

from __future__ import annotations

import numpy as np
from bouc_wen_id.diagnosis.data import harmonic_levels
from wiener_sim import ar1

PHI, PERIODS, SAMPLES = 0.3, 4, 256


def _true_level(j: int) -> float:
    """The AR(1)'s level at harmonic j, in per-sample units of its unit-variance innovation law."""
    return float((1.0 - PHI**2) / abs(1.0 - PHI * np.exp(-2j * np.pi * j / SAMPLES)) ** 2)


def test_inverse_levels_are_unbiased_on_four_periods() -> None:
    rng = np.random.default_rng([46, 1])
    ratios = []
    for _ in range(400):
        rows = ar1(rng, PERIODS * SAMPLES, 1.0, PHI).reshape(PERIODS, SAMPLES)
        lv = harmonic_levels(rows, 1.0)
        ratios.append([_true_level(j) / lv[j] for j in (1, 2, 3)])
    mean = np.mean(ratios, axis=0)
    # 400 draws: the mean of nu / chi2_nu (nu 6 to 10) has an se under 0.05; main's were 1.5, 1.33, 1.25.
    assert np.all(np.abs(mean - 1.0) < 0.12), mean
