"""Review 38, item 2a: every named term must still pass its own test in the final model (final_terms.py)."""

from __future__ import annotations

import math

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import final_terms
from bouc_wen_id.diagnosis.result import NamedTerm
from bouc_wen_id.diagnosis.select import Step
from bouc_wen_id.terms import StiffnessX, ViscousX

TWO_PI = 2.0 * math.pi


def _isolator(seed: int) -> list[bw.Recording]:
    """Review 38's d1 isolator, made by the package's simulator: a spring and a damper on x, first-order G,
    0.5-4 Hz at two levels."""
    om = np.repeat(TWO_PI * np.array([0.5, 1.0, 2.0, 4.0]), 2)
    lin = bw.TransferFunction([1.0], [0.02, 1.0])
    plan = bw.SinePlan(
        om,
        np.tile([0.5, 1.0], 4),
        settle_periods=8,
        periods=12,
        samples_per_period=64,
        substeps=8,
        noise_sd=0.01,
        seed=seed,
    )
    plant = bw.WienerPlant(lin, bw.BoucWen(0.6, 0.4, 1.5), terms=(StiffnessX(0.5), ViscousX(0.02)))
    return bw.simulate(plant, plan)


def test_a_term_named_first_and_unneeded_once_the_pair_is_named_is_dropped() -> None:
    # Step 1 names viscous damping on u (the plain model's best), step 2 the pair on x. In the final model
    # the damper on u is 0.5 se from zero with a negative value: before final_terms.py it stayed in the
    # final model, and the verdict was "explained in part" with a "not physical" damper on u.
    d = bw.diagnose(_isolator(seed=1))
    assert [s.chosen for s in d.steps][:2] == ["viscous", "viscous@x"], d.summary()
    assert d.status == "explained", d.summary()
    assert set(d.named_terms) == {"viscous@x", "stiffness@x"}, d.summary()
    assert [t for t, _ in d.steps[-1].unneeded] == ["viscous"]
    assert "viscous" not in d.final_fit.params.terms  # refitted without it
    assert "not needed once" in d.verdict and "viscous damping on the measured input u" in d.verdict
    c = next(n for n in d.named if n.term == "viscous@x")
    assert abs(c.value - 0.02) < 4 * c.standard_error, d.summary()
    assert d.steps[-1].to_dict()["unneeded"][0]["term"] == "viscous"


def test_no_term_dropped_no_clause() -> None:
    named = (NamedTerm("viscous", "c", 0.05, 0.001, "s"),)
    steps = [Step(1.0, 1, (), "viscous")]
    assert final_terms.text(steps, named) == ""
    said = final_terms.text([Step(1.0, 1, (), "offset", unneeded=(("offset", 0.4),))], named)
    assert "offset (p adj = 0.4)" in said and "not needed once viscous damping" in said


def test_the_level_is_the_step_s_own() -> None:
    assert final_terms.level_of(Step(1.0, 1, (), "offset"), 0.05) == 0.05
    assert final_terms.level_of(Step(1.0, 1, (), "offset", targeted=True), 0.05) == 0.025
    assert final_terms.level_of(
        Step(1.0, 1, (), "offset", targeted=True, after_named=True), 0.05
    ) == pytest.approx(0.005)
