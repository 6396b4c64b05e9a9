"""A Wiener-Bouc-Wen simulator written for the tests, apart from the library's and the benches' generators.

RK4 on a resonant G's two states and the Bouc-Wen state together, a pure delay on the sine drive (exact for a
sine), four steps a sample; Spencer's series dashpot (``rho``: the element driven by its own travel,
``ddot = xdot - rho w``) optional. Used by test_record_zeros.py, test_diagnosis_bounds_said.py and
test_across_colour.py; test_ring_down.py uses its integrator and AR(1) noise.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from on_x_sim import sample_step

P = 128
WN, ZETA, DELAY = 2 * math.pi * 6.0, 0.25, 0.004  # G = WN^2 / (s^2 + 2 ZETA WN s + WN^2) e^{-s DELAY}
BETA, GAMMA, MU = 0.5, 0.3, 1.5
SETTLE, PERIODS = 8, 24


def simulate(
    freqs: np.ndarray, amps: np.ndarray, delta: float = 0.0, mu: float = MU, rho: float = 0.0
) -> tuple[Any, Any, Any]:
    """(h, u, w) per experiment: ``P`` samples a period, four RK4 steps a sample; ``delta`` the asymmetry
    (the library's asymmetry term: ``delta |w|^mu sgn(w)`` beside gamma); ``mu`` may be below 1 (a loop
    softer than the library's bracket allows); ``rho`` a series dashpot (w driven by ``x' - rho w``)."""
    om = 2 * math.pi * freqs
    h = 2 * math.pi / om / P
    n = (SETTLE + PERIODS) * P

    def rate(t: np.ndarray, s: np.ndarray) -> np.ndarray:
        x, v, w = s
        aw = np.abs(w)
        u = amps * np.cos(om * (t - DELAY))
        pw = aw**mu  # |w|^(mu - 1) w written as |w|^mu sgn(w): finite at w = 0 for mu < 1 too
        d = v - rho * w  # the element's own travel rate behind a series dashpot (v itself when rho = 0)
        dw = d - (BETA * np.abs(d) * pw * np.sign(w) + GAMMA * d * pw + delta * d * pw * np.sign(w))
        return np.array([v, WN**2 * (u - x) - 2 * ZETA * WN * v, dw])

    ws = hysteretic_states(rate, h, n)
    tt = np.arange(n)[:, None] * h[None, :]
    return h, (amps * np.cos(om * tt)).T, ws.T


def hysteretic_states(rate: Callable[[Any, Any], Any], h: Any, n: int) -> Any:
    """``n`` samples (rows) of the third state (the Bouc-Wen w) of the ODE ``rate(t, s)`` on the states
    ``(x, v, w)`` of each experiment (columns, step ``h[i]``), from rest, four RK4 steps a sample."""
    s, t, ws = np.zeros((3, h.size)), np.zeros(h.size), np.zeros((n, h.size))
    for k in range(n):
        ws[k] = s[2]
        s, t = sample_step(rate, s, t, h)  # four RK4 steps a sample
    return ws


def recordings(
    seed: int,
    offsets: list[float],
    c: float = 0.0,
    delta: float = 0.0,
    amps: Any = None,
    phi: float = 0.0,
    rho: float = 0.0,
) -> list[Any]:
    """Recordings at 2, 4, 6 and 8 Hz (amplitude 1.5 unless ``amps``): :func:`simulate`'s w, viscous damping
    on u (``c`` times u's rate), each one's output zero ``offsets[i]`` and noise of 1 % of w's RMS from
    ``seed``, white or AR(1) with coefficient ``phi`` (the same sd); ``rho`` a series dashpot."""
    import bouc_wen_id as bw

    freqs = np.array([2.0, 4.0, 6.0, 8.0])
    a = np.full(freqs.size, 1.5) if amps is None else np.asarray(amps, dtype=np.float64)
    h, u, w = simulate(freqs, a, delta, rho=rho)
    rng = np.random.default_rng(seed)
    out = []
    for i, f in enumerate(freqs):
        t = np.arange(w[i].size) * h[i]
        du = -a[i] * 2 * math.pi * f * np.sin(2 * math.pi * f * t)
        sd = 0.01 * float(np.sqrt(np.mean(w[i] ** 2)))
        y = w[i] + c * du + offsets[i] + (ar1(rng, t.size, sd, phi) if phi else rng.normal(0.0, sd, t.size))
        out.append(bw.Recording(t, u[i], y, float(a[i]), 2 * math.pi * float(f), settle_periods=SETTLE))
    return out


def ar1(rng: np.random.Generator, n: int, sd: float, phi: float) -> Any:
    """AR(1) noise of standard deviation ``sd``, started from its stationary law."""
    e = rng.normal(0.0, sd * math.sqrt(1.0 - phi**2), n)
    out = np.empty(n)
    prev = rng.normal(0.0, sd)
    for k in range(n):
        prev = phi * prev + e[k]
        out[k] = prev
    return out
