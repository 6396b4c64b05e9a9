"""Records of a degrading Baber-Noori element, simulated apart from the library's generator (session 45's
test_eta_value.py RK4, shared since session 46 by test_eta_value.py and test_nu_value.py).

The element ``w' = [x' - nu (beta |x'| |w|^(mu-1) w + gamma x' |w|^mu)] / eta`` with ``nu = 1 + delta_nu e``
(strength degradation), ``eta = 1 + delta_eta e`` (stiffness degradation) and ``e' = w x'``, driven by
``x = u = U cos(omega t)`` (G = 1) from rest; RK4 on [w, e] with x' exact, four steps a sample, every
experiment at once; white noise from ``default_rng([45, seed])``.
"""

from __future__ import annotations

import math
import warnings

import bouc_wen_id as bw
import numpy as np
from rk4 import rk4_step

TWO_PI = 2.0 * math.pi
BETA, GAMMA, MU = 1.2, 0.3, 1.5
#: Three frequencies by three amplitudes (x at 0.4, 1 and 2.5 times the saturation level, 0.82).
OMEGAS = np.repeat([2.0, 5.0, 10.0], 3)
AMPS = np.tile([0.33, 0.82, 2.05], 3)
SETTLE, PERIODS, SAMPLES, SUBSTEPS = 10, 20, 64, 4


def records(noise: float, seed: int, delta_nu: float = 0.0, delta_eta: float = 0.0) -> list[bw.Recording]:
    """One recording per experiment, the settling periods included (``settle_periods=SETTLE``)."""
    n = (SETTLE + PERIODS) * SAMPLES
    h = TWO_PI / OMEGAS / (SAMPLES * SUBSTEPS)

    def rate(t: np.ndarray, w: np.ndarray, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        v = -AMPS * OMEGAS * np.sin(OMEGAS * t)
        aw = np.abs(w)
        loss = (1.0 + delta_nu * e) * (BETA * np.abs(v) * aw ** (MU - 1.0) * w + GAMMA * v * aw**MU)
        return (v - loss) / (1.0 + delta_eta * e), w * v

    w, e, t = np.zeros(OMEGAS.size), np.zeros(OMEGAS.size), np.zeros(OMEGAS.size)
    out = np.empty((OMEGAS.size, n))
    for k in range(n):
        out[:, k] = w
        for _ in range(SUBSTEPS):
            w, e = rk4_step(rate, t, w, e, h)
            t = t + h
    rng = np.random.default_rng([45, seed])
    recs = []
    for i in range(OMEGAS.size):
        tt = np.arange(n) * TWO_PI / OMEGAS[i] / SAMPLES
        u = AMPS[i] * np.cos(OMEGAS[i] * tt)
        y = out[i] + noise * rng.standard_normal(n)
        recs.append(bw.Recording(tt, u, y, float(AMPS[i]), float(OMEGAS[i]), settle_periods=SETTLE))
    return recs


def named_z(noise: float, seed: int, term: str, truth: float, **delta: float) -> tuple[bw.Diagnosis, float]:
    """``bw.diagnose`` on :func:`records` with ``candidates=[term]`` (its warnings silenced), and the z of
    ``term``'s named value against ``truth`` (NaN when it is not named)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(records(noise, seed, **delta), candidates=[term])
    named = [t for t in d.named if t.term == term]
    z = (named[0].value - truth) / named[0].standard_error if named else math.nan
    return d, z
