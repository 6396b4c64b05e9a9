"""The experiment planner: its predicted bounds are cramer_rao's, it beats the naive design on its own
criterion, it obeys every constraint, refuses bad input by name, and is deterministic.

Small candidate grids keep each plan to a few tens of milliseconds; the Monte Carlo check that a planned
design reaches its predicted precision is ``benches/planner.py``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import cli
from bouc_wen_id.errors import FileFormatError, InvalidParameterError, NonFiniteError
from bouc_wen_id.planning import criterion_value
from bouc_wen_id.terms import Play

PRIOR = bw.demo_plant()
#: Lab limits of the tests: a band around the demo resonance (5 rad/s), 100 Hz sampling, |U| <= 1.
LIMITS: dict[str, Any] = dict(
    band=(1.0, 10.0),
    max_amplitude=1.0,
    noise_sd=0.05,
    sample_rate=100.0,
    settle_periods=10,
    n_frequencies=6,
    n_amplitudes=3,
    overhead=2.0,
)


def _plan(target: str = "bouc_wen", budget: float = 300.0, **kw: Any) -> bw.ExperimentPlan:
    return bw.plan_experiment(PRIOR, budget, target=target, **{**LIMITS, **kw})  # type: ignore[arg-type]


@pytest.mark.parametrize("target", ["bouc_wen", "gamma", "G"])
def test_predicted_standard_errors_are_cramer_raos(target: str) -> None:
    plan = _plan(target)
    # The planner's experiments, each its own SinePlan (own N and P), through the public bound.
    cr = bw.cramer_rao(PRIOR, plan.plans(seed=1))
    # Same code path and inputs: only summation order could differ, far below 1e-10 relative.
    for name in ("beta", "gamma", "mu"):
        assert getattr(plan.predicted, name) == pytest.approx(getattr(cr, name), rel=1e-10)
    np.testing.assert_allclose(plan.predicted.gain, cr.gain, rtol=1e-10)
    np.testing.assert_allclose(plan.predicted.phase, cr.phase, rtol=1e-10)
    freqs = np.array([e.frequency for e in plan.experiments])
    assert plan.design.criterion == pytest.approx(criterion_value(target, PRIOR, freqs, cr), rel=1e-10)


@pytest.mark.parametrize("target", ["bouc_wen", "beta", "gamma", "mu", "G"])
def test_planned_design_beats_or_equals_the_naive_one(target: str) -> None:
    plan = _plan(target)
    assert plan.naive is not None
    assert plan.naive.total_time <= plan.budget
    assert plan.design.criterion <= plan.naive.criterion
    assert plan.improvement is not None and plan.improvement >= 1.0
    # The naive design is what it says: equal N, the largest amplitude, evenly log-spaced frequencies.
    naive = plan.naive.experiments
    assert len({e.periods for e in naive}) == 1
    assert all(e.amplitude == LIMITS["max_amplitude"] for e in naive)


def test_no_random_design_on_the_candidate_grid_beats_the_plan() -> None:
    """The greedy + exchange search is local: check it against 40 seeded random designs of 1-3
    experiments on the same candidates, spending the same budget (whole periods, N >= min_periods)."""
    budget = 300.0
    plan = _plan("bouc_wen", budget)
    omegas = np.array(plan.settings["candidate_frequencies"])
    period = 2 * np.pi / omegas
    rng = np.random.default_rng(11)
    best = math.inf
    for _ in range(40):
        ks = rng.choice(len(omegas), int(rng.integers(1, 4)), replace=False)
        free = budget - sum(LIMITS["overhead"] + LIMITS["settle_periods"] * period[k] for k in ks)
        shares = rng.dirichlet(np.ones(len(ks)))
        periods = [int(f * free // period[k]) for k, f in zip(ks, shares)]
        if free <= 0 or min(periods) < 5:
            continue
        plans = [
            bw.SinePlan(
                [omegas[k]],
                [LIMITS["max_amplitude"] * int(rng.integers(1, 4)) / 3],
                periods=n,
                samples_per_period=min(512, int(LIMITS["sample_rate"] * period[k])),
                noise_sd=LIMITS["noise_sd"],
            )
            for k, n in zip(ks, periods)
        ]
        cr = bw.cramer_rao(PRIOR, plans)
        best = min(best, criterion_value("bouc_wen", PRIOR, omegas[ks], cr))
    assert math.isfinite(best)
    assert plan.design.criterion <= best


def test_a_sequence_of_plans_is_one_design_for_cramer_rao() -> None:
    plan = bw.SinePlan([2.0, 5.0, 8.0], [0.4, 0.3, 0.5], periods=30, samples_per_period=64, noise_sd=0.05)
    whole = bw.cramer_rao(PRIOR, plan)
    split = [
        bw.SinePlan([w], [u], periods=30, samples_per_period=64, noise_sd=0.05)
        for w, u in zip(plan.frequencies, plan.amplitudes)
    ]
    parts = bw.cramer_rao(PRIOR, split)
    np.testing.assert_allclose(parts.fisher, whole.fisher, rtol=1e-12)
    # Doubling one experiment's N doubles its information (Fisher linear in N).
    longer = [split[0], split[1], bw.SinePlan([8.0], [0.5], periods=60, samples_per_period=64, noise_sd=0.05)]
    more = bw.cramer_rao(PRIOR, longer).fisher - whole.fisher
    np.testing.assert_allclose(more[np.ix_([7, 8], [7, 8])], whole.fisher[np.ix_([7, 8], [7, 8])], rtol=1e-12)
    with pytest.raises(InvalidParameterError, match="SinePlan"):
        bw.cramer_rao(PRIOR, [])


def test_constraints_hold() -> None:
    plan = _plan("bouc_wen", budget=400.0, max_rate=4.0, max_samples_per_period=64, min_periods=7)
    lo, hi = LIMITS["band"]
    assert plan.total_time <= 400.0
    assert plan.total_time == pytest.approx(sum(e.duration for e in plan.experiments))
    for e in plan.experiments:
        assert lo <= e.frequency <= hi
        assert 0 < e.amplitude <= LIMITS["max_amplitude"]
        assert e.amplitude * e.frequency <= 4.0 * (1 + 1e-12)
        assert e.sample_rate <= LIMITS["sample_rate"] * (1 + 1e-12)
        assert 16 <= e.samples_per_period <= 64
        assert e.periods >= 7 and e.settle_periods == LIMITS["settle_periods"]
        expected = LIMITS["overhead"] + (LIMITS["settle_periods"] + e.periods) * 2 * math.pi / e.frequency
        assert e.duration == pytest.approx(expected)
    # The budget is spent down to less than one period of the longest-period experiment used.
    assert 400.0 - plan.total_time < max(2 * math.pi / e.frequency for e in plan.experiments)


def test_target_g_tests_every_grid_frequency_and_spends_the_budget() -> None:
    plan = _plan("G", budget=400.0)
    freqs = [e.frequency for e in plan.experiments]
    # The grid, each point moved onto the lab's rate by less than half a sample in 16 per period.
    np.testing.assert_allclose(freqs, np.geomspace(1.0, 10.0, LIMITS["n_frequencies"]), rtol=1 / 32)
    assert [e.frequency for e in plan.naive.experiments] == freqs  # type: ignore[union-attr]
    assert plan.total_time <= 400.0


def test_the_planner_is_deterministic_and_its_plans_are_seeded() -> None:
    a, b = _plan("bouc_wen"), _plan("bouc_wen")
    assert a.to_dict() == b.to_dict()
    json.dumps(a.to_dict())  # JSON-ready
    seeds1 = [p.seed for p in a.plans(seed=5)]
    assert seeds1 == [p.seed for p in b.plans(seed=5)]
    assert seeds1 != [p.seed for p in a.plans(seed=6)]
    r1 = a.simulate(seed=5)
    r2 = b.simulate(seed=5)
    assert all(np.array_equal(x.y, y.y) for x, y in zip(r1, r2))
    assert not np.array_equal(r1[0].y, a.simulate(seed=6)[0].y)
    assert [r.frequency for r in r1] == [e.frequency for e in a.experiments]
    assert [r.amplitude for r in r1] == [e.amplitude for e in a.experiments]


def test_summary_names_the_design_and_the_gain() -> None:
    plan = _plan("gamma")
    text = str(plan)
    for word in ("target 'gamma'", "beta", "gamma", "mu", "naive", "criterion", "smaller"):
        assert word in text
    assert len(text.splitlines()) == 2 + len(plan.experiments) + 7


@pytest.mark.parametrize(
    ("change", "error", "match"),
    [
        (dict(budget=5.0), InvalidParameterError, "too small for even one experiment"),
        (dict(budget=float("nan")), NonFiniteError, "budget"),
        (dict(budget=-1.0), InvalidParameterError, "budget"),
        (dict(band=(5.0, 5.0)), InvalidParameterError, "empty"),
        (dict(band=(10.0, 1.0)), InvalidParameterError, "empty"),
        (dict(band=(1.0, float("inf"))), NonFiniteError, "band"),
        (dict(band=(1.0,)), InvalidParameterError, "band"),
        (dict(noise_sd=0.0), InvalidParameterError, "noise_sd"),
        (dict(max_amplitude=float("nan")), NonFiniteError, "max_amplitude"),
        (dict(sample_rate=0.5), InvalidParameterError, "samples per period"),
        (dict(target="phase"), InvalidParameterError, "target"),
        (dict(n_frequencies=1), InvalidParameterError, "n_frequencies"),
        (dict(n_frequencies=10**6), InvalidParameterError, "n_frequencies"),
        (dict(n_amplitudes=2.5), InvalidParameterError, "n_amplitudes"),
        (dict(overhead=-1.0), InvalidParameterError, "overhead"),
        (dict(target="G", budget=100.0), InvalidParameterError, "every one of the 6 grid"),
    ],
)
def test_bad_input_is_refused_by_name(change: dict[str, Any], error: type[Exception], match: str) -> None:
    kw = {**LIMITS, "budget": 300.0, **change}
    budget = kw.pop("budget")
    with pytest.raises(error, match=match):
        bw.plan_experiment(PRIOR, budget, **kw)


def test_a_plant_with_terms_or_no_plant_is_refused() -> None:
    with_terms = bw.WienerPlant(PRIOR.linear, PRIOR.hysteresis, (Play(0.05),))
    with pytest.raises(InvalidParameterError, match="without terms"):
        bw.plan_experiment(with_terms, 300.0, **LIMITS)
    with pytest.raises(InvalidParameterError, match="WienerPlant"):
        bw.plan_experiment("plant", 300.0, **LIMITS)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------------
# bouc-wen-id plan
# --------------------------------------------------------------------------------------------------

CLI_LIMITS = [
    "--budget", "300", "--band", "1", "10", "--max-amplitude", "1", "--noise", "0.05",
    "--sample-rate", "100", "--settle-periods", "10", "--frequencies", "6", "--amplitudes", "3",
    "--overhead", "2",
]  # fmt: skip


def test_cli_plan_prints_and_writes_the_plan(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    plant = tmp_path / "plant.json"
    plant.write_text(json.dumps(PRIOR.to_dict()), encoding="utf-8")
    out = tmp_path / "plan.json"
    assert cli.main(["plan", "--plant", str(plant), *CLI_LIMITS, "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "Predicted standard deviations" in printed and f"wrote {out}" in printed
    saved = json.loads(out.read_text(encoding="utf-8"))
    assert saved["format"] == "bouc_wen_id.plan"
    assert saved["design"] == _plan("bouc_wen").design.to_dict()
    # Refuses to replace it without --overwrite.
    assert cli.main(["plan", "--plant", str(plant), *CLI_LIMITS, "--out", str(out)]) == 2
    assert "--overwrite" in capsys.readouterr().err


def test_cli_plan_from_a_result_json_needs_g(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    result = tmp_path / "result.json"
    h = PRIOR.normalized().hysteresis
    result.write_text(
        json.dumps({"format": "bouc_wen_id.result", "beta": h.beta, "gamma": h.gamma, "mu": h.mu}),
        encoding="utf-8",
    )
    assert cli.main(["plan", "--plant", str(result), *CLI_LIMITS]) == 2
    assert "--num/--den" in capsys.readouterr().err
    lin = PRIOR.normalized().linear
    num = [str(v) for v in lin.num]
    den = [str(v) for v in lin.den]
    args = ["plan", "--plant", str(result), "--num", *num, "--den", *den, "--delay", str(lin.delay)]
    assert cli.main([*args, *CLI_LIMITS]) == 0
    # The alpha-normalised prior plans the same design as the plant it came from.
    expected = _plan("bouc_wen").summary().splitlines()[2]
    assert expected in capsys.readouterr().out


def test_cli_plan_refuses_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["plan", "--budget", "5", *CLI_LIMITS[2:]]) == 2
    assert "too small" in capsys.readouterr().err
    assert cli.main(["plan", "--beta", "0.8", *CLI_LIMITS]) == 2
    assert "--num, --den" in capsys.readouterr().err
    bad = tmp_path / "bad.json"
    bad.write_text("[1, 2]", encoding="utf-8")
    with pytest.raises(FileFormatError):
        cli._prior_from_args(cli.build_parser().parse_args(["plan", "--plant", str(bad), *CLI_LIMITS]))


def test_the_labs_sample_rate_is_kept() -> None:
    # The planner turned the lab's 100 Hz into 99.38 Hz (P = 117 at 5.337 rad/s); now the frequency moves.
    plan = _plan("bouc_wen", n_frequencies=12, max_samples_per_period=512)
    for d in (plan.design, plan.naive):
        assert d is not None
        for e in d.experiments:
            ratio = LIMITS["sample_rate"] / e.sample_rate  # a whole decimation factor, 1 where P fits
            assert ratio == pytest.approx(round(ratio), rel=1e-12)
            assert (round(ratio) == 1) == (2 * math.pi * LIMITS["sample_rate"] / e.frequency <= 512 + 1e-6)
    # The simulated record's step is the lab's: 1 / 100 s.
    rec = plan.simulate(seed=1)[0]
    assert np.median(np.diff(rec.t)) == pytest.approx(1.0 / LIMITS["sample_rate"], rel=1e-9)


def test_low_frequencies_are_decimated_whole() -> None:
    # At 1 rad/s and 100 Hz a period holds 628 samples, over the cap of 64: sampled at 100 / d Hz.
    plan = _plan("G", budget=400.0, max_samples_per_period=64)
    for e in plan.experiments:
        d = LIMITS["sample_rate"] / e.sample_rate
        assert d == pytest.approx(round(d), rel=1e-12) and 16 <= e.samples_per_period <= 64


def _readme_planning_example() -> str:
    text = (Path(__file__).resolve().parents[1] / "README.md").read_text(encoding="utf-8")
    section = text[text.index("## Planning an experiment") :]
    start = section.index("```python") + len("```python")
    return section[start : section.index("```", start)]


@pytest.mark.parametrize("target", ["bouc_wen", "beta", "gamma", "mu", "G"])
def test_the_readme_planning_example_runs_with_its_own_numbers(target: str) -> None:
    # It failed for target="G" (budget too small); every target its comment names must run as written.
    code = _readme_planning_example()
    assert 'target="bouc_wen",' in code and f'"{target}"' in code
    code = code.replace('target="bouc_wen",', f'target="{target}",')
    scope: dict[str, Any] = {"bw": bw}
    exec(compile(code, "README.md", "exec"), scope)  # noqa: S102 - the README's own example
    plan = scope["plan"]
    assert plan.target == target and plan.total_time <= plan.budget
    assert plan.improvement is not None and plan.improvement >= 1.0
