"""A detection plan promises *naming*, not only its F-test's power; Dahl and absurd sizes get named errors.

- ``naming_chance``: the F-test passing *and* the held-out test (leave one experiment out) improving, in
  seeded draws of the linearised model. On one experiment (no held-out test) it is the F-test's power; on a
  two-experiment design whose one fold barely sees the term it is well below that power; it never exceeds it.
- A plan reports both (summary, JSON), picks designs by the chance to name, and :meth:`DetectionPlan.scaled`
  reaches the chance it is asked for.
- Dahl friction (two parameters) is refused with a named error that says why and what to plan instead.
- A size whose term would dwarf the plant (``viscous=1e308`` overflowed the model's output and was reported as
  the user's non-finite data) or a NaN size is refused by a named error that says so.
"""

from __future__ import annotations

import math
from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id import cli
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.planning import (
    DETECTABLE,
    OversizedTermError,
    PlannedExperiment,
    TwoParameterTermError,
    detection_power,
    naming_chance,
)
from bouc_wen_id.planning._power import MAX_TERM_RATIO

PRIOR = bw.demo_plant()
#: The README's example: plan --detect sensor_lag=0.01, budget 300 s, noise 0.05.
README: dict[str, Any] = dict(
    band=(1.0, 10.0), max_amplitude=1.0, noise_sd=0.05, sample_rate=100.0, settle_periods=10
)
LAB: dict[str, Any] = dict(
    band=(2.0, 12.0),
    max_amplitude=1.5,
    noise_sd=0.01,
    sample_rate=200.0,
    max_samples_per_period=64,
    settle_periods=10,
    n_frequencies=6,
    n_amplitudes=2,
)


def _exp(omega: float, periods: int) -> PlannedExperiment:
    return PlannedExperiment(omega, 1.0, periods, int(round(100.0 * 2.0 * math.pi / omega)), 10)


def test_on_one_experiment_the_chance_to_name_is_the_power() -> None:
    design = [_exp(8.16, 3000)]
    p = detection_power(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05)
    c = naming_chance(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05, power=p, rivals=(), seed=3)
    assert 0.2 < p.power < 0.95  # a power the draws can check
    se = math.sqrt(p.power * (1.0 - p.power) / c.draws)
    assert abs(c.chance - p.power) < 4.0 * se
    assert c.named_given_f == 1.0 and c.fold_lams == () and c.rival_named == 0.0
    # the diagnosis's linear candidates beside it: a rival with a larger cost drop is named instead at times
    r = naming_chance(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05, power=p, seed=3)
    assert "coulomb@x" in r.rivals and "sensor_lag" not in r.rivals
    assert r.chance == pytest.approx(c.chance - r.rival_named, abs=4.0 * se) and r.rival_named > 0.0


def test_a_fold_that_barely_sees_the_term_lowers_the_chance_to_name() -> None:
    # The README's 2-experiment plan at its old 90 % budget: one fold fits the lag on 202 periods at
    # 5.3 rad/s, where G's phase absorbs it (the diagnosis named the lag in 6 of 12 draws, docs/power.md).
    lopsided = [_exp(5.32, 202), _exp(8.16, 256)]
    p = detection_power(PRIOR, lopsided, "sensor_lag", 0.01, noise_sd=0.05)
    c = naming_chance(PRIOR, lopsided, "sensor_lag", 0.01, noise_sd=0.05, power=p)
    assert c.chance < p.power - 0.15
    assert c.named_given_f < 0.85
    assert c.weakest_fold < p.lam / 4.0
    balanced = [_exp(5.32, 52), _exp(8.16, 611), _exp(9.97, 1028)]  # the balanced plan at about the same F
    pb = detection_power(PRIOR, balanced, "sensor_lag", 0.01, noise_sd=0.05)
    cb = naming_chance(PRIOR, balanced, "sensor_lag", 0.01, noise_sd=0.05, power=pb)
    assert cb.chance - c.chance > 0.1 and cb.chance <= pb.power + 0.02
    assert cb.weakest_fold > c.weakest_fold


def test_the_chance_is_seeded() -> None:
    design = [_exp(5.32, 202), _exp(8.16, 256)]
    a = naming_chance(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05, draws=500, seed=1)
    b = naming_chance(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05, draws=500, seed=1)
    assert a == b


@pytest.fixture(scope="module")
def readme() -> bw.DetectionPlan:
    return bw.plan_detection(PRIOR, 300.0, {"sensor_lag": 0.01}, **README)


def test_a_plan_reports_its_chance_to_name(readme: bw.DetectionPlan) -> None:
    assert readme.naming is not None and readme.naive_naming is not None
    assert readme.naming.chance <= readme.predicted.power + 0.02
    text = readme.summary()
    assert "predicted chance to name" in text and "chance to name needs" in text
    d = readme.to_dict()
    assert d["naming"]["chance"] == readme.naming.chance
    assert d["naming"]["weakest_fold"] == min(readme.naming.fold_lams)


def test_the_scaled_plan_reaches_the_chance_to_name_it_states(readme: bw.DetectionPlan) -> None:
    exps = readme.scaled(0.9)
    assert exps and sum(e.duration for e in exps) == pytest.approx(readme.budget_for(0.9))
    p = detection_power(PRIOR, exps, "sensor_lag", 0.01, noise_sd=0.05)
    c = naming_chance(PRIOR, exps, "sensor_lag", 0.01, noise_sd=0.05, power=p, seed=7)
    assert c.chance >= 0.87 and p.power >= 0.9
    assert readme.periods_factor(0.9) > readme.predicted.periods_factor(0.9)  # naming asks more than F


@pytest.mark.parametrize(
    "term, limit", [("dahl", "coulomb"), ("dahl_sigma", "stiffness"), ("dahl@x", "coulomb@x")]
)
def test_dahl_gets_a_named_error_that_says_why_and_what_to_plan(term: str, limit: str) -> None:
    with pytest.raises(TwoParameterTermError) as err:
        bw.plan_detection(PRIOR, 100.0, {term: 0.05}, **LAB)
    text = str(err.value)
    assert "2 degrees of freedom" in text and "Jacobian" in text
    assert f"'{limit}'" in text and limit in DETECTABLE
    assert issubclass(TwoParameterTermError, InvalidParameterError)


@pytest.mark.parametrize("size, what", [(1e308, "overflow"), (1e3, "output swing .* at every frequency")])
def test_an_oversized_term_gets_a_named_error(size: float, what: str) -> None:
    with pytest.raises(OversizedTermError, match=what):
        bw.plan_detection(PRIOR, 100.0, {"viscous": size}, **LAB)
    assert issubclass(OversizedTermError, InvalidParameterError)


def test_a_large_but_plausible_term_is_planned() -> None:
    # 0.5 x the plant's output at the top of the band: large, but a term missing from a model
    plan = bw.plan_detection(PRIOR, 100.0, {"viscous": 0.01}, **LAB)
    assert plan.experiments and MAX_TERM_RATIO >= 10.0


def test_a_nan_size_is_the_users_size_said_as_such() -> None:
    with pytest.raises(InvalidParameterError, match=r"detect\['viscous'\] = nan"):
        bw.plan_detection(PRIOR, 100.0, {"viscous": float("nan")}, **LAB)


def test_cli_says_the_term_is_oversized(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["plan", "--budget", "100", "--band", "2", "12", "--max-amplitude", "1.5", "--noise", "0.01"]
    argv += ["--sample-rate", "200", "--max-samples-per-period", "64", "--frequencies", "6"]
    argv += ["--amplitudes", "2", "--detect", "viscous=1e308"]
    assert cli.main(argv) != 0
    err = capsys.readouterr().err
    assert "OversizedTermError" in err and "NonFiniteError" not in err and "clean or drop" not in err


@pytest.mark.parametrize("term", ["offset", "sensor_lag", "series_dashpot", "stiffness@x"])
def test_any_term_beyond_floating_point_gets_the_named_error(term: str) -> None:
    with pytest.raises(OversizedTermError, match=term):
        bw.plan_detection(PRIOR, 100.0, {term: 1e308}, **LAB)
