"""The "adequate" verdict lists the few candidates closest to detection; a user who knows a term is present
(review 33: a 3x term) must learn where that term's own limit is: the verdict names the others and points
to the summary, which lists every candidate's limit (diagnosis/resolution.py, diagnosis/limits.py)."""

from __future__ import annotations

from typing import Any

import pytest
from bouc_wen_id.diagnosis import resolution
from bouc_wen_id.diagnosis.limits import VERDICT_LIMITS, DetectionLimit

TERMS = ("stiffness", "viscous", "inertia", "coulomb", "sensor_lag", "offset", "play")


def _lim(term: str, k: int) -> DetectionLimit:
    return DetectionLimit(
        term=term,
        symbol="v",
        unit="[y]",
        limit=1e-3 * (k + 1),
        limit_90=1.5e-3 * (k + 1),
        value=1e-4 * (len(TERMS) - k),
        standard_error=1e-4,
        level=1e-3,
        one_sided=False,
        absorbed=0.0,
    )


def test_the_verdict_names_the_candidates_it_does_not_list_and_points_to_the_summary(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(resolution, "hint_text", lambda lim, exps: "")
    monkeypatch.setattr(resolution, "resolution_text", lambda d, alpha, unit: "")

    class _D:
        experiments: tuple[Any, ...] = ()

    lims = [_lim(t, k) for k, t in enumerate(TERMS)]
    tail = resolution.adequate_tail(lims, _D(), 0.01)
    assert len(TERMS) > VERDICT_LIMITS
    rest = tail.split("not excluded below")[1]
    for lim in lims:
        assert lim.label in rest, lim.label
    assert f"the other {len(TERMS) - VERDICT_LIMITS} candidates" in tail and "summary" in tail
    few = resolution.adequate_tail(lims[:VERDICT_LIMITS], _D(), 0.01)
    assert "the other" not in few
