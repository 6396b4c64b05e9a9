"""A lightly damped G still ringing after the settle periods is no physics (review 44, failure 1).

The plant has no term beyond the plain Wiener-Bouc-Wen model: G = wn^2 / (s^2 + 2 zeta wn s + wn^2) with
zeta 0.05 at 6 rad/s, started from rest, 10 settle periods and 4 averaged ones, AR(1) noise (review 44's
design D). Before ring_down.py the diagnosis read the ring-down left in the averaged periods as a drift of
the loop and said "explained by: stiffness degradation". The data come from this file's own plant (G's two
states and the Bouc-Wen state, integrated together by wiener_sim's RK4), not from the library's simulator.
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numpy as np
from wiener_sim import ar1, hysteretic_states

P = 128
WN, ZETA = 6.0, 0.05
BETA, GAMMA, MU = 1.2, 0.3, 1.5
SETTLE, PERIODS = 10, 4
OMEGAS = np.array([2.0, 4.0, 7.0, 11.0] * 2)
AMPS = np.array([0.95] * 4 + [1.9] * 4)


def _simulate() -> tuple[Any, Any]:
    """``(h, w)``: each experiment's step and its Bouc-Wen state, four RK4 steps a sample, from rest."""
    h = 2 * math.pi / OMEGAS / P
    n = (SETTLE + PERIODS) * P

    def rate(t: Any, s: Any) -> Any:
        x, v, w = s
        pw = np.abs(w) ** MU
        dw = v - (BETA * np.abs(v) * pw * np.sign(w) + GAMMA * v * pw)
        return np.array([v, WN**2 * (AMPS * np.cos(OMEGAS * t) - x) - 2 * ZETA * WN * v, dw])

    return h, hysteretic_states(rate, h, n).T


def _recordings(seed: int) -> list[Any]:
    """The plain plant's recordings, AR(1) noise (coefficient 0.9, sd 0.01) from ``seed``."""
    import bouc_wen_id as bw

    h, w = _simulate()
    rng = np.random.default_rng(seed)
    out = []
    for i, om in enumerate(OMEGAS):
        t = np.arange(w[i].size) * h[i]
        u = AMPS[i] * np.cos(om * t)
        y = w[i] + ar1(rng, t.size, 0.01, 0.9)
        out.append(bw.Recording(t, u, y, float(AMPS[i]), float(om), settle_periods=SETTLE))
    return out


def test_a_ringing_null_names_nothing() -> None:
    import bouc_wen_id as bw
    from bouc_wen_id.errors import TransientWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        d = bw.diagnose(_recordings(13))
    said = f"{d.status}: {d.verdict}"
    assert not d.named, said  # main: "explained by: stiffness degradation delta_eta = ..."
    assert not any(t.term.endswith("degradation") for t in d.partial), said
    assert d.status != "explained", said
    assert d.verdict.startswith("not settled"), said
    assert "more settle periods" in d.verdict, said
    assert any(issubclass(w.category, TransientWarning) for w in caught)


def _periods(change: Any, seed: int) -> Any:
    """14 periods of a loop-like waveform (a sine and its third harmonic) plus ``change(k, phase)`` in
    period k, white noise of sd 0.003 from ``seed``."""
    th = 2 * math.pi * np.arange(P) / P
    rng = np.random.default_rng(seed)
    rows = [np.cos(th) + 0.2 * np.cos(3 * th) + change(k, th) for k in range(14)]
    return np.concatenate(rows) + rng.normal(0.0, 0.003, 14 * P)


def test_the_fall_tells_a_ring_down_from_a_steady_drift() -> None:
    from bouc_wen_id.diagnosis.ring_down import ringing

    # A free oscillation at 0.55 of the drive's frequency, falling by 0.8 a period.
    ring = _periods(lambda k, th: 0.5 * 0.8**k * np.cos(0.55 * (th + 2 * math.pi * k)), 1)
    assert 0.7 < ringing(ring, P, 14) < 0.9
    # A loop that softens by the same amount every period (a degradation at a steady rate): no ring-down.
    drift = _periods(lambda k, th: -0.01 * k * np.cos(th), 2)
    assert ringing(drift, P, 14) == 0.0
    # Noise about a settled loop: none either.
    assert ringing(_periods(lambda k, th: 0.0 * th, 3), P, 14) == 0.0
