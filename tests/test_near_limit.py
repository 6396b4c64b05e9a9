"""A value named near its detection limit carries the selection-bias note (review 36 problem 6: a term is
named when its draw is high; cu_sub, c = 0.0003 below its 50 % limit 0.0004, named 2 of 9 draws, both above
the truth)."""

from __future__ import annotations

import math

from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import near_limit
from bouc_wen_id.diagnosis.limits import DetectionLimit
from bouc_wen_id.diagnosis.result import NamedTerm

C_U = T.Viscous.kind
OFFSET = T.Offset.kind


def _lim(term: str, limit: float) -> DetectionLimit:
    return DetectionLimit(term, "c", "s", limit, 1.4 * limit, 0.0, 0.1 * limit, 0.01, False, 0.0)


def test_a_value_within_twice_its_50_percent_limit_is_said_biased() -> None:
    lim = 0.0004
    lims = [_lim(C_U, lim), _lim(OFFSET, -lim)]
    near = NamedTerm(C_U, "c", near_limit.NEAR * 0.9 * lim, 0.3 * lim, "s")
    got = near_limit.text([near], lims)
    assert near_limit.MARK in got and "biased" in got and got.startswith("; ")
    assert f"{near.value:.4g}" in got and f"{lim:.2g}" in got
    # Far above its limit: a tail draw there is not selection, and nothing is said.
    far = NamedTerm(C_U, "c", near_limit.NEAR * 1.1 * lim, 0.3 * lim, "s")
    assert near_limit.text([far], lims) == ""
    # A negative value is judged by its magnitude, against a limit of either sign.
    neg = NamedTerm(OFFSET, "y0", -1.5 * lim, 0.3 * lim, "")
    assert near_limit.MARK in near_limit.text([neg], lims)
    # No finite limit, or no limit for the term: nothing said.
    assert near_limit.text([near], [_lim(C_U, math.inf)]) == ""
    assert near_limit.text([near], []) == ""
    # Each near term says its own clause.
    assert near_limit.text([near, neg], lims).count(near_limit.MARK) == 2
