"""A term whose place differs between conditions is said so, not as an active element (review 36b, 1).

Viscous damping on u at condition 0 and across the hysteretic element (on x) at 0.5 and 1: the joint
search, one place shared by every condition, fitted it on x everywhere, negative at 0 (c = -0.00097,
0.0101, 0.00999), and the verdict read "energy supplied each cycle: an active element ... or a phase error".
Its first step's trial of the same physics on u fits condition 0 with a physical value and removes more
there: the verdict now says the place differs between the conditions, with each condition's value at its
place, and names no active element. Without such a sibling fit the old reading stands.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import across_bounds, across_moved, bounds_said
from bouc_wen_id.diagnosis.select import siblings

ON_U = T.Viscous.kind
ON_X = siblings(ON_U)[0]


def _fit(term: str, v: float) -> Any:
    params = SimpleNamespace(terms=(term,), values=np.array([v]), mu=1.0)
    return SimpleNamespace(params=params, standard_error=lambda term: 1e-4, cost=100.0)


def _said(monkeypatch: pytest.MonkeyPatch, on_u: list[float], imp_u: list[float]) -> str:
    monkeypatch.setattr(across_moved, "dof_of", lambda sx, f: 100)
    scale = SimpleNamespace(factor=lambda term, mu: 1.0, y=1.0)
    groups = [SimpleNamespace(label=lab, scale=scale, sx=()) for lab in ("0", "0.5", "1")]
    tr = SimpleNamespace(
        term=ON_X,
        fits=[_fit(ON_X, v) for v in (-0.00097, 0.01012, 0.009991)],
        improvements=[53.0, 9760.0, 9547.0],
        share=0.74,
        p_adjusted=0.0,
    )
    sib = SimpleNamespace(term=ON_U, fits=[_fit(ON_U, v) for v in on_u], improvements=imp_u)
    steps = [SimpleNamespace(trials=(sib, tr), level=0.01)]
    b = across_bounds.BeyondAcross((tr,), False)
    return across_bounds.text(b, groups, ("[y]", "[u]"), 0.0, [], steps)


def test_the_other_place_fitting_where_unphysical_is_said(monkeypatch: pytest.MonkeyPatch) -> None:
    said = _said(monkeypatch, [0.0099, 0.001, 0.002], [6716.0, 1753.0, 1967.0])
    assert "the place of viscous damping differs between the conditions" in said, said
    assert f"{T.TERMS[ON_U].acts_on.label} at 0 (c = 0.0099" in said, said
    assert f"{T.TERMS[ON_X].acts_on.label} at 0.5, 1 (c = 0.01012, 0.009991" in said, said
    assert bounds_said._suggests(ON_X) not in said and "active element" not in said, said


@pytest.mark.parametrize(
    ("on_u", "imp_u"),
    [([-0.002, 0.001, 0.002], [6716.0, 1753.0, 1967.0]), ([0.0099, 0.001, 0.002], [20.0, 1753.0, 1967.0])],
)
def test_without_a_physical_better_fit_at_the_other_place_the_old_reading_stands(
    monkeypatch: pytest.MonkeyPatch, on_u: list[float], imp_u: list[float]
) -> None:
    said = _said(monkeypatch, on_u, imp_u)
    assert "differs between the conditions" not in said, said
    assert "beyond its physical range at 0 only" in said and bounds_said._suggests(ON_X) in said, said
