"""A zero standard error in the zero-drift test is a void statistic that says why, never a crash (issue 18:
"every statistic is valid or says why not").

A recording whose periods repeat exactly (noise-free output, or quantised output with nothing to dither it)
has no period-to-period noise: every slope's standard error is 0, and the decay test divided by it
(ZeroDivisionError in ``zero_drift._recording``, from ``diagnose`` on quantised, nearly noise-free output of
the bench's first-order G). Now such a recording's test is void (``zero_drift.NOISELESS``), named in the
drift's note when the other recordings drift, and ``diagnose`` names the missing noise floor as it does for
any noise-free record (``InsufficientDataError``).
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import zero_drift

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")

TWO_PI = 2.0 * math.pi
P = 128
SD = 0.01


def _drifting(seed: int, m: int = 5, periods: int = 16, settle: int = 4) -> list[Any]:
    """``m`` recordings of a saturating loop written down directly, white noise and a straight-line drift of
    one noise sd over the record, then one whose periods repeat exactly (one period tiled, no noise)."""
    rng = np.random.default_rng([seed, 30])
    n = (settle + periods) * P
    out = []
    for i in range(m + 1):
        om = TWO_PI * (0.5 + 0.25 * i)
        t = np.arange(n) * (TWO_PI / om / P)
        u = (1.0 + 0.2 * i) * np.cos(om * t)
        if i == m:  # the repeating one: one period, tiled
            y = np.tile(np.tanh(2.0 * np.cos(om * t[:P] - 0.4)), settle + periods)
        else:
            line = float(rng.choice([-1.0, 1.0])) * SD * np.linspace(0.0, 1.0, n)
            y = np.tanh(2.0 * np.cos(om * t - 0.4)) + rng.normal(0.0, SD, n) + line
        out.append(bw.Recording(t, u, y, 1.0 + 0.2 * i, om, settle_periods=settle))
    return out


def test_a_recording_whose_periods_repeat_is_void_and_named() -> None:
    for seed in range(3):
        recs = _drifting(seed)
        d = zero_drift.detect(recs, 0.05 / 20)  # before: ZeroDivisionError
        assert d is not None, seed
        last = f"item {len(recs) - 1}"
        assert d.noiseless == (last,) and last not in d.short
        assert d.slopes[-1] == 0.0  # its line not tested
        assert f"{last}: {zero_drift.NOISELESS}" in d.note()
        assert d.dof == len(recs) - 1  # the others tested as before


def test_diagnose_on_quantised_noise_free_output_names_the_missing_noise() -> None:
    """The bench's first-order G (not the closed form the drift test was shaped on), viscous damping, its
    output quantised at the averaged noise sd with no noise to dither it."""
    p = gen.make_plant(4101, shape="first")
    b = gen.base(p)
    q = math.sqrt(12.0) * gen.NOISE_SD / math.sqrt(gen.PERIODS)
    _, _, y = gen._calibrate(p, "viscous", "u", 6.0, b)
    recs = []
    for i in range(p.omegas.size):
        n = y.shape[-1]
        t = np.arange(n) * (TWO_PI / float(p.omegas[i]) / gen.P)
        u = float(p.amplitudes[i]) * np.cos(float(p.omegas[i]) * t)
        yy = np.round(y[i] / q) * q
        recs.append(
            bw.Recording(t, u, yy, float(p.amplitudes[i]), float(p.omegas[i]), settle_periods=gen.SETTLE)
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        # Before: ZeroDivisionError, then a refusal ("no noise floor"); the docs promise the quantisation
        # floor N q^2 / 12 for a quantised output (review 31a item 8), and the notes say it applied.
        d = bw.diagnose(recs, candidates=[T.Viscous.kind, T.Offset.kind])
    assert d.verdict and any("quantisation step" in n for n in d.notes)
