"""``diagnose_across`` runs ``diagnose``'s two revisits of a named single term (diagnosis/across_revisit.py,
through revisit.py, rival_revisit.py and revisit.settle): where a joint step named a term over a rival that
fits at least as well but fails its law alone, the rival with its partner is named in its place when their
laws hold jointly, as each level's own diagnosis names them (review 33's mx_lag_30: inertia on x beside a
sensor lag, named "viscous damping on u").

As in tests/test_diagnosis_rival_revisit.py the joint selection's inputs are built directly (a cost per set of
terms at each condition, a law p per term and set), so that the rule, not a noise draw, decides; the fits'
checks (physical range, null, restarts) are stubbed. The simulated case (the reviewer's plant at two noise
draws) is studies/across_revisit.py's.
"""

from __future__ import annotations

from collections.abc import Callable
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import (
    across,
    across_final,
    across_pairs,
    across_rules,
    across_verdict,
    pairs,
    revisit,
    rival_revisit,
    run,
    select,
    speed,
)

M, N = 4, 100  # experiments per condition, samples per averaged period
S, A, B = T.Viscous.kind, T.InertiaX.kind, T.SensorLag.kind  # the named single, the rival, its partner
#: Each condition's cost per set of terms (1000 when absent): A fits best alone (425) but fails its law;
#: S (430) holds its law and is adequate; A with B (395) hold theirs jointly.
COSTS = {frozenset(): 500.0, frozenset({A}): 425.0, frozenset({S}): 430.0, frozenset({B}): 470.0}
COSTS[frozenset({A, B})] = 395.0


def _fit(terms: tuple[str, ...], costs: dict[frozenset[str], float] = COSTS) -> Any:
    par = SimpleNamespace(terms=terms, values=np.full(len(terms), 0.01), gains=np.ones(M), phases=np.zeros(M))
    return SimpleNamespace(params=par, cost=costs.get(frozenset(terms), 1000.0))


#: The revisit's plant (tests/test_diagnosis_revisit.py's): S named first (not adequate: the limit is 420),
#: then B beside S removes most of what is left (400) but fails its law.
LEAD = {**COSTS, frozenset({S, B}): 400.0}


def _law(holds: tuple[frozenset[str], ...], alone: float = 0.003) -> Callable[[Any, Any, str, int], float]:
    """S's law holds alone; A's fails alone at p ``alone`` at each condition (0.003: 0.006 with Bonferroni
    over the two, above select.PREFERRED_LAW_FLOOR, a rival by fit); every law holds in the sets ``holds``;
    every other fails."""

    def law(exps: Any, fit: Any, t: str, sub: int) -> float:
        terms = frozenset(fit.params.terms)
        if terms == frozenset({S}) or terms in holds:
            return 0.4
        return alone if terms == frozenset({A}) else 1e-6

    return law


def _select(
    monkeypatch: pytest.MonkeyPatch,
    holds: tuple[frozenset[str], ...],
    costs: dict[frozenset[str], float] = COSTS,
    limit: float = 432.0,
    alone: float = 0.003,
) -> tuple[list[Any], list[Any]]:
    """across._select over S, A, B at two conditions from plain fits of cost 500 (each condition's cost per
    set ``costs``); a model is adequate at a condition below cost ``limit`` (432: S's model is, the joint
    selection names S and its targeted step nothing); A's law p alone ``alone`` (:func:`_law`)."""
    monkeypatch.setattr(speed, "MEMO_FITS", False)
    monkeypatch.setattr(select, "fit_with", lambda exps, base, t, sub: _fit((*base.params.terms, t), costs))
    monkeypatch.setattr(select, "wide_fit", lambda exps, base, t, sub, first: first)
    # The final check's refits without a named term (across_final.py), from the same cost table.
    drop = lambda par, t: SimpleNamespace(terms=tuple(x for x in par.terms if x != t))  # noqa: E731
    monkeypatch.setattr(across_final, "without", drop)
    monkeypatch.setattr(across_final, "fit_from", lambda exps, par, sub: _fit(par.terms, costs))
    law = _law(holds, alone)
    for mod in (select, pairs, across_rules):
        monkeypatch.setattr(mod, "element_law_test", law)
    sep = lambda exps, fa, fb, sub: "a separating design"  # noqa: E731
    for mod in (select, pairs, across_rules, across_pairs):
        monkeypatch.setattr(mod, "_separating", sep)
    monkeypatch.setattr(across_rules, "_correlation", lambda fit, a, b: 0.3)
    monkeypatch.setattr(across, "rebase_groups", lambda *a: ())
    for mod in (across, across_pairs):
        monkeypatch.setattr(mod, "_admissible", lambda f, t: True)
        monkeypatch.setattr(mod, "at_null", lambda f, t: False)
        monkeypatch.setattr(mod, "away_from_null", lambda *a: True)
    monkeypatch.setattr(across_pairs, "at_a_limit", lambda sx, f, t: False)
    p_of = lambda g, f: 0.5 if f.cost < limit else 1e-6  # noqa: E731
    monkeypatch.setattr(across_verdict, "p_of", p_of)
    groups = []
    for k in range(2):
        sx: Any = [SimpleNamespace(ybar=np.zeros(N), grid_phase=0.0, source=f"e{i}") for i in range(M)]
        plain = _fit((), costs)
        groups.append(across._Group(f"c{k}", float(k), sx, None, 2, 400, plain, plain))  # type: ignore[arg-type]
    steps = across._select(groups, [S, A, B], 0.05, False, lambda *a: None)
    return groups, steps


def test_the_joint_structure_names_the_rival_with_its_partner_in_place_of_the_single(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """S named jointly over A (which fits better but fails its law alone); A with B hold their laws jointly
    at both conditions and pass adequacy: named in S's place, as diagnose names them (on main the joint
    structure stayed S, A only its alternative)."""
    groups, steps = _select(monkeypatch, (frozenset({A, B}),))
    assert len(steps) == 1 and set(steps[0].pair) == {A, B}, [(s.chosen, s.alternatives) for s in steps]
    assert all(set(g.current.params.terms) == {A, B} for g in groups)
    assert {m.term for m in steps[0].members} == {A, B} and all(all(m.present) for m in steps[0].members)
    (rec,) = revisit.records(steps)
    assert rec.by_rival and rec.outcome == "named" and rec.replaced == S
    said = run._law_text(steps)
    assert "was named over" in said and "named in its place" in said and "a separating design" in said
    assert pairs.text(steps) == "" and steps[0].to_dict()["pairs"][-1]["by_rival"] is True


def test_without_the_rival_revisit_the_single_stays_named(monkeypatch: pytest.MonkeyPatch) -> None:
    """Switched off (main's joint selection): S named, A its alternative with the law p."""
    monkeypatch.setattr(rival_revisit, "ENABLED", False)
    groups, steps = _select(monkeypatch, (frozenset({A, B}),))
    assert steps[0].chosen == S and not steps[0].pair and not revisit.records(steps)
    assert [a.rival for a in steps[0].alternatives] == [A]
    assert all(g.current.params.terms == (S,) for g in groups)


def test_no_set_whose_laws_hold_leaves_the_single(monkeypatch: pytest.MonkeyPatch) -> None:
    """Outside physics: no set holds its laws jointly; S stays named, nothing said of a revisit."""
    groups, steps = _select(monkeypatch, ())
    assert steps[0].chosen == S and not steps[0].pair and not revisit.records(steps)
    assert revisit.text(steps) == "" and all(g.current.params.terms == (S,) for g in groups)


def test_a_single_whose_later_lead_fails_its_law_is_revisited_across(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """diagnose's revisit (revisit.py) on the joint steps: S named at step 1 (its model not adequate), B
    beside it removes most of what is left but fails its law at step 2; A with B hold their laws jointly and
    pass adequacy: named in S's place (on main: S named, "explained in part", B law-failed)."""
    groups, steps = _select(monkeypatch, (frozenset({A, B}),), LEAD, 420.0, 1e-6)
    assert len(steps) == 1 and set(steps[0].pair) == {A, B}, [(s.chosen, s.law_failed) for s in steps]
    assert all(set(g.current.params.terms) == {A, B} for g in groups)
    (rec,) = revisit.records(steps)
    assert rec.outcome == "named" and rec.replaced == S and not rec.by_rival
    assert "revisited" in run._law_text(steps) and "a separating design" in run._law_text(steps)
