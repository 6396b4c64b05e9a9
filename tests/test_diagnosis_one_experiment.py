"""One experiment allows no held-out test: the verdict says so when it names a term (review 31a item 7)."""

from __future__ import annotations

import bouc_wen_id as bw
from bouc_wen_id.terms import Viscous


def _one(term: bool) -> bw.Diagnosis:
    plant = bw.WienerPlant(
        bw.TransferFunction([1.5], [0.2, 1.0]),
        bw.BoucWen(beta=1.0, gamma=0.3, mu=1.5, alpha=1.0),
        terms=(Viscous(0.08),) if term else (),
    )
    plan = bw.SinePlan(
        frequencies=[4.0], amplitudes=1.0, settle_periods=10, periods=16, samples_per_period=128,
        noise_sd=0.01, seed=3,
    )  # fmt: skip
    return bw.diagnose(bw.simulate(plant, plan))


def test_a_term_named_from_one_experiment_says_the_held_out_test_was_not_possible() -> None:
    d = _one(term=True)
    assert d.named
    assert "held-out test: not possible with one experiment" in d.verdict


def test_nothing_named_nothing_said() -> None:
    d = _one(term=False)
    assert not d.named
    assert "held-out test" not in d.verdict
