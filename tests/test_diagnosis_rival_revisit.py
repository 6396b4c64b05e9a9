"""The revisit of a named single term whose rival fit at least as well but failed its law alone
(diagnosis/rival_revisit.py; review 33: inertia on x beside a sensor lag named as viscous damping on u,
stiffness on u beside play named as viscous damping on x, both "explained").

As in tests/test_diagnosis_revisit.py the selection's inputs are built directly (a cost per set of terms, a
law p per term and set), so that the rule, not a noise draw, decides; select.rebase and select.wide_fit are
stubbed. The plants themselves: /work/review33's mx_lag_30 and play_ku (numbers in the module docstring).
"""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace
from typing import Any, cast

import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import pairs, revisit, rival_revisit, run, select, speed

M, N = 4, 100  # experiments, samples per averaged period
S, A, B = T.Viscous.kind, T.InertiaX.kind, T.SensorLag.kind  # the named single, the rival, its partner
COSTS = {frozenset({A}): 425.0, frozenset({S}): 430.0, frozenset({B}): 470.0, frozenset({A, B}): 395.0}


def _fit(terms: tuple[str, ...], cost: float) -> Any:
    par = SimpleNamespace(terms=terms, values=np.full(len(terms), 0.01), gains=np.ones(M), phases=np.zeros(M))
    return SimpleNamespace(params=par, cost=cost)


Law = Callable[[frozenset[str], str], float]


def _law(holds: tuple[frozenset[str], ...]) -> Law:
    """S's law holds alone; A's fails alone at p 0.005 (above select.PREFERRED_LAW_FLOOR: a rival by fit);
    in each set of ``holds`` every law holds; every other law fails far below."""

    def law(terms: frozenset[str], t: str) -> float:
        if terms == frozenset({S}) or terms in holds:
            return 0.4
        return 0.005 if terms == frozenset({A}) else 1e-6

    return law


def _select(
    monkeypatch: pytest.MonkeyPatch, law: Law, adequate: Callable[[Any], bool] = lambda f: f.cost < 432.0
) -> tuple[Any, list[select.Step]]:
    """revisit.select from a plain fit of cost 500 over S, A, B: S's model is adequate, so the selection
    names S alone and stops (the verdict "explained" by S)."""
    monkeypatch.setattr(speed, "MEMO_FITS", False)

    def fit_with(exps: Any, base: Any, t: str, sub: int) -> Any:
        terms = (*base.params.terms, t)
        return _fit(terms, COSTS.get(frozenset(terms), 1000.0))

    def law_test(exps: Any, fit: Any, t: str, sub: int) -> float:
        return law(frozenset(fit.params.terms), t)

    monkeypatch.setattr(select, "fit_with", fit_with)
    for mod in (select, pairs):
        monkeypatch.setattr(mod, "element_law_test", law_test)
        monkeypatch.setattr(mod, "_separating", lambda exps, fa, fb, sub: "a separating design")
    monkeypatch.setattr(select, "_correlation", lambda fit, a, b: 0.3)
    monkeypatch.setattr(select, "rebase", lambda *a, **k: None)
    monkeypatch.setattr(select, "wide_fit", lambda exps, base, t, sub, first: first)
    exps = [SimpleNamespace(ybar=np.zeros(N), grid_phase=0.0, source=f"e{i}") for i in range(M)]
    return rival_revisit.select(
        cast(Any, exps),
        _fit((), 500.0),
        [S, A, B],
        adequate,
        2,
        use_held_out=False,
        pair_step=pairs.pair_step,
    )


def test_the_named_term_is_replaced_by_its_rival_with_the_partner_whose_laws_hold(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """S named (adequate, its law holds) over A, which fits better but fails its law alone; A with B hold
    their laws jointly, pass adequacy and fit better: named in S's place, S said as the rival; the pair
    step's "none alone fits" clause is not said (S did)."""
    final, steps = _select(monkeypatch, _law((frozenset({A, B}),)))
    assert set(final.params.terms) == {A, B}
    assert len(steps) == 1 and set(steps[0].pair) == {A, B}
    (rec,) = revisit.records(steps)
    assert rec.by_rival and rec.outcome == "named" and rec.replaced == S
    text = revisit.text(steps)
    assert "was named over" in text and "named in its place" in text and "a separating design" in text
    assert pairs.text(steps) == "" and steps[0].to_dict()["pairs"][-1]["by_rival"] is True
    assert "not named" not in run._law_text(steps)


def test_without_it_the_single_stays_named_with_its_rival(monkeypatch: pytest.MonkeyPatch) -> None:
    """Main's selection: S named alone, A only its alternative with the law p."""
    monkeypatch.setattr(rival_revisit, "ENABLED", False)
    final, steps = _select(monkeypatch, _law((frozenset({A, B}),)))
    assert final.params.terms == (S,)
    assert [(a.rival, a.law_p_value) for a in steps[0].alternatives] == [(A, 0.005)]
    assert not revisit.records(steps)


def test_a_set_whose_model_fails_adequacy_is_said_as_another_reading(monkeypatch: pytest.MonkeyPatch) -> None:
    """The set's laws hold but its model is not adequate: S stays named, the set is said (not "explained"
    by S alone without it)."""
    final, steps = _select(
        monkeypatch, _law((frozenset({A, B}),)), lambda f: f.cost < 432.0 and set(f.params.terms) != {A, B}
    )
    assert final.params.terms == (S,)
    (rec,) = revisit.records(steps)
    assert rec.by_rival and rec.outcome.startswith("alternative") and "adequacy" in rec.outcome
    text = revisit.text(steps)
    assert "not the only reading" in text and "a separating design" in text and "cost lower" not in text


def test_no_set_whose_laws_hold_leaves_the_single(monkeypatch: pytest.MonkeyPatch) -> None:
    """Outside physics: no set holds its laws, S stays named with A its alternative, nothing else said."""
    final, steps = _select(monkeypatch, _law(()))
    assert final.params.terms == (S,) and not revisit.records(steps) and revisit.text(steps) == ""
    assert [a.rival for a in steps[0].alternatives] == [A]
