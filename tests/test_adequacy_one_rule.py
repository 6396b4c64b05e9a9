"""Every place a diagnosis says a model is adequate follows one rule (diagnosis/adequacy.py).

The status decided the plain model at ``alpha / 2`` (gate.plain_passes) and the detection limits' voiding
did too, while the JSON's ``after.adequate`` and the summary's / report's "where the final model misses"
read the localisation at 0.05 whatever ``alpha``: a plain model at p = 0.035 was "adequate" in its status
and ``"after": {"adequate": false}`` with a place it misses in the same result.
"""

from __future__ import annotations

import json
import warnings
from dataclasses import replace

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import adequacy, limits_void
from bouc_wen_id.diagnosis.report import html_page
from bouc_wen_id.diagnosis.run import diagnose as run_diagnose


@pytest.fixture(scope="module")
def plain() -> bw.Diagnosis:
    """A real diagnosis of a plain plant (first-order G, coloured-free noise of its own seed), adequate."""
    lin = bw.TransferFunction([2.0], [1.0, 2.0])
    om = np.array([0.8, 1.6, 3.2])
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        om, 1.1 / g, settle_periods=20, periods=10, samples_per_period=64, substeps=8, noise_sd=0.005,
        seed=37,
    )  # fmt: skip
    recs = bw.simulate(bw.WienerPlant(lin, bw.BoucWen(0.5, 0.5, 1.4)), plan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run_diagnose(recs, candidates=[bw.terms.Stiffness.kind])


def _at(d: bw.Diagnosis, p: float) -> bw.Diagnosis:
    """``d`` with its plain and final models (and their localisations) at p-value ``p``."""
    return replace(
        d,
        plain=replace(d.plain, p_value=p),
        final=replace(d.final, p_value=p),
        before=replace(d.before, p_value=p),
        after=replace(d.after, p_value=p),
    )


def _statements(d: bw.Diagnosis) -> list[bool]:
    """Every statement ``d`` makes on whether its final model passes: the JSON, the limits' voiding, the
    summary's and the report's words on where it misses."""
    doc = json.loads(d.to_json())
    limits = not doc["detection_limits_void"] if d.limits else doc["after"]["adequate"]
    said = [doc["after"]["adequate"], limits]
    said.append(f"where the final model misses: {adequacy.NOWHERE}" in d.summary())
    said.append(f"Final: {adequacy.NOWHERE}" in html_page(d, {}))
    return said


def test_a_plain_model_between_half_alpha_and_alpha_is_adequate_everywhere(plain: bw.Diagnosis) -> None:
    assert plain.status == "adequate" and not plain.named, plain.verdict
    alpha = float(plain.settings["alpha"])
    # Between alpha / 2 and alpha: the plain model's global test passes (the status's rule).
    d = _at(plain, 0.7 * alpha)
    assert adequacy.final_passes(d)
    assert _statements(d) == [True] * 4, d.summary()
    assert json.loads(d.to_json())["after"]["adequacy_level"] == pytest.approx(0.5 * alpha)
    # Below alpha / 2 it fails everywhere.
    d = _at(plain, 0.3 * alpha)
    assert _statements(d) == [False] * 4, d.summary()
    if d.limits:
        assert limits_void.void(d)


def test_the_level_follows_the_alpha_the_user_set(plain: bw.Diagnosis) -> None:
    """At alpha = 0.2 a plain model at p = 0.08 (below 0.1) fails everywhere, though above locate's 0.05."""
    d = _at(replace(plain, settings={**plain.settings, "alpha": 0.2}), 0.08)
    assert _statements(d) == [False] * 4, d.summary()


def test_a_named_model_is_tested_at_alpha() -> None:
    """With named terms the level is alpha (the status's "explained" rule), without them alpha / 2."""
    assert adequacy.level(0.05, True) == 0.05 and adequacy.level(0.05, False) == 0.025
    assert not adequacy.passes(0.04, 0.05, True) and adequacy.passes(0.04, 0.05, False)
    assert not adequacy.passes(0.5, 0.05, False, drifting=True)
