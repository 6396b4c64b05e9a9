"""Review 47 failure 1: a Bouc-Wen element with mu = 0.75 (outside the model) under AR(1) noise of
coefficient 0.95 passed the plain model's global test, and the targeted step named terms beside mu held at
the lower end of its bracket (review 47: stiffness@x + play, "explained"); with white noise the same terms
were refused as stand-ins for a loop softer than mu = 1. The guard (diagnosis/bounds_said.py) holds on the
targeted path too. Data: on_x_sim.py's RK4 (not the library's, the benches' or review 47's generators), a
first-order G, four frequencies at two amplitudes, AR(1) noise from a fixed seed."""

from __future__ import annotations

import math
import warnings
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import bounds_said
from bouc_wen_id.diagnosis.result import NamedTerm
from on_x_sim import BETA, GAMMA, Lin, simulate
from wiener_sim import ar1

G = Lin(1, 2.0)  # a corner at 2 Hz
FREQS = np.array([0.2, 0.4, 0.8, 1.6] * 2)
P, SETTLE, PERIODS = 160, 10, 8


def _recordings(mu: float, k: float, seed: int) -> list[Any]:
    """``w + k x`` (``k``: a spring across the element, on x) with AR(1) noise (0.95) of 1 % of the
    element's saturation level, the drive 1.2 and 2.4 times it."""
    wu = (1.0 / (BETA + GAMMA)) ** (1.0 / mu)
    amps = np.array([1.2] * 4 + [2.4] * 4) * wu
    r = simulate(G, FREQS, amps, P, SETTLE, PERIODS, mu=mu)
    rng = np.random.default_rng(seed)
    recs = []
    for i, f in enumerate(FREQS):
        t = np.arange(r.w[i].size) * r.h[i]
        y = r.w[i] + k * r.x[i] + ar1(rng, t.size, 0.01 * wu, 0.95)
        recs.append(bw.Recording(t, r.u[i], y, float(amps[i]), 2 * math.pi * float(f), settle_periods=SETTLE))
    return recs


def _diagnose(mu: float, k: float, seed: int) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(_recordings(mu, k, seed))


def _across(mu: float, k: float) -> Any:
    """``diagnose_across`` on two conditions, the same device, the noise from seeds 1 and 2."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across([_recordings(mu, k, 1), _recordings(mu, k, 2)], [0.0, 1.0])


def test_a_soft_loop_under_ar1_noise_names_no_term_on_the_targeted_path() -> None:
    d = _diagnose(0.75, 0.0, 1)
    assert d.steps and d.steps[0].targeted, d.verdict  # the plain model passed its global test
    assert not d.named and d.status != "explained", d.verdict  # on main: Dahl on x named, "explained"
    assert d.verdict.startswith(bounds_said.SOFT_HEAD), d.verdict
    assert "softer than mu = 1 allows" in d.verdict and bounds_said.HELD_MARK in d.verdict, d.verdict


def test_a_true_spring_on_x_with_mu_inside_its_bracket_is_still_named() -> None:
    k = 0.05
    d = _diagnose(1.5, k, 1)
    assert d.steps and d.steps[0].targeted, d.verdict  # the same path
    assert d.status == "explained" and [t.term for t in d.named] == ["stiffness@x"], d.verdict
    t = d.named[0]
    assert abs(t.value - k) < 3.0 * t.standard_error, (t.value, t.standard_error)
    assert bounds_said.MU_MARK not in d.verdict and bounds_said.SOFT_HEAD not in d.verdict, d.verdict


def test_an_adequate_final_model_is_demoted_only_on_the_targeted_path() -> None:
    """:func:`.bounds_said.apply` on an "explained" verdict with mu held at the lower end: the terms stand
    only when they did not come from the targeted step (an adequate final model after a failed plain one)."""
    kept = (NamedTerm("stiffness@x", "k", 0.014, 0.002, ""),)
    held = bounds_said.Beyond(mu_face="lower", mu=1.0)
    assert bounds_said.apply(held, "explained", kept, kept, 1.0) == ("explained", kept, "", "")
    soft = bounds_said.apply(
        bounds_said.Beyond(mu_face="lower", mu=1.0, targeted_soft=True), "explained", kept, kept, 1.0
    )
    assert soft[0] == "unexplained" and soft[1] == () and soft[2].startswith(bounds_said.SOFT_HEAD), soft
    assert bounds_said.HELD_MARK in soft[3] and "k = 0.014" in soft[3], soft


def test_diagnose_across_takes_the_same_guard() -> None:
    d = _across(0.75, 0.0)
    assert d.steps and d.steps[0].targeted, d.verdict
    assert not d.named and d.status == "unexplained", d.verdict  # on main: Dahl on x named at both
    assert bounds_said.SOFT_HEAD in d.verdict.split("; ")[0], d.verdict
    assert "fitted with mu held there, not named" in d.verdict and "0 % of the summed excess" not in d.verdict
    control = _across(1.5, 0.05)
    assert control.status == "explained" and "stiffness@x" in control.named, control.verdict
    assert bounds_said.SOFT_HEAD not in control.verdict, control.verdict
