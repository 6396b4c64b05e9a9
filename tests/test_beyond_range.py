"""A value just outside a term's physical range is not "not physical" (diagnosis/beyond_range.py; review 36b's
placeflat: a damping 0.46 se below zero was said "not physical (a negative damping)").

Both sides of the rule: within :func:`beyond_range.margin` standard errors of the range the term is neither
named nor called non-physical, and the verdict says it is indistinguishable from zero; beyond them "not
physical" stands, on the single-group rule and on the joint one (across_verdict).
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any

import numpy as np
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import across_verdict as V
from bouc_wen_id.diagnosis import beyond_range
from bouc_wen_id.diagnosis.across import TermAcross
from bouc_wen_id.diagnosis.result import NamedTerm

VISC = T.Viscous.kind


def test_the_margin_is_the_one_sided_wald_point() -> None:
    assert math.isclose(beyond_range.margin(0.05), 1.6448536, rel_tol=1e-6)
    assert beyond_range.margin(0.01) > beyond_range.margin(0.05)


def test_a_value_within_its_uncertainty_of_zero_is_not_clearly_outside() -> None:
    se = 0.01
    for value, clear in ((-0.46 * se, False), (-1.6 * se, False), (-1.7 * se, True), (-5 * se, True)):
        assert beyond_range.clearly_outside(VISC, value, se) is clear, value
        assert beyond_range.within(VISC, value, se) is (not clear), value
    for value in (0.0, 0.3 * se, 10 * se):  # inside the range: neither
        assert not beyond_range.clearly_outside(VISC, value, se) and not beyond_range.within(VISC, value, se)
    # No uncertainty to weigh: any value outside is not physical, as before.
    for se_bad in (math.nan, 0.0, -1.0):
        assert beyond_range.clearly_outside(VISC, -1e-9, se_bad) and not beyond_range.within(
            VISC, -1e-9, se_bad
        )
    assert not beyond_range.clearly_outside(VISC, math.nan, se) and not beyond_range.within(
        VISC, math.nan, se
    )


def test_the_clause_says_indistinguishable_from_zero() -> None:
    t = NamedTerm(VISC, "c", -0.0046, 0.01, "")
    text = beyond_range.text([t])
    assert "not named" in text and "indistinguishable from zero" in text and "-0.0046" in text
    assert "not physical" not in text and beyond_range.text([]) == ""


def _fit(cost: float, terms: tuple[str, ...]) -> Any:
    return SimpleNamespace(cost=cost, params=SimpleNamespace(terms=terms, gains=(1.0, 1.0)))


def _groups(terms: tuple[str, ...]) -> list[Any]:
    sx = [SimpleNamespace(ybar=np.zeros(256)) for _ in range(2)]
    dof = float(2 * 256 - (3 + len(terms) + 4))  # the final structure at the noise floor
    return [
        SimpleNamespace(sx=sx, plain=_fit(5000.0, ()), current=_fit(dof, terms), noise_dof=10**6)
        for _ in range(2)
    ]


def _term(kind: str, values: tuple[float, float], se: float) -> TermAcross:
    return TermAcross(
        kind, T.TERMS[kind].place_label(), "c", "", values, (se, se), (True, True), (0.0, 0.0), (), None
    )


def test_across_a_value_within_its_uncertainty_is_neither_named_nor_non_physical() -> None:
    """placeflat's reading: the damping present at both conditions, at 0.5 and -0.046 +- 0.1 (0.46 se below
    zero). Before, it was said "not physical (a negative damping)"; now it is not named, not non-physical,
    and said within its uncertainty of zero. At -0.3 +- 0.1 (3 se) "not physical" stands."""
    off = _term(T.Offset.kind, (0.1, -0.1), 0.01)
    faint = _term(VISC, (0.5, -0.046), 0.1)
    g = _groups((faint.term, off.term))
    status, named, partial = V.judged(g, [faint, off], 0.05)
    assert named == [off] and partial == [faint] and status == "explained", status
    assert V.unphysical(partial) == []
    near = V.unphysical(partial, clearly=False)
    assert [t.term for t in near] == [VISC] and near[0].value == -0.046
    said = beyond_range.text(near)
    assert "indistinguishable from zero" in said and "not physical" not in said
    clear = _term(VISC, (0.5, -0.3), 0.1)
    status, named, partial = V.judged(_groups((clear.term, off.term)), [clear, off], 0.05)
    assert status == "partly explained" and named == [off] and partial == [clear]
    assert [t.value for t in V.unphysical(partial)] == [-0.3] and V.unphysical(partial, clearly=False) == []
