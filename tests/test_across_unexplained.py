"""Review 38 item 4: diagnose-across named nothing on an MR damper whose every condition failed its adequacy
test (chi2/dof 1830-3280) and said only "nothing named"; the status was "unexplained" and diagnose says so
in its first words. The words come from across_verdict.head, where the across status words are made."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any, cast

from bouc_wen_id.diagnosis import across, across_said, across_verdict


def test_nothing_named_and_not_adequate_says_unexplained_first() -> None:
    conds = cast(Any, [SimpleNamespace(label=str(v)) for v in (0, 0.5, 1)])
    steps = cast(Any, [SimpleNamespace(trials=("tried",), alternatives=())])
    v = across._verdict([], conds, steps)
    assert v.startswith(
        f"across 3 conditions: {across_verdict.UNEXPLAINED}; nothing named (no candidate passes"
    )
    assert v == across_verdict.head("unexplained", (), 3, 0.0) + across_said.NOTHING
    # No candidate tested at all: the same status words, the other reason.
    v = across._verdict([], conds, cast(Any, [SimpleNamespace(trials=(), alternatives=())]))
    assert v.endswith("; nothing named (no candidate tested)") and across_verdict.UNEXPLAINED in v
