"""Stiffness degradation's named value and its standard error (review 44 failure 2, session 45).

The records come from a few-line RK4 written here (the Baber-Noori element ``w' = [x' - (beta |x'| |w|^(mu-1)
w + gamma x' |w|^mu)] / (1 + delta_eta e)``, ``e' = w x'``, on ``x = U cos(omega t)`` from rest), not from
the library's simulator. Before session 45 the value was refined on a steady cost that was circular (its
minimum at the first-order d, its curvature 10 times too sharp) after two unconverged correction passes: on
this design (eta about 3 at the record's end) it came out 9 % and 7 % low at z -17 and -12.5, the second with
a steady term named beside it ("partly explained"); now z -1.0 and 0.1 (seeds 3, 4: -0.5, 0.6).
"""

from __future__ import annotations

import math
import warnings

import bouc_wen_id as bw
import numpy as np
import pytest

TWO_PI = 2.0 * math.pi
ETA = "stiffness_degradation"
BETA, GAMMA, MU = 1.2, 0.3, 1.5
#: Three frequencies by three amplitudes (x at 0.4, 1 and 2.5 times the saturation level, 0.82).
OMEGAS = np.repeat([2.0, 5.0, 10.0], 3)
AMPS = np.tile([0.33, 0.82, 2.05], 3)
SETTLE, PERIODS, SAMPLES, SUBSTEPS = 10, 20, 64, 4


def _record(delta_eta: float, noise: float, seed: int) -> list[bw.Recording]:
    """The element driven by x = u (G = 1) from rest, RK4 on [w, e] with x' exact, four steps a sample."""
    n = (SETTLE + PERIODS) * SAMPLES
    h = TWO_PI / OMEGAS / (SAMPLES * SUBSTEPS)

    def rate(t: np.ndarray, w: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = -AMPS * OMEGAS * np.sin(OMEGAS * t)
        aw = np.abs(w)
        dw = (v - BETA * np.abs(v) * aw ** (MU - 1.0) * w - GAMMA * v * aw**MU) / (1.0 + delta_eta * e)
        return dw, w * v

    w, e, t = np.zeros(OMEGAS.size), np.zeros(OMEGAS.size), np.zeros(OMEGAS.size)
    out = np.empty((OMEGAS.size, n))
    for k in range(n):
        out[:, k] = w
        for _ in range(SUBSTEPS):
            a1, b1 = rate(t, w, e)
            a2, b2 = rate(t + h / 2, w + h / 2 * a1, e + h / 2 * b1)
            a3, b3 = rate(t + h / 2, w + h / 2 * a2, e + h / 2 * b2)
            a4, b4 = rate(t + h, w + h * a3, e + h * b3)
            w = w + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)
            e = e + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
            t = t + h
    rng = np.random.default_rng([45, seed])
    recs = []
    for i in range(OMEGAS.size):
        tt = np.arange(n) * TWO_PI / OMEGAS[i] / SAMPLES
        u = AMPS[i] * np.cos(OMEGAS[i] * tt)
        y = out[i] + noise * rng.standard_normal(n)
        recs.append(bw.Recording(tt, u, y, float(AMPS[i]), float(OMEGAS[i]), settle_periods=SETTLE))
    return recs


@pytest.mark.parametrize("seed", [1, 2])
def test_stiffness_degradation_value_within_its_standard_error(seed: int) -> None:
    truth = 0.01
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(_record(truth, 0.01, seed), candidates=[ETA])
    named = [t for t in d.named if t.term == ETA]
    assert named, d.summary()
    z = (named[0].value - truth) / named[0].standard_error
    # A Gaussian z: |z| > 3.5 once in 2000 draws.
    assert abs(z) < 3.5, (named[0].value, named[0].standard_error, z)
    # The periods brought back to the virgin stiffness leave nothing for a steady term.
    assert d.status == "explained", d.summary()
