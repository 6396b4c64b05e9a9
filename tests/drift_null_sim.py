"""Null and drifting sets for the drift tests, simulated apart from the library's generator (session 45,
honest45): a Bouc-Wen element (beta 0.6, gamma 0.2, mu 1.5, unit A) behind a first-order G = 1 / (1 + tau s)
with a pure delay, RK4 on (x, w) four steps a sample for every experiment at once, y = w + 0.4 x plus white
or AR(1) noise; optionally a decaying offset on the output's centre or an output gain drifting over each
record (the positive controls).
Used by test_drift_left_out.py and studies/honest45 (nulls45.py, scan45.py); the noise is wiener_sim.ar1."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rk4 import rk4_step
from wiener_sim import ar1

BETA, GAMMA, MU, ALPHA_X = 0.6, 0.2, 1.5, 0.4
SUB = 4
TAU, DELAY = 0.03, 0.004
#: The noise's sd, the periods recorded after the settling ones, and the samples per period.
SD, PERIODS, SETTLE, SAMPLES = 0.01, 20, 4, 128


def loops(omega: Any, amp: Any, n: int, samples: int) -> Any:
    """Noise-free y (rows: experiments) at ``n`` samples, ``samples`` a period, from rest (the drive on
    from t = DELAY)."""
    h = 2.0 * math.pi / omega / samples / SUB

    def rate(t: Any, x: Any, w: Any) -> tuple[Any, Any]:
        u = np.where(t >= DELAY, amp * np.cos(omega * (t - DELAY)), 0.0)
        xd = (u - x) / TAU
        aw = np.abs(w)
        return xd, xd - BETA * np.abs(xd) * aw ** (MU - 1.0) * w - GAMMA * xd * aw**MU

    x, w = np.zeros_like(omega), np.zeros_like(omega)
    out = np.empty((omega.size, n))
    for i in range(n):
        out[:, i] = w + ALPHA_X * x
        for j in range(SUB):
            x, w = rk4_step(rate, (i * SUB + j) * h, x, w, h)
    return out


def recordings(
    seed: int,
    n_exp: int = 10,
    phi: float = 0.0,
    offset: tuple[float, tuple[int, ...]] = (0.0, ()),
    gain: tuple[float, tuple[int, ...]] = (0.0, ()),
) -> list[Any]:
    """``n_exp`` recordings (0.5-4 Hz, amplitudes 0.8, 1.5, 2.5 w_u in turn), noise seeded by ``seed``; an
    ``offset`` (size, experiments) decaying with the record's length as its time constant, a ``gain`` (its
    relative change over the record, experiments) drifting linearly."""
    import bouc_wen_id as bw

    rng = np.random.default_rng([45, seed])
    wu = (1.0 / (BETA + GAMMA)) ** (1.0 / MU)
    freqs = np.geomspace(0.5, 4.0, n_exp)
    amps = wu * np.resize([0.8, 1.5, 2.5], n_exp)
    n = (SETTLE + PERIODS) * SAMPLES
    ys = loops(2.0 * math.pi * freqs, amps, n, SAMPLES)
    out = []
    for i, (f, a) in enumerate(zip(freqs, amps)):
        t = np.arange(n) / f / SAMPLES
        rec = np.clip(t - SETTLE / f, 0.0, None) * f / PERIODS  # 0 .. 1 over the record
        y = ys[i]
        if i in offset[1]:
            y = y + offset[0] * np.exp(-rec)
        if i in gain[1]:
            y = y * (1.0 + gain[0] * rec)
        y = y + ar1(rng, n, SD, phi)  # white at phi 0
        u = a * np.cos(2.0 * math.pi * f * t)
        name = f"r{i}_f{f:.2g}"
        out.append(
            bw.Recording(t, u, y, float(a), 2.0 * math.pi * f, settle_periods=SETTLE, metadata={"name": name})
        )
    return out
