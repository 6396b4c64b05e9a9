"""Detection limits (diagnosis/limits.py): what the experiments could not have seen, and its calibration.

Data from the diagnosis bench's own generator (benches/generator.py: G solved exactly, its own RK4 of the
hysteresis and of a first-order sensor lag, its own seeded noise), not from the library's simulator.
"""

from __future__ import annotations

import importlib
import json
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis.limits import most_relevant
from bouc_wen_id.diagnosis.report import html_page

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
#: The bench's generator, a script beside the package (not an installed module).
gen: Any = importlib.import_module("generator")

SEED = 9101
#: Two candidates keep each diagnosis short; the limit is computed at their own Bonferroni level.
CANDIDATES = ("sensor_lag", "viscous@x")


def _diagnose(recs: list[Any], candidates: Any = CANDIDATES) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs, candidates=candidates)


@pytest.fixture(scope="module")
def plant() -> tuple[Any, Any]:
    p = gen.make_plant(SEED, shape="resonant")
    return p, gen.base(p)


@pytest.fixture(scope="module")
def null(plant: tuple[Any, Any]) -> Any:
    p, b = plant
    return _diagnose(gen.recordings(p, gen.run(p, gen.Effect(), shared=b)[0], 1))


def test_every_fitted_candidate_has_a_finite_positive_limit(null: Any) -> None:
    assert null.steps, "the targeted step must have run on the plain data"
    fitted = {t.term for t in null.steps[0].trials if t.fit is not None}
    assert fitted == set(CANDIDATES)
    by_term = {lim.term: lim for lim in null.limits}
    for term in fitted:
        lim = by_term[term]
        assert math.isfinite(lim.limit) and lim.limit > 0, lim
        assert lim.limit_90 > lim.limit
        assert 0.0 < lim.level < float(null.settings["alpha"])
        # named at its place (named_limit.py): not below its test's own 90 % value; the rival, if any (one
        # taking the trace only outside its physical range is none), is the other candidate
        assert lim.named_90 >= lim.limit_90 and lim.rival in {""} | (set(CANDIDATES) - {term}), lim


def test_to_dict_and_json_carry_the_limits(null: Any) -> None:
    js = json.loads(null.to_json())
    got = {e["term"]: e for e in js["detection_limits"]}
    assert set(got) == set(CANDIDATES)
    for lim in null.limits:
        assert got[lim.term]["limit"] == pytest.approx(lim.limit)
        assert got[lim.term]["limit_90"] == pytest.approx(lim.limit_90)
        assert got[lim.term]["unit"] == lim.unit
    assert "detection limits" in null.summary()
    page = html_page(null, {})
    assert "Detection limits" in page and all(lim.label in page for lim in null.limits)


def test_an_adequate_verdict_names_what_it_could_not_have_seen(null: Any) -> None:
    assert null.status == "adequate", null.verdict
    assert "not excluded below" in null.verdict
    for lim in most_relevant(null.limits):
        assert lim.label in null.verdict


def _sensor_lag_rate(plant: tuple[Any, Any], tau: float, draws: int) -> float:
    """Share of noise draws at a true sensor lag ``tau`` (seconds) whose diagnosis names the sensor lag."""
    p, b = plant
    y = gen.run(p, gen.Effect("sensor_lag", "", np.array([tau])), shared=b)[0]
    hits = [_diagnose(gen.recordings(p, y, 100 + j)).named_terms == ("sensor_lag",) for j in range(draws)]
    return float(np.mean(hits))


def test_the_limit_is_calibrated_on_a_sensor_lag(plant: tuple[Any, Any], null: Any) -> None:
    """At 2x the reported 50 %-power limit a sensor lag is named far more often than at 0.5x: the limit
    says where the design's power is, on data the library did not make."""
    lim = next(x for x in null.limits if x.term == "sensor_lag")
    low = _sensor_lag_rate(plant, 0.5 * lim.limit, 10)
    high = _sensor_lag_rate(plant, 2.0 * lim.limit, 10)
    assert low <= 0.3, (low, high)
    assert high >= 0.7, (low, high)
