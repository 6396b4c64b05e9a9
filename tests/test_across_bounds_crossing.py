"""A value beyond its physical range at some conditions only is said there only (review 35m, F7).

Three conditions of a stiffness on u at -0.045, -0.015 and +0.03 (review 35m's ``across_mine.py ksign``):
the across verdict said "k = -0.04787, -0.01852, 0.03049 ... beyond its physical range" at all three and
that the kept terms stand in for it everywhere, though +0.0305 is physical (the single diagnosis at that
condition names it). Now it says at which conditions the value lies beyond the range, that it crosses zero
between them, and the kept terms stand in for it at those conditions only; a value beyond the range at
every condition reads as before.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import across_bounds

KIND = T.Stiffness.kind
LABEL = T.TERMS[KIND].place_label()


def _fit(v: float) -> Any:
    params = SimpleNamespace(terms=(KIND,), values=np.array([v]), mu=1.0)
    return SimpleNamespace(params=params, standard_error=lambda term: 0.003)


def _said(values: list[float]) -> str:
    scale = SimpleNamespace(factor=lambda term, mu: 1.0, y=1.0)
    groups = [SimpleNamespace(label=f"c{i}", scale=scale) for i in range(len(values))]
    tr = SimpleNamespace(term=KIND, fits=[_fit(v) for v in values], share=1.0, p_adjusted=1e-90)
    b = across_bounds.BeyondAcross((tr,), True)
    return across_bounds.text(b, groups, ("[u]", "[y]"), 0.41, ["sensor lag"])


def test_a_value_crossing_zero_is_beyond_its_range_only_where_negative() -> None:
    said = _said([-0.048, -0.0185, 0.0305])
    assert "beyond its physical range at c0, c1 only (within it at c2" in said, said
    assert "crosses zero" in said, said
    assert "stand in for it at c0, c1, not named" in said, said
    assert "beyond its physical range:" not in said, said


def test_a_value_beyond_its_range_everywhere_reads_as_before() -> None:
    said = _said([-0.048, -0.0185, -0.03])
    assert f"{LABEL} k = -0.048, -0.0185, -0.03" in said, said
    assert "beyond its physical range:" in said and "only (within" not in said, said
    assert "stand in for it, not named" in said, said
