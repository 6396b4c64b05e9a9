"""A drive with a mean of its own (review 35, problem 1): a parallel spring's share of the input's mean is
said as the spring's, not as a sensor zero error (diagnosis/input_dc.py).

The plant is made here, apart from the package's simulators and the reviewer's: G = 1/(1 + s/3) without a
delay, Bouc-Wen (beta 0.8, gamma 0.2, mu 1.3) by RK4 on the analytic steady x, input U (cos + 0.25).
"""

from __future__ import annotations

import math

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import input_dc
from bouc_wen_id.diagnosis.data import prepare
from bouc_wen_id.diagnosis.result import NamedTerm

FREQS = (1.0, 2.0, 3.5, 5.0)
P, SETTLE, PERIODS, SUB = 96, 6, 8, 8


def _loop(om: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Sample times and the Bouc-Wen w on x = G u's steady sine (G = 1/(1 + s/3))."""
    g = 1.0 / (1.0 + 1j * om / 3.0)
    amp, lag = abs(g), math.atan2(g.imag, g.real)
    h = 2.0 * math.pi / om / P / SUB
    t = np.arange(n) * (2.0 * math.pi / om / P)

    def f(w: float, s: float) -> float:
        v = -amp * om * math.sin(om * s + lag)
        return v - 0.8 * abs(v) * abs(w) ** 0.3 * w - 0.2 * v * abs(w) ** 1.3

    w, ws = 0.0, np.zeros(n)
    for j in range(n):
        ws[j] = w
        for i in range(SUB):
            s = t[j] + i * h
            k1 = f(w, s)
            k2 = f(w + 0.5 * h * k1, s + 0.5 * h)
            k3 = f(w + 0.5 * h * k2, s + 0.5 * h)
            w += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + f(w + h * k3, s + h))
    return t, ws


def _records(k_u: float, dc: float, seed: int, sd: float = 0.004) -> list[bw.Recording]:
    rng = np.random.default_rng(seed)
    out = []
    for om in FREQS:
        n = (SETTLE + PERIODS) * P
        t, ws = _loop(om, n)
        u = np.cos(om * t) + dc
        y = ws + k_u * u + sd * rng.standard_normal(n)
        out.append(bw.Recording(t, u, y, amplitude=1.0, frequency=om, settle_periods=SETTLE))
    return out


def test_a_spring_on_a_preloaded_drive_is_no_sensor_offset() -> None:
    dg = bw.diagnose(_records(0.06, 0.25, 3))
    names = {t.term for t in dg.named}
    assert "stiffness" in names and "offset" in names, dg.verdict
    # Its DC share is said where the offset is: not a sensor zero (main said "output offset y0 = ..." alone).
    if "offset" in names:
        assert "not a sensor zero" in dg.verdict, dg.verdict
        assert "k × u0" in dg.verdict


def test_a_preloaded_drive_alone_stays_quiet() -> None:
    dg = bw.diagnose(_records(0.0, 0.25, 4))
    assert dg.status == "adequate", dg.verdict


def _term(term: str, sym: str, v: float, se: float) -> NamedTerm:
    return NamedTerm(term, sym, v, se, "")


def test_qualify_on_u_splits_the_offset_and_on_x_gives_both_readings() -> None:
    exps = prepare(_records(0.0, 0.25, 5))
    assert all(abs(e.input_dc - 0.25) < 1e-3 for e in exps)
    off = _term("offset", "y0", 0.0151, 0.0002)
    said = "explained by: " + str(off) + ", k"
    on_u = input_dc.qualify(said, [off, _term("stiffness", "k", 0.06, 0.002)], exps)
    assert "not a sensor zero" in on_u and on_u.startswith(said[:-3])
    big = _term("offset", "y0", 0.05, 0.0002)
    real = input_dc.qualify(f"explained by: {big}", [big, _term("stiffness", "k", 0.06, 0.002)], exps)
    assert "is a sensor zero or another preload" in real
    on_x = input_dc.qualify(said, [off, _term("stiffness@x", "k", 0.06, 0.002)], exps)
    assert "cannot tell a sensor zero from a preloaded spring" in on_x and "G(0) = 1.01" in on_x
    # A centred drive, or an offset without a spring, leaves the verdict as it was.
    centred = prepare(_records(0.0, 0.0, 5))
    assert input_dc.qualify(said, [off, _term("stiffness", "k", 0.06, 0.002)], centred) == said
    assert input_dc.qualify(said, [off], exps) == said
