"""Loops that have not settled, across conditions: ``diagnose_across`` leaves them out as ``diagnose`` does.

:func:`.run.diagnose` tests every experiment's loop for a drift from period to period beyond the noise
(:func:`.settling._unsettled`) and, unless degradation explains it, leaves the drifting experiments out
(:func:`.settling.settled_only`), saying which; when none is settled it names nothing (issue 18: "a loop that
has not settled is not physics"). ``diagnose_across`` fitted every experiment of every condition: a
low-amplitude loop still settling its centre at one condition left a misfit the joint selection read as
structure. Here the same rule per condition:

- given the condition's own diagnosis, the experiments it left out (recorded in its ``settings`` under
  :data:`.settling.LEFT_OUT`) stay out (its experiments and plain fit are the settled ones);
- without it, :func:`.settling.settled_only` on the condition's prepared experiments; when some drift,
  the condition's own judgement of the drift, as diagnose makes it (:func:`degrades`: ``diagnose`` of that
  condition with the candidates' drift terms). Degradation is not modelled across conditions (its test
  runs on period blocks), so a drift it explains is said, not hidden: the drifting experiments are left
  out *because the loop degrades* ("diagnose the condition alone"), never "not settled, and no
  degradation explains it", which was said without a test (session 31 review: a degrading specimen at
  one condition, named by diagnose, read "adequate ... at every condition");
- a condition whose own diagnosis names degradation is treated the same way (its experiments and plain
  fit are not reused: the joint selection on its degrading loops named Dahl friction on x);
- a condition with no settled experiment is left out of the joint structure (:class:`NotSettled`), and
  with fewer than two conditions left nothing is named (:func:`too_few`'s verdict).

The verdict says which experiments and conditions were left out (:func:`clause`), and the notes why
(:func:`.settling.left_out_note`, prefixed by the condition).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from typing import Any, Optional

from .data import DiagExperiment
from .settling import LEFT_OUT, left_out_note, settled_only

#: Why experiments were left out (``_Group.left_why``, :class:`NotSettled`): degradation explains their
#: drift at the condition, or it was not tested (no drift term among the candidates).
DEGRADES, UNTESTED = "degrades", "untested"


class NotSettled(Exception):
    """No experiment of a condition has settled: the condition is left out of the joint structure."""

    def __init__(self, label: str, names: Sequence[str], why: str = "") -> None:
        super().__init__(f"{label}: not settled ({', '.join(names)})")
        self.label = label
        self.names = tuple(names)
        self.left_why = why


def why_own(own: Any) -> str:
    """Why the condition's own diagnosis left its experiments out: :data:`UNTESTED` when it had no drift term
    among its candidates (degradation not tested), else "" (tested, and none named)."""
    from .drift import DRIFT_TERMS

    cands = (own.settings or {}).get("candidates", DRIFT_TERMS)
    return "" if any(c in DRIFT_TERMS for c in cands) else UNTESTED


def names_degradation(d: Any) -> bool:
    """Whether the diagnosis ``d`` names degradation (diagnose's own rule: a drift term named, or its
    degradation test named, or passed when ``d`` ran without the held-out test)."""
    from .drift import DRIFT_TERMS

    deg = d.degradation  # a Diagnosis always has the field (None when the test was not formed)
    held_out = (d.settings or {}).get("held_out_test", True)
    named = deg is not None and deg.accepted(held_out)
    return named or any(t.term in DRIFT_TERMS for t in d.named)


def degrades(items: Any, cands: Sequence[str], alpha: float, held_out_test: bool) -> Optional[bool]:
    """The condition's own judgement of a drift: ``diagnose`` of its ``items`` with ``cands`` (the user's,
    drift terms included), whether it names degradation; None when no drift term is a candidate (not
    tested)."""
    from .drift import DRIFT_TERMS
    from .run import diagnose

    if not any(c in DRIFT_TERMS for c in cands):
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the condition's warnings are diagnose's to give
        d = diagnose(items, candidates=list(cands), alpha=alpha, held_out_test=held_out_test)
    return names_degradation(d)


def from_own(own: Any, label: str) -> tuple[str, ...]:
    """The experiments the condition's own diagnosis left out as not settled (its experiments are then the
    settled ones); raises :class:`NotSettled` when it left out every one."""
    left = tuple(str(s) for s in (own.settings or {}).get(LEFT_OUT, ()))
    if left and {e.source for e in own.experiments} <= set(left):
        raise NotSettled(label, left)
    return left


def drop(
    exps: Sequence[DiagExperiment],
    label: str,
    judge: Callable[[], Optional[bool]],
    ringing: frozenset[str] = frozenset(),
) -> tuple[list[DiagExperiment], tuple[str, ...], str]:
    """``exps`` without those whose loop still drifts (:func:`.settling.settled_only`) or still rings (their
    names in ``ringing``: a free ring-down of G, which diagnose leaves out as a drift no degradation
    explains, ring_down.py), their names and why (:data:`DEGRADES` when ``judge``, the condition's own
    judgement run only when some drift, names degradation; :data:`UNTESTED` when it did not test it; else
    ""); raises :class:`NotSettled` when none is left."""
    keep, drifting = settled_only(exps, False)
    rung = [i for i, e in enumerate(exps) if e.source in ringing]
    keep = [i for i in keep if i not in rung]
    names = tuple(exps[i].source for i in sorted({*drifting, *rung}))
    why = ""
    if set(drifting) - set(rung):  # a drift beside the rings: the condition's own judgement of it
        verdict = judge()
        why = UNTESTED if verdict is None else DEGRADES if verdict else ""
    if not keep:
        raise NotSettled(label, names, why)
    return [exps[i] for i in keep], names, why


def _reason(why: str) -> str:
    """The words on why experiments were left out, after their names."""
    if why == DEGRADES:
        return (
            "the loop degrades: diagnose of that condition alone names degradation, which the structure "
            "across conditions does not model (its test runs on period blocks); diagnose the condition alone"
        )
    if why == UNTESTED:
        return (
            "the loop still drifts from period to period: not settled; degradation was not tested (no drift "
            "term among the candidates); record more settling periods"
        )
    return "the loop still drifts from period to period"


def _note(label: str, names: Sequence[str], why: str) -> str:
    """A condition's note on what was left out: diagnose's wording (:func:`.settling.left_out_note`) when
    the drift was tested and is no degradation's, else :func:`_reason`'s."""
    if not why:
        return f"{label}: {left_out_note(', '.join(names))}"
    return f"{label}: left out of the diagnosis: {', '.join(names)} ({_reason(why)})"


def clause(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> str:
    """The verdict's word on what was left out as not settled: experiments per condition, whole
    conditions."""
    text = ""
    untested = " (degradation not tested: no drift term among the candidates)"
    parts = [
        f"{', '.join(g.left_out)} at {g.label}" + (untested if _why(g) == UNTESTED else "")
        for g in groups
        if g.left_out and _why(g) != DEGRADES
    ]
    if parts:
        text += f"; left out as not settled (the loop still drifts from period to period): {'; '.join(parts)}"
    for g in groups:
        if g.left_out and _why(g) == DEGRADES:
            text += f"; left out at {g.label}: {', '.join(g.left_out)} ({_reason(DEGRADES)})"
    plain = [u.label for u in unsettled if u.left_why != DEGRADES]
    if plain:
        text += (
            f"; condition {', '.join(plain)} left out: no experiment there has settled (every loop still "
            "drifts from period to period); nothing is named from a loop that has not settled"
        )
    for u in unsettled:
        if u.left_why == DEGRADES:
            text += f"; condition {u.label} left out ({_reason(DEGRADES)})"
    return text


def _why(g: Any) -> str:
    return str(getattr(g, "left_why", ""))


def notes(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> tuple[str, ...]:
    """Each condition's left-out note, as diagnose words it (:func:`.settling.left_out_note`)."""
    out = [_note(g.label, g.left_out, _why(g)) for g in groups if g.left_out]
    out += [_note(u.label, u.names, u.left_why) for u in unsettled]
    return tuple(out)


def too_few(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> Optional[str]:
    """The verdict when fewer than two conditions have a settled experiment: nothing is named (None when
    two or more are left: the joint selection runs)."""
    if len(groups) >= 2:
        return None
    n = len(groups) + len(unsettled)
    return (
        f"across {n} conditions: not settled: only {len(groups)} condition(s) with a settled experiment, "
        "and one structure across conditions needs two; nothing is named from a loop that has not settled "
        "(record more settling periods, or a longer record)" + clause(groups, unsettled)
    )


def measured_noise(items: Any, wander: Any) -> bool:
    """Whether every experiment's noise floor is measured noise (settling._noise_floors set none), of a
    condition's ``items`` and ``wander`` as across._group reads them."""
    from . import baseline
    from .data import prepare
    from .settling import _noise_floors, _settled

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        settled, _ = _settled(baseline.removed(items, wander))
    return not _noise_floors(settled, prepare(settled))[1]


__all__ = [
    "measured_noise",
    "NotSettled",
    "from_own",
    "why_own",
    "drop",
    "degrades",
    "names_degradation",
    "clause",
    "notes",
    "too_few",
]
