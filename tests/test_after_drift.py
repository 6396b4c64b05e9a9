"""The targeted step after a named drift term (after_named.drift_targeted; review rv35m F12 note): once a
drift correction is accepted and the corrected steady model passes the global test, a steady term beside
the drift term still gets its targeted step (and so its detection limit), as beside any named term."""

from __future__ import annotations

import math
from typing import Any

import pytest
from bouc_wen_id.diagnosis import after_named
from bouc_wen_id.diagnosis.select import Step

START: Any = object()  # a stand-in fit (forward_select is stubbed)
ALPHA = 0.05


def test_the_gate_needs_a_named_drift_term_measured_noise_and_a_passing_start() -> None:
    ok = 0.9  # a corrected start's global p well above alpha / 2
    assert after_named.drift_targeted(True, True, ok, ALPHA)
    assert not after_named.drift_targeted(False, True, ok, ALPHA)  # no drift term named: the plain gate's
    assert not after_named.drift_targeted(True, False, ok, ALPHA)  # a floored noise: no targeted step
    assert not after_named.drift_targeted(True, True, 0.4 * ALPHA, ALPHA)  # fails: an ordinary step runs
    assert not after_named.drift_targeted(True, True, math.nan, ALPHA)
    assert after_named.drift_targeted(True, True, 0.5 * ALPHA, ALPHA)  # the gate's own level, alpha / 2


def test_after_a_drift_term_the_first_step_is_the_targeted_one_after_a_named_term(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    calls: list[tuple[bool, bool]] = []

    def fake(exps: Any, start: Any, cands: Any, adequate: Any, substeps: int, **kw: Any) -> Any:
        calls.append((bool(kw["targeted"]), bool(kw.get("after_named", False))))
        return start, [Step(1.0, 1, (), None)]

    def stop(fit: Any) -> bool:
        return True

    monkeypatch.setattr(after_named, "forward_select", fake)
    # again False (a named drift term moved the loop): before, one untargeted call that stopped at once.
    after_named.select([], START, [], stop, lambda f: 1.0, 1, False, False, True, alpha=ALPHA)
    assert calls == [(True, True)]  # its candidates at alpha / 10 (gate.targeted_level)
    calls.clear()
    after_named.select([], START, [], stop, lambda f: 1.0, 1, False, False, False, alpha=ALPHA)
    assert calls == [(False, False)]  # no drift term named: unchanged
