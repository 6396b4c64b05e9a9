"""A step that names nothing because its best candidate's law failed near the test's level says that the
term itself, refused by chance, is one reading (diagnosis/law_chance.py); and the bench's oracle
(benches/oracle.py) tells an undetectable miss from a refused law, a rejected truth and a search failure.

The selection's inputs are built directly (fits with set costs, a law p per term), as in
test_diagnosis_law_alternatives.py, so that the rule decides, not a noise draw.
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import Any, cast

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import law_chance, run, select, speed

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")
oracle: Any = importlib.import_module("oracle")

M, N = 4, 100  # experiments, samples per averaged period


def _fit(terms: tuple[str, ...], cost: float) -> Any:
    par = SimpleNamespace(terms=terms, values=np.full(len(terms), 0.01), gains=np.ones(M), phases=np.zeros(M))
    return SimpleNamespace(params=par, cost=cost)


def _steps(monkeypatch: pytest.MonkeyPatch, costs: dict[str, float], law: dict[str, float]) -> Any:
    """The targeted first step (the global test accepted the plain model, cost 390 on dof 389) over
    ``costs``' candidates, each term's law p from ``law`` (0.5 when absent)."""
    monkeypatch.setattr(speed, "MEMO_FITS", False)
    monkeypatch.setattr(
        select, "fit_with", lambda exps, base, t, sub: _fit((*base.params.terms, t), costs[t])
    )
    monkeypatch.setattr(select, "element_law_test", lambda exps, fit, t, sub: law.get(t, 0.5))
    monkeypatch.setattr(select, "_correlation", lambda fit, a, b: 0.3)
    monkeypatch.setattr(select, "_separating", lambda exps, fa, fb, sub: "a separating design")
    monkeypatch.setattr(select, "rebase", lambda *a, **k: None)
    monkeypatch.setattr(select, "wide_fit", lambda exps, base, t, sub, first: first)
    exps = [SimpleNamespace(ybar=np.zeros(N), grid_phase=0.0, source=f"e{i}") for i in range(M)]
    _, steps = select.forward_select(
        cast(Any, exps), _fit((), 390.0), list(costs), lambda f: True, 2, use_held_out=False, targeted=True
    )
    return steps


COSTS = {"sensor_lag": 365.0, "coulomb@x": 389.5, "offset": 389.9}


def test_a_best_candidate_refused_near_the_laws_level_is_said_to_be_possibly_the_term(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Sensor lag removes chi2 25 in the targeted step, nothing else passes, its law p = 0.0076 (the bench's
    sensor lag 10x seed 35004): nothing is named, and the verdict says the lag itself, refused by chance, is
    a reading, with the experiment that separates it from physics outside the library."""
    steps = _steps(monkeypatch, COSTS, {"sensor_lag": 0.0076})
    assert steps[0].chosen is None and steps[0].law_failed == ("sensor_lag",)
    assert law_chance.by_chance(steps) == {"sensor_lag": 0.0076}
    text = run._law_text(steps)
    assert "not named: sensor lag (p = 0.0076)" in text
    assert "its law refused by chance" in text and "repeat the same experiments" in text


def test_a_law_far_below_the_truths_range_keeps_the_stand_in_reading_alone(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A law p of 1e-5 (below select.PREFERRED_LAW_FLOOR: the truth's law p never fell so low in the 1798
    calibration cases) is no chance refusal: the verdict keeps "stands in for physics outside the library"
    alone."""
    steps = _steps(monkeypatch, COSTS, {"sensor_lag": 1e-5})
    assert steps[0].chosen is None
    assert law_chance.by_chance(steps) == {}
    text = run._law_text(steps)
    assert "stands in for physics outside the library" in text and "by chance" not in text


def test_no_chance_clause_where_a_term_is_named_or_the_refused_one_is_not_the_best() -> None:
    """A step that named a term says nothing of chance (the refused one is its alternative or a worse fit);
    a refused candidate that fits worse than another passed one is not the step's best reading."""
    lag = select.Trial("sensor_lag", 380.0, 10.0, 10.0, 1e-3, 0.01, 1.0, True, law_p_value=0.005)
    other = select.Trial("coulomb@x", 370.0, 20.0, 20.0, 1e-5, 1e-4, 1.0, True, law_p_value=0.004)
    named = SimpleNamespace(trials=(lag,), chosen="offset", law_failed=("sensor_lag",), pair=())
    assert law_chance.by_chance([named]) == {}
    worse = SimpleNamespace(trials=(lag, other), chosen=None, law_failed=("sensor_lag",), pair=())
    assert law_chance.by_chance([worse]) == {}
    both = SimpleNamespace(trials=(lag, other), chosen=None, law_failed=("sensor_lag", "coulomb@x"), pair=())
    assert law_chance.by_chance([both]) == {"coulomb@x": 0.004}


def test_the_oracle_sorts_a_miss_by_its_cause() -> None:
    """Right cases have no cause; a miss is undetectable before anything else, then a refused law, then a
    rejected truth, then a local minimum (the step's trial of the truth above the oracle's fit), else
    search. The row's columns: detectable share, right among the detectable, causes counted, and the old
    right rate is not the one computed here."""
    base = {"right_place": False, "lr_detectable": True, "truth_law_p": 0.5, "truth_p": 0.5, "trial_gap": 0.0}
    assert oracle.cause({**base, "right_place": True}) == ""
    assert oracle.cause({**base, "lr_detectable": False, "truth_law_p": 0.001}) == "undetectable"
    assert oracle.cause({**base, "truth_law_p": 0.0076, "truth_p": 0.001}) == "law refused"
    assert oracle.cause({**base, "truth_p": 0.011}) == "truth rejected"
    assert oracle.cause({**base, "trial_gap": 5.0}) == "local minimum"
    assert oracle.cause(base) == "search"
    assert oracle.cause({"right_place": False}) == ""  # no oracle numbers: not scored
    rows = [{**base, "right_place": True} for _ in range(3)]
    rows += [{**base, "lr_detectable": False}, {**base, "truth_law_p": 0.002}]
    got = oracle.columns(rows)
    assert got["lr_det"] == pytest.approx(4 / 5) and got["right_lr"] == pytest.approx(3 / 4)
    assert got["causes"] == {"undetectable": 1, "law refused": 1}


def test_a_miss_seen_by_the_truths_test_alone_is_below_the_search_level_not_undetectable() -> None:
    """The bench's "undetectable" is kept for a truth whose own F test fails even alone (no Bonferroni);
    one that passes alone at the step's level but not after the Bonferroni over the step's candidates is
    "below search level" (sensor lag 10x seed 35014: raw p 0.0027 at level 0.025, 16 candidates). Without
    the raw p (an old row) it stays "undetectable"."""
    base = {"right_place": False, "lr_detectable": False, "truth_law_p": 0.5, "truth_p": 0.5}
    base["lr_level"] = 0.025
    assert oracle.cause({**base, "lr_p": 0.0027, "lr_p_adj": 0.043}) == "below search level"
    assert oracle.cause({**base, "lr_p": 0.2, "lr_p_adj": 1.0}) == "undetectable"
    assert oracle.cause(base) == "undetectable"
    rows = [{**base, "lr_p": 0.0027, "power_search": 0.8}, {**base, "lr_p": 0.2, "power_search": 0.6}]
    got = oracle.columns(rows)
    assert got["causes"] == {"below search level": 1, "undetectable": 1}
    assert got["power_search"] == pytest.approx(0.7)


@pytest.mark.parametrize("boundary", [False, True])
def test_the_oracle_power_is_the_rejection_rate_of_its_test(boundary: bool) -> None:
    """``oracle.powers`` against the test it stands for, drawn: the step's statistic at non-centrality lam
    (a unit normal shifted by sqrt(lam); squared and two-sided, or one-sided with half the p for a term
    bounded at 0), rejected at the level alone and at the level over the candidates. At lam = 0 the power is
    the level; it grows with lam; the search's is below the test alone's."""
    from scipy.stats import chi2, norm  # type: ignore[import-untyped]

    rng = np.random.default_rng(35)
    level, cands, lam = 0.025, 16, 17.1
    z = rng.standard_normal(200_000) + math.sqrt(lam)
    if boundary:
        drawn = [float(np.mean(z > norm.isf(a))) for a in (level, level / cands)]
    else:
        drawn = [float(np.mean(z**2 > chi2.isf(a, 1))) for a in (level, level / cands)]
    alone, search = oracle.powers(lam, level, cands, boundary)
    assert alone == pytest.approx(drawn[0], abs=0.005) and search == pytest.approx(drawn[1], abs=0.005)
    assert search < alone < 1.0
    assert oracle.powers(0.0, level, cands, boundary)[0] == pytest.approx(level)
    assert oracle.powers(30.0, level, cands, boundary)[1] > search
    assert all(math.isnan(v) for v in oracle.powers(math.nan, level, cands, boundary))


def _diagnose(recordings: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recordings)


def test_the_oracle_on_a_plain_plant_and_on_a_large_sensor_lag() -> None:
    """On benches/generator.py's records (its own G and RK4): a 30x sensor lag is detectable by the true
    model's LR test, its gain is the diagnosis's own step-1 improvement (no local minimum: trial gap ~ 0) and
    its law p is a p-value; on the same kind of plant with no effect, the truth "sensor lag" gains too little
    to be detected. A drift term has no steady oracle."""
    case = gen.make_case("library", "sensor_lag", "", 30.0, 36001)
    d = _diagnose(case.recordings)
    got = oracle.truth_lr(d, "sensor_lag")
    trial = next(t for t in d.steps[0].trials if t.term == "sensor_lag")
    assert got["lr_detectable"] and got["lr_p_adj"] < got["lr_level"]
    assert got["lr_gain"] >= trial.improvement - oracle.LOCAL_TOL and got["trial_gap"] <= oracle.LOCAL_TOL
    assert 0.0 <= got["truth_law_p"] <= 1.0 and 0.0 <= got["truth_p"] <= 1.0
    assert oracle.truth_lr(d, "degradation") == {} and oracle.truth_lr(d, None) == {}
    p = gen.make_plant(36001)
    plain = _diagnose(gen.recordings(p, gen.run(p, gen.Effect())[0], 36001))
    none = oracle.truth_lr(plain, "sensor_lag")
    assert not none["lr_detectable"] and none["lr_gain"] < got["lr_gain"]
    assert math.isfinite(none["lr_p_adj"])
