"""The headline says where structure remains when its only evidence is the experiments' DCs (review 45,
failure 1; diagnosis/centre_only.dc_only).

Under pink (1/f) noise a plain plant was told "unexplained structure remains spread over the cycle" at a
plain p of 1.0: the only structure the targeted step found was each experiment's DC (the output offset fitted
it only with a value that differs between experiments), and "spread over the cycle" is the localisation's word
for no place found, which a user reads as physics missing across the loop. The headline now says the DC. (The
false alarm itself, the DC's noise level understated under long memory, is not fixed here:
studies/pink45/README.md.)

The pink noise here is a sum of 12 AR(1) processes with time constants 2^j samples (a 1/f spectrum made
another way than review 45's FFT shaping), seeded.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import replace
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import centre_only
from bouc_wen_id.diagnosis.run import diagnose as run_diagnose


def _pink(n: int, rng: np.random.Generator, k: int = 12) -> np.ndarray:
    """Unit-variance 1/f noise: equal-variance AR(1)s with time constants 1, 2, 4, .. 2^(k-1) samples."""
    out = np.zeros(n)
    for j in range(k):
        a = math.exp(-1.0 / 2.0**j)
        e = rng.normal(size=n) * math.sqrt(1.0 - a * a)
        x = np.empty(n)
        x[0] = rng.normal()
        for i in range(1, n):
            x[i] = a * x[i - 1] + e[i]
        out += x
    return out / float(np.std(out))


@pytest.fixture(scope="module")
def pink_null() -> bw.Diagnosis:
    """A plain plant (second-order G, mu = 2.5) under pink noise of 1 % of the output's peak, 8 periods."""
    lin = bw.TransferFunction([36.0], [1.0, 3.6, 36.0])
    om = np.geomspace(1.0, 8.0, 8)
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        om, 1.5 / g, settle_periods=15, periods=8, samples_per_period=100, substeps=8, noise_sd=0.0, seed=1
    )
    clean = bw.simulate(bw.WienerPlant(lin, bw.BoucWen(1.2, 0.4, 2.5)), plan)
    sd = 0.01 * float(np.max(np.abs(clean[0].y)))
    rng = np.random.default_rng([45, 1])
    recs = [replace(r, y=r.y + sd * _pink(r.y.size, rng)) for r in clean]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_diagnose(recs)


def test_a_pink_null_whose_only_structure_is_the_dc_is_said_at_the_dc(pink_null: bw.Diagnosis) -> None:
    d = pink_null
    assert d.plain.p_value >= 0.05 and not d.named  # the plain model fits: nothing across the cycle
    if d.status == "adequate":
        pytest.skip("this draw was read as noise: nothing to word")  # a later fix of the DC's noise level
    assert "spread over the cycle" not in d.headline, d.headline
    assert d.headline.endswith(centre_only.DC_ONLY_WHERE), d.headline


def _step(trials: list[tuple[str, bool]], law_failed: tuple[str, ...]) -> Any:
    return SimpleNamespace(
        trials=[SimpleNamespace(term=t, passed=ok, law_p_value=1e-6) for t, ok in trials],
        law_failed=law_failed,
    )


def test_dc_only_needs_a_passing_plain_model_and_centre_terms_alone() -> None:
    only = [_step([("offset", True), ("stiffness", False)], ("offset",))]
    assert centre_only.dc_only(True, False, only)
    assert not centre_only.dc_only(False, False, only)  # the plain model failed its global test
    assert not centre_only.dc_only(True, True, only)  # a term was named
    assert not centre_only.dc_only(True, False, [_step([("offset", False)], ())])  # nothing law-failed
    beside = [_step([("offset", True), ("stiffness", True)], ("offset",))]
    assert not centre_only.dc_only(True, False, beside)  # a passing non-centre candidate
    other = [_step([("stiffness", True)], ("stiffness",))]
    assert not centre_only.dc_only(True, False, other)  # a law-failed candidate that is no centre term
