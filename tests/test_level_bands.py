"""Noise levels per harmonic that follow a narrow-band colour (levels47, nuar46's fix B).

Under AR(2) noise with its peak on harmonic 2 (review 46's H plan: poles 0.95 e^{+-0.3i} a sample, 40
samples a period) ``data.harmonic_levels`` pooled every level over +-2 harmonics: the level at the peak was
about 3 times too low (the blocks' chi-square at 2.96 of its dof there), and its neighbours' 2-16 times too
high (0.12-0.38), so the degradation test's share gate read 0 under a 10x strength degradation. The noise
here comes from a few-line AR(2) recursion of its own (not sim46's lfilter), each record from its own seed.
"""

from __future__ import annotations

import math

import numpy as np
from bouc_wen_id.diagnosis import data, deg_unnamed, level_bands
from bouc_wen_id.diagnosis.drift import DEGRADATION
from bouc_wen_id.diagnosis.settling import left_out_note

P, PERIODS, RECORDS = 40, 20, 24


def ar2(n: int, seed: int, radius: float = 0.95, harmonic: float = 2.0) -> np.ndarray:
    """``n`` samples of AR(2) noise whose spectral peak sits at ``harmonic`` cycles a period of P samples."""
    a1, a2 = 2.0 * radius * math.cos(2.0 * math.pi * harmonic / P), -(radius**2)
    e = np.random.default_rng([47, seed]).standard_normal(n + 400)
    y = np.zeros_like(e)
    for i in range(2, e.size):
        y[i] = a1 * y[i - 1] + a2 * y[i - 2] + e[i]
    return y[400:] / float(np.std(y[400:]))


def block_calibration(rows_of: list[np.ndarray]) -> np.ndarray:
    """The blocks' chi-square over its dof at each harmonic, weighed by ``harmonic_levels`` (as the drift
    test weighs them: block samples over each harmonic's level), about their weighted mean."""
    chi, dof = np.zeros(0), np.zeros(0)
    for rows in rows_of:
        hv = data.harmonic_levels(rows, float(np.var(rows)))
        coef, samples, _, _ = data._recording_blocks(rows)
        mean = (samples[:, None] * coef).sum(axis=0) / samples.sum()
        dev = coef - mean
        c = 0.5 * np.abs(dev) ** 2 * samples[:, None] / hv
        c[:, 0] = dev[:, 0].real ** 2 * samples / hv[0]
        d = np.full(hv.size, 2.0 * (samples.size - 1))
        d[0] = samples.size - 1
        chi, dof = (c.sum(axis=0), d) if chi.size == 0 else (chi + c.sum(axis=0), dof + d)
    return np.asarray(chi / dof)


def test_levels_let_a_narrow_band_peak_stand() -> None:
    rows = [ar2(P * PERIODS, s).reshape(PERIODS, P) for s in range(RECORDS)]
    ratio = block_calibration(rows)
    # The peak's own level: neither smeared down (main: about 3) nor far above its blocks' spread.
    assert 0.7 < ratio[2] < 1.4, ratio
    # Its neighbours are no longer weighed by the peak's power (main: 0.38 and 0.12).
    assert ratio[3] > 0.6 and ratio[4] > 0.6, ratio


def test_a_smooth_band_stays_whole() -> None:
    rng = np.random.default_rng(470)
    single = rng.chisquare(34, 16) / 34.0
    assert level_bands.band(single, 7, 2, 1, 34.0, True) == (5, 9)
    single[7] *= 8.0  # a peak: its band shrinks to the harmonic alone, its neighbours' bands avoid it
    assert level_bands.band(single, 7, 2, 1, 34.0, True) == (7, 7)
    assert 7 not in range(*np.add(level_bands.band(single, 5, 2, 1, 34.0, True), (0, 1)))


class _Deg:
    """A degradation test that fitted the drift at p adj 1e-43 and explained none of its excess."""

    term, p_adjusted, share = DEGRADATION, 1.4e-43, 0.0
    held_out_before, held_out_after = (1168.0,), (962.0,)


def test_left_out_note_says_what_stopped_a_significant_degradation() -> None:
    why = deg_unnamed.clause(_Deg(), 0.05)
    note = left_out_note("x6_w6", ["x6_w6"], [2.6e-5], why)
    assert "no degradation explains" not in note
    assert "1.4e-43" in note and "0% of the drift's excess" in note
    # Not significant: the old words, which are then true.
    weak = _Deg()
    weak.p_adjusted = 0.3
    assert "no degradation explains it" in left_out_note(
        "x6_w6", ["x6_w6"], [2.6e-5], deg_unnamed.clause(weak, 0.05)
    )
