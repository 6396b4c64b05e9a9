"""Loops that have not settled, across conditions: ``diagnose_across`` leaves them out as ``diagnose`` does.

:func:`.run.diagnose` tests every experiment's loop for a drift from period to period beyond the noise
(:func:`.settling._unsettled`) and, unless degradation explains it, leaves the drifting experiments out
(:func:`.settling.settled_only`), saying which; when none is settled it names nothing (issue 18: "a loop that
has not settled is not physics"). ``diagnose_across`` fitted every experiment of every condition: a
low-amplitude loop still settling its centre at one condition left a misfit the joint selection read as
structure. Here the same rule per condition:

- given the condition's own diagnosis, the experiments it left out (recorded in its ``settings`` under
  :data:`.settling.LEFT_OUT`) stay out (its experiments and plain fit are the settled ones);
- without it, :func:`.settling.settled_only` on the condition's prepared experiments (no degradation test
  runs across conditions: a drift there is not degradation's);
- a condition with no settled experiment is left out of the joint structure (:class:`NotSettled`), and
  with fewer than two conditions left nothing is named (:func:`too_few`'s verdict).

The verdict says which experiments and conditions were left out (:func:`clause`), and the notes why
(:func:`.settling.left_out_note`, prefixed by the condition).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Optional

from .data import DiagExperiment
from .settling import LEFT_OUT, left_out_note, settled_only


class NotSettled(Exception):
    """No experiment of a condition has settled: the condition is left out of the joint structure."""

    def __init__(self, label: str, names: Sequence[str]) -> None:
        super().__init__(f"{label}: not settled ({', '.join(names)})")
        self.label = label
        self.names = tuple(names)


def from_own(own: Any, label: str) -> tuple[str, ...]:
    """The experiments the condition's own diagnosis left out as not settled (its experiments are then the
    settled ones); raises :class:`NotSettled` when it left out every one."""
    left = tuple(str(s) for s in (own.settings or {}).get(LEFT_OUT, ()))
    if left and {e.source for e in own.experiments} <= set(left):
        raise NotSettled(label, left)
    return left


def drop(exps: Sequence[DiagExperiment], label: str) -> tuple[list[DiagExperiment], tuple[str, ...]]:
    """``exps`` without those whose loop still drifts (:func:`.settling.settled_only`, no degradation
    named), and their names; raises :class:`NotSettled` when none is left."""
    keep, drifting = settled_only(exps, False)
    names = tuple(exps[i].source for i in drifting)
    if not keep:
        raise NotSettled(label, names)
    return [exps[i] for i in keep], names


def clause(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> str:
    """The verdict's word on what was left out as not settled: experiments per condition, whole
    conditions."""
    text = ""
    parts = [f"{', '.join(g.left_out)} at {g.label}" for g in groups if g.left_out]
    if parts:
        text += f"; left out as not settled (the loop still drifts from period to period): {'; '.join(parts)}"
    if unsettled:
        which = ", ".join(u.label for u in unsettled)
        text += (
            f"; condition {which} left out: no experiment there has settled (every loop still drifts from "
            "period to period); nothing is named from a loop that has not settled"
        )
    return text


def notes(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> tuple[str, ...]:
    """Each condition's left-out note, as diagnose words it (:func:`.settling.left_out_note`)."""
    out = [f"{g.label}: {left_out_note(', '.join(g.left_out))}" for g in groups if g.left_out]
    out += [f"{u.label}: {left_out_note(', '.join(u.names))}" for u in unsettled]
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


__all__ = ["NotSettled", "from_own", "drop", "clause", "notes", "too_few"]
