"""Physics on the hysteresis' input x = G u, simulated for the tests apart from the library's, the benches'
and wiener_sim's generators (review 43's devices: a Kelvin element across the hysteretic element, a
Prandtl-Ishlinskii loop beside it).

RK4 on G's states (first order: a corner; second order: a resonance) and the Bouc-Wen state together, a pure
delay on the sine drive (exact for a sine), four steps a sample. :func:`simulate` returns x, its rate and w
per sample; the caller builds the output from them (``w + k x + c xdot``, or ``w + play_sum(x, ...)``).
Used by test_pairs_kelvin_x.py, test_place_tie.py and test_masing_pi_on_x.py; :func:`sample_step` by
wiener_sim.py, test_soft_value.py and test_soft_rate.py too.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

BETA, GAMMA, MU = 0.5, 0.3, 1.5
SUBSTEPS = 4


@dataclass(frozen=True)
class Lin:
    """G: ``1 / (1 + s / (2 pi f))`` (``order`` 1, ``f`` the corner in Hz) or ``wn^2 / (s^2 + 2 zeta wn s +
    wn^2)`` (``order`` 2, ``wn = 2 pi f``), behind a pure delay ``delay`` s; unit gain at DC."""

    order: int
    f: float
    zeta: float = 0.0
    delay: float = 0.0


@dataclass(frozen=True)
class Run:
    """Per experiment (rows) and sample (columns): ``u`` the drive, ``x`` = G u, ``v`` its rate, ``w`` the
    Bouc-Wen output (alpha 1); ``h`` the sample step per experiment."""

    h: Any
    u: Any
    x: Any
    v: Any
    w: Any


def sample_step(rate: Callable[[Any, Any], Any], s: Any, t: Any, h: Any) -> tuple[Any, Any]:
    """(state, time) one sample ``h`` later: :data:`SUBSTEPS` classical RK4 steps of ds/dt = rate(t, s)."""
    hh = h / SUBSTEPS
    for _ in range(SUBSTEPS):
        k1 = rate(t, s)
        k2 = rate(t + hh / 2, s + hh / 2 * k1)
        k3 = rate(t + hh / 2, s + hh / 2 * k2)
        k4 = rate(t + hh, s + hh * k3)
        s, t = s + hh / 6 * (k1 + 2 * k2 + 2 * k3 + k4), t + hh
    return s, t


def simulate(g: Lin, freqs: Any, amps: Any, p: int, settle: int, periods: int, mu: float = MU) -> Run:
    """The noise-free runs at ``freqs`` (Hz) and ``amps`` (the sine's amplitude at u), ``p`` samples a
    period, ``settle + periods`` periods, started at rest; ``mu`` may be below 1 (outside the library)."""
    freqs, amps = np.asarray(freqs, dtype=np.float64), np.asarray(amps, dtype=np.float64)
    om, wg = 2 * math.pi * freqs, 2 * math.pi * g.f
    h = 2 * math.pi / om / p
    n = (settle + periods) * p

    def lin(t: Any, x: Any, v: Any) -> tuple[Any, Any]:
        """(x's rate, v's rate): the second order carries v as a state, the first order has none."""
        ud = amps * np.cos(om * (t - g.delay))
        if g.order == 1:
            return wg * (ud - x), np.zeros_like(x)
        return v, wg**2 * (ud - x) - 2 * g.zeta * wg * v

    def rate(t: Any, s: Any) -> Any:
        x, v, w = s
        dx, dv = lin(t, x, v)
        pw = np.abs(w) ** mu  # |w|^mu sgn(w) as below: finite at w = 0 for mu < 1 too
        return np.array([dx, dv, dx - BETA * np.abs(dx) * pw * np.sign(w) - GAMMA * dx * pw])

    s, t = np.zeros((3, om.size)), np.zeros(om.size)
    xs, vs, ws = (np.zeros((n, om.size)) for _ in range(3))
    for i in range(n):
        xs[i], vs[i], ws[i] = s[0], lin(t, s[0], s[1])[0], s[2]
        s, t = sample_step(rate, s, t, h)
    tt = np.arange(n)[:, None] * h[None, :]
    return Run(h, (amps * np.cos(om * tt)).T, xs.T, vs.T, ws.T)


def play_sum(x: Any, thresholds: Any, weights: Any) -> Any:
    """A Prandtl-Ishlinskii loop: ``sum_j weights[j] play_{thresholds[j]}(x)`` along each row of ``x``, every
    play started at zero (its output follows x once x leaves the band ``|x - out| <= r``)."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    r = np.asarray(thresholds, dtype=np.float64)[None, :]
    out = np.zeros((x.shape[0], r.size))
    total = np.zeros_like(x)
    for k in range(x.shape[1]):
        out = np.clip(out, x[:, k : k + 1] - r, x[:, k : k + 1] + r)
        total[:, k] = out @ np.asarray(weights, dtype=np.float64)
    return total
