"""diagnosis/prefetch.py: a step's candidate fits on threads give what the loop gave, in its order."""

from __future__ import annotations

import contextvars
import threading
import time
import warnings

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
    said: list[tuple[int, str]] = []
    try:
        out = prefetch.in_order(_slow, ["a", "b", "c", "d"], lambda k, t: said.append((k, t)))
    finally:
        _VAR.reset(token)
    assert [o[0] for o in out] == ["a", "b", "c", "d"]
    assert said == [(0, "a"), (1, "b"), (2, "c"), (3, "d")]  # progress in the loop's order
    assert all(o[1] == "scope" for o in out)  # fit_share.scope's store is seen in every thread
    main = threading.get_ident()
    assert any(o[2] != main for o in out) == threads


def test_an_error_is_raised_and_the_rest_dropped(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(speed, "THREAD_CANDIDATE_FITS", True)
    monkeypatch.setattr("os.cpu_count", lambda: 2)

    def fit(t: str) -> str:
        if t == "b":
            raise ValueError("b failed")
        return t

    with pytest.raises(ValueError, match="b failed"):
        prefetch.in_order(fit, ["a", "b", "c"])


def test_the_callers_warning_filters_survive_threads_that_silence_their_own(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Each fit wraps itself in ``catch_warnings`` (fitting.py); interleaved on threads they restore each
    other's filter lists. After the step the caller's filters are its own again."""
    monkeypatch.setattr(speed, "THREAD_CANDIDATE_FITS", True)
    monkeypatch.setattr("os.cpu_count", lambda: 4)
    barrier = threading.Barrier(4)

    def fit(t: str) -> str:
        k = "abcd".index(t)
        time.sleep(0.02 * k)  # enter in order a, b, c, d ...
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            barrier.wait(timeout=5)
            time.sleep(0.02 * k)  # ... and leave in the same order: b, c, d restore lists a put in place
        return t

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        before = list(warnings.filters)
        assert prefetch.in_order(fit, ["a", "b", "c", "d"]) == ["a", "b", "c", "d"]
        assert warnings.filters == before
        with pytest.raises(UserWarning):
            warnings.warn("still raised", UserWarning, stacklevel=1)
