"""The rivals a detection plan models are the diagnosis's own: the candidates it will be given, each at its
own critical value; and the chance's draws come from a seed the user sets.

- ``candidates=1`` (``diagnose(candidates=[term])``) changed the critical value but nine linear rivals were
  still modelled; now the rivals follow the candidate list (a count, or the names the diagnosis is given).
- A rival was tested at the term's critical value (a sensor lag's one-sided 2.955) although the diagnosis
  tests a rival whose range is not confined to ``>= 0`` two-sided (3.163 at the same level).
- ``plan_detection(seed=...)`` and ``plan --seed`` set the naming draws' seed (it was always 0).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id import cli
from bouc_wen_id.diagnosis.candidates import step_candidates
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.planning import PlannedExperiment, _naming, _power, detection_power, naming_chance
from bouc_wen_id.planning._naming import linear_rivals
from bouc_wen_id.terms import TERMS

PRIOR = bw.demo_plant()
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


def _design() -> list[PlannedExperiment]:
    return [
        PlannedExperiment(w, 1.0, 300, int(round(100.0 * 2.0 * math.pi / w)), 10) for w in (2.0, 5.0, 9.0)
    ]


def test_one_candidate_models_no_rival() -> None:
    design = _design()
    alone = naming_chance(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05, candidates=1)
    assert alone.rivals == () and alone.rival_named == 0.0
    named = naming_chance(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05, candidates=["sensor_lag"])
    assert named.rivals == () and named.chance == alone.chance
    full = naming_chance(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05)
    assert full.rivals and full.rivals == linear_rivals("sensor_lag", step_candidates(pure_sines=True))


def test_the_rivals_follow_the_names_given() -> None:
    rival = next(t for t in linear_rivals("sensor_lag", list(TERMS)))
    n, rv = _naming.family("sensor_lag", ["sensor_lag", rival])
    assert n == 2 and rv == (rival,)
    with pytest.raises(InvalidParameterError, match="do not include"):
        _naming.family("sensor_lag", [rival])
    plan = bw.plan_detection(PRIOR, 100.0, {"sensor_lag": 0.01}, candidates=["sensor_lag", rival], **LAB)
    assert plan.naming is not None and plan.naming.rivals == (rival,)
    assert plan.settings["candidates"] == 2


def test_each_rival_is_tested_at_its_own_critical_value() -> None:
    design = _design()
    pw = detection_power(PRIOR, design, "sensor_lag", 0.01, noise_sd=0.05)
    rivals = linear_rivals("sensor_lag", list(TERMS))
    lin, _, rv = _naming._setup(PRIOR, design, "sensor_lag", 0.01, pw, 0.05, 8, rivals, 16, 100, 0)
    assert lin.z_c == (pw.z_c, *(_power.z_critical(t, pw.level) for t in rv))
    two_sided = [t for t in rv if TERMS[t].bounds[0] != 0.0]
    assert two_sided and all(lin.z_c[1 + rv.index(t)] > pw.z_c for t in two_sided)


def test_the_seed_is_the_users(tmp_path: Path) -> None:
    plan = bw.plan_detection(PRIOR, 100.0, {"sensor_lag": 0.01}, seed=7, **LAB)
    assert plan.naming is not None and plan.naming.seed == 7 and plan.settings["seed"] == 7
    with pytest.raises(InvalidParameterError, match="seed"):
        bw.plan_detection(PRIOR, 100.0, {"sensor_lag": 0.01}, seed=-1, **LAB)
    out = tmp_path / "plan.json"
    argv = ["plan", "--budget", "100", "--band", "2", "12", "--max-amplitude", "1.5", "--noise", "0.01"]
    argv += ["--sample-rate", "200", "--max-samples-per-period", "64", "--frequencies", "6"]
    argv += ["--amplitudes", "2", "--settle-periods", "10", "--detect", "sensor_lag=0.01", "--seed", "7"]
    assert cli.main([*argv, "--out", str(out)]) == 0
    got = json.loads(out.read_text())
    assert got["naming"]["seed"] == 7 and got["naming"]["chance"] == plan.naming.chance
