"""Review 47 failure 4: a rate-dependent loop width on a mu = 1.5 element (a sweep at one amplitude) read "not
explained: the loops may be softer than mu = 1 allows": the fit of every frequency together held mu at its
lower end, but the hint pointed at the exponent while the structure was the rate's. diagnosis/soft_rate.py
fits the lower and the upper half of the frequencies apart: the slower half holds the element's exponent,
and the verdict says the loop's shape changes with frequency instead.

Data: a right-hand side of its own (no G: x = u, so the rate is the drive's), ``z' = v (1 - (1 + R |v| / V)
(beta |z|^mu sgn(z v) + gamma |z|^mu))`` (review 47's K element: gamma/beta = -0.9, softening), integrated by
on_x_sim's classical RK4 stepper; not the library's, the benches' or review 47's generators; white noise
from a fixed seed."""

from __future__ import annotations

import math
import warnings
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.augmented import AugExperiment
from bouc_wen_id.diagnosis import bounds_said
from on_x_sim import sample_step

BETA, GAMMA, MU = 1.0, -0.9, 1.5
FREQS = tuple(float(f) for f in np.geomspace(0.1, 2.0, 8))  # Hz, one amplitude: a sweep
P, SETTLE, PERIODS = 128, 5, 4
AMP = 1.5 * 10.0 ** (1 / 1.5)  # times the saturation level (beta + gamma)^(-1/mu)


def _run(f: float, rate: float) -> tuple[Any, Any]:
    """(u, z) of one experiment from rest; V the fastest experiment's peak rate."""
    om, h, vmax = 2 * math.pi * f, 1.0 / (f * P), 2 * math.pi * max(FREQS) * AMP

    def dz(t: float, z: float) -> float:
        v = -AMP * om * math.sin(om * t)
        return float(v * (1 - (1 + rate * abs(v) / vmax) * (BETA * np.sign(z * v) + GAMMA) * abs(z) ** MU))

    n = (SETTLE + PERIODS) * P
    u, z, t, s = np.empty(n), np.empty(n), 0.0, 0.0
    for k in range(n):
        u[k], z[k] = AMP * math.cos(om * t), s
        s, t = sample_step(dz, s, t, h)
    return u, z


def _diagnose(rate: float, seed: int) -> Any:
    rng = np.random.default_rng(seed)
    recs = []
    for f in FREQS:
        u, z = _run(f, rate)
        y = z + rng.normal(0.0, 0.01, z.size)
        t = np.arange(z.size) / (f * P)
        recs.append(bw.Recording(t, u, y, AMP, 2 * math.pi * f, settle_periods=SETTLE))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


def test_a_rate_dependent_width_is_said_as_such_not_as_a_softer_exponent() -> None:
    d = _diagnose(2.0, 1)
    assert d.status != "explained" and not d.named, d.verdict
    head = d.verdict.split("; ")[0]
    assert "changes with frequency" in head, d.verdict  # on main: "the loops may be softer than mu = 1"
    assert not d.verdict.startswith(bounds_said.SOFT_HEAD), d.verdict
    # the slower half holds the element's exponent
    slow = float(head.split("hold mu = ")[1].split(" ")[0])
    assert abs(slow - MU) < 0.4, head


def test_halves_need_a_shared_amplitude() -> None:
    from bouc_wen_id.diagnosis import (
        soft_rate,
    )  # new on this branch: imported here, the test above fails on main

    def e(f: float, a: float) -> AugExperiment:
        return AugExperiment(ybar=np.zeros(8), amplitude=a, frequency=f, grid_phase=0.0, weight=1.0)

    shared = [e(1.0, 1.0), e(2.0, 1.0), e(3.0, 1.0), e(4.0, 1.0)]
    assert soft_rate.halves(shared) == ([0, 1], [2, 3])
    apart = [e(1.0, 1.0), e(2.0, 1.0), e(3.0, 2.0), e(4.0, 2.0)]  # each half at its own amplitude
    assert soft_rate.halves(apart) is None
    assert soft_rate.halves([e(1.0, 1.0), e(1.0, 2.0)]) is None  # one frequency
