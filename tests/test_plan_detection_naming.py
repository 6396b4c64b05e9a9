"""A detection plan is for the diagnosis's *naming* (review of branch plandetect, mended on planmend).

- The diagnosis names a term only if its F-test passes and it improves the held-out fit (leave-one-experiment
  out): a plan has at least 3 experiments by default, built by the search (not the naive fallback), and its
  summary says the power is the F-test's and what the experiment count means for the held-out test.
- A ``baseline`` with fewer experiments than ``min_experiments`` does not replace the plan.
- A size outside the term's physical range is refused by name; a term whose physical range is one-sided
  counts one tail of the power (the diagnosis never names the other sign).
- Dahl friction (two parameters) is not offered as detectable; the candidate count is the diagnosis's own.
- The adequate verdict's hint counts periods after the settling ones; the CLI takes --min-experiments.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id import cli
from bouc_wen_id.diagnosis.candidates import step_candidates
from bouc_wen_id.diagnosis.design_hint import DesignHint
from bouc_wen_id.diagnosis.limits import DetectionLimit
from bouc_wen_id.diagnosis.resolution import hint_text
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.planning import DETECTABLE, PlannedExperiment, detection_power
from bouc_wen_id.planning._power import DEFAULT_CANDIDATES, UnphysicalSizeError
from bouc_wen_id.terms import DIAGNOSIS_CANDIDATES, TERMS
from scipy.special import ndtr  # type: ignore[import-untyped]

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


@pytest.fixture(scope="module")
def readme() -> bw.DetectionPlan:
    return bw.plan_detection(PRIOR, 300.0, {"sensor_lag": 0.01}, **README)


def test_a_plan_has_three_experiments_by_default_and_says_what_its_power_is(readme: bw.DetectionPlan) -> None:
    assert len(readme.experiments) >= 3
    text = readme.summary()
    assert "naming also needs the held-out test across experiments" in text
    assert "min_experiments = 3" in text
    one = replace(
        readme, experiments=readme.experiments[:1], settings={**readme.settings, "min_experiments": 1}
    )
    assert "cannot run" in one.summary()


def test_three_experiments_are_searched_not_the_naive_fallback() -> None:
    three = bw.plan_detection(PRIOR, 300.0, {"sensor_lag": 0.01}, min_experiments=3, **README)
    assert len(three.experiments) >= 3 and three.total_time <= three.budget
    assert three.naive is not None and len(three.naive_experiments) == len(three.experiments)
    assert three.predicted.lam > 2.0 * three.naive.lam  # the fallback was the naive design itself


def test_a_short_baseline_does_not_replace_the_plan() -> None:
    one = bw.plan_detection(PRIOR, 120.0, {"sensor_lag": 2e-4}, min_experiments=1, **LAB)
    base = one.experiments[:1]
    plan = bw.plan_detection(PRIOR, 120.0, {"sensor_lag": 2e-4}, min_experiments=3, baseline=base, **LAB)
    assert len(plan.experiments) >= 3
    alone = detection_power(PRIOR, base, "sensor_lag", 2e-4, noise_sd=LAB["noise_sd"])
    assert alone.lam_used > 0.0


@pytest.mark.parametrize("term", ["viscous", "stiffness", "coulomb@x", "inertia"])
def test_an_unphysical_size_gets_a_named_error(term: str) -> None:
    assert TERMS[term].physical[0] == 0.0
    with pytest.raises(UnphysicalSizeError, match=term):
        bw.plan_detection(PRIOR, 100.0, {term: -0.01}, **LAB)
    assert issubclass(UnphysicalSizeError, InvalidParameterError)


def test_a_one_sided_physical_range_counts_one_tail() -> None:
    design = [PlannedExperiment(5.0, 1.5, 10, 64, 10)]
    p = detection_power(PRIOR, design, "stiffness", 1e-4, noise_sd=0.01)
    assert not p.one_sided  # the F-test of a stiffness is two-sided (its fitted range is unbounded)
    d = p.lam_used**0.5
    assert p.power == pytest.approx(float(ndtr(d - p.z_c)), rel=1e-12, abs=1e-15)
    assert p.power < float(ndtr(d - p.z_c)) + float(ndtr(-d - p.z_c))


def test_dahl_is_not_offered_and_the_candidate_count_is_the_diagnosis_own() -> None:
    assert not any(TERMS[t].part_of or TERMS[t].companion for t in DETECTABLE)
    with pytest.raises(InvalidParameterError, match="two-parameter") as err:
        bw.plan_detection(PRIOR, 100.0, {"dahl": 0.05}, **LAB)
    assert "dahl," not in str(err.value).split("detect are")[-1]
    assert DEFAULT_CANDIDATES == len(step_candidates(DIAGNOSIS_CANDIDATES, pure_sines=True))
    assert len(step_candidates(DIAGNOSIS_CANDIDATES, pure_sines=False)) == DEFAULT_CANDIDATES + 1


def test_the_hint_counts_periods_after_the_settling_ones() -> None:
    lim = DetectionLimit("sensor_lag", "tau", "s", 1e-3, 2e-3, 0.0, 1e-3, 1e-4, True, 0.99)
    lim = replace(lim, hint=DesignHint(2.0, 0, 3.0))
    exps = [PlannedExperiment(5.0, 1.0, 20, 64, 10), PlannedExperiment(8.0, 1.0, 20, 64, 10)]
    assert "40 periods after the settling ones per experiment" in hint_text(lim, exps)


def test_cli_takes_min_experiments(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["plan", "--budget", "120", "--band", "2", "12", "--max-amplitude", "1.5", "--noise", "0.01"]
    argv += ["--sample-rate", "200", "--max-samples-per-period", "64", "--frequencies", "6"]
    argv += ["--amplitudes", "2", "--detect", "sensor_lag=2e-4", "--candidates", "16"]
    assert cli.main([*argv, "--min-experiments", "1"]) == 0
    out = capsys.readouterr().out
    assert "min_experiments = 1" in out
    assert cli.main([*argv, "--min-experiments", "4"]) == 0
    assert "min_experiments = 4" in capsys.readouterr().out
