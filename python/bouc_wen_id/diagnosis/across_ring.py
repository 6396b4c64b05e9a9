"""A free ring-down of G still in the averaged periods, across conditions: diagnose_across reads it as
diagnose does (ring_down.py; session 45, counted per condition in session 46).

:func:`.run.diagnose` finds the recordings whose averaged periods still hold the free ring-down of a lightly
damped G (:func:`.ring_down.rings`), leaves a minority of them out as a drift no degradation explains, and
when most or all ring names nothing: "not settled", with the settle periods that would let it die out
(:func:`.ring_down.not_settled`). ``diagnose_across`` fitted every condition's ringing records: the drift of
the loop from period to period read as structure at every level. Here the same check, on every condition's
records as given:

- :func:`found`: each condition's ringing recordings (their names as the condition's experiments carry
  them), and the rings labelled with their condition. ``across_settling.drop`` leaves them out of the
  condition's fit; where most of the condition's experiments ring it leaves the condition out whole
  (diagnose names nothing from such a set). The majority is counted per condition, over its experiments (a
  measurement's segments each one): a condition is the set diagnose would be given. Session 45 counted it
  over every condition's items at once (a measurement counted once however many segments it held): a
  condition that rang throughout beside two that did not was fitted whole, its ring read as structure, and
  two conditions half ringing were refused together though diagnose judges each on its settled half;
- :func:`said`: the notes on each ring; when fewer than two conditions are left (the rest not settled) and
  most of all the experiments ring, the verdict is diagnose's "not settled" (its words,
  :func:`.ring_down.not_settled`, with the settle periods that would help) and nothing is named.
- the segments too short for the check are said where it matters (ring_unchecked.py), as diagnose says them.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, TypeVar

from . import ring_down

_A = TypeVar("_A", bound=Any)


@dataclass(frozen=True)
class Found:
    """What :func:`found` read: per condition the names of its ringing records (``sources``), every ring
    labelled with its condition, their notes, the segments too short for the check (labelled) and how many
    records were read in all (``total``: a measurement's segments each one)."""

    sources: list[frozenset[str]]
    rings: list[Any]
    notes: list[str]
    short: list[str]
    total: int


def found(groups: Sequence[Sequence[Any]], labels: Sequence[str]) -> Found:
    """:class:`Found` of ``groups`` (one set of experiments per condition, named by ``labels``): diagnose's
    note on each ring (one TransientWarning each, as diagnose gives)."""
    out = Found([], [], [], [], 0)
    total = 0
    for items, label in zip(groups, labels):
        got, words, short, n = ring_down.checked(items)
        out.sources.append(frozenset(r.source for r in got))
        out.rings.extend(replace(r, source=f"{label}: {r.source}") for r in got)
        out.notes.extend(f"{label}: {note}" for note in words)
        out.short.extend(f"{label}: {s}" for s in short)
        total += n
    return replace(out, total=total)


def said(out: _A, ring: Found, n: int, few: bool) -> _A:
    """``out`` (an AcrossDiagnosis of ``n`` conditions) with the rings' notes, and, when ``few`` (fewer than
    two conditions left to fit) and most of all the experiments ring, diagnose's "not settled" verdict with
    nothing named (its terms, partial terms and the steps' alternatives cleared: a loop that has not settled
    names no physics)."""
    out = replace(out, notes=(*out.notes, *ring.notes)) if ring.notes else out
    verdict = ring_down.not_settled(ring.rings, ring.total) if few else ""
    if not verdict:
        return out
    steps = tuple(replace(st, alternatives=()) for st in out.steps)
    return replace(
        out,
        status="unexplained",
        verdict=f"across {n} conditions: {verdict}",
        terms=(),
        partial=(),
        steps=steps,
    )


def drift_read(groups: Sequence[Any], unsettled: Sequence[Any]) -> str:
    """What the joint diagnosis read of a change of the loop from period to period (ring_unchecked.py):
    records left out as drifting (not those that ring), conditions with no settled record; "" when none."""
    from .across_settling import RINGS

    left = [f"{n} at {g.label}" for g in groups for n in g.left_out if n not in getattr(g, "rung", ())]
    left += [f"condition {u.label}" for u in unsettled if u.left_why != RINGS]
    return f"records were left out as drifting from period to period ({', '.join(left)})" if left else ""


__all__ = ["Found", "drift_read", "found", "said"]
