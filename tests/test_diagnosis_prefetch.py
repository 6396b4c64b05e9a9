"""diagnosis/prefetch.py: a step's candidate fits on threads give what the loop gave, in its order."""

from __future__ import annotations

import contextvars
import threading
import time

import pytest
from bouc_wen_id.diagnosis import prefetch, speed

_VAR: contextvars.ContextVar[str] = contextvars.ContextVar("_VAR", default="unset")


def _slow(t: str) -> tuple[str, str, int]:
    time.sleep(0.02 if t == "a" else 0.0)  # the first finishes last
    return t, _VAR.get(), threading.get_ident()


@pytest.mark.parametrize("threads", [False, True])
def test_results_in_order_with_the_callers_context(threads: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(speed, "THREAD_CANDIDATE_FITS", threads)
    monkeypatch.setattr("os.cpu_count", lambda: 2)
    token = _VAR.set("scope")
    try:
        out = list(prefetch.in_order(_slow, ["a", "b", "c", "d"]))
    finally:
        _VAR.reset(token)
    assert [o[0] for o in out] == ["a", "b", "c", "d"]
    assert all(o[1] == "scope" for o in out)  # fit_share.scope's store is seen in every thread
    main = threading.get_ident()
    assert any(o[2] != main for o in out) == threads


def test_an_error_is_raised_at_its_turn(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(speed, "THREAD_CANDIDATE_FITS", True)
    monkeypatch.setattr("os.cpu_count", lambda: 2)

    def fit(t: str) -> str:
        if t == "b":
            raise ValueError("b failed")
        return t

    got = []
    with pytest.raises(ValueError, match="b failed"):
        for r in prefetch.in_order(fit, ["a", "b", "c"]):
            got.append(r)
    assert got == ["a"]
