"""A free ring-down of G still in the averaged periods, across conditions: diagnose_across reads it as
diagnose does (ring_down.py; session 45).

:func:`.run.diagnose` finds the recordings whose averaged periods still hold the free ring-down of a lightly
damped G (:func:`.ring_down.rings`), leaves a minority of them out as a drift no degradation explains, and
when most or all ring names nothing: "not settled", with the settle periods that would let it die out
(:func:`.ring_down.not_settled`). ``diagnose_across`` fitted every condition's ringing records: the drift of
the loop from period to period read as structure at every level. Here the same check, on every condition's
records as given:

- :func:`found`: each condition's ringing recordings (their names as the condition's experiments carry them),
  left out of its fit (``across_settling.drop``) when some of its experiments ring, not all (diagnose's
  rule for one set: when all ring, they are all fitted); and the rings labelled with their condition;
- :func:`said`: when most of all the conditions' experiments ring, the verdict is diagnose's "not settled"
  (its words, :func:`.ring_down.not_settled`) and nothing is named. As in diagnose, an adequate verdict
  stands only when it was reached on every ringing record (none left out): after leaving most records out
  it would rest on a minority, which diagnose does not judge (drift_majority.py). The notes say which
  recordings ring either way.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any, TypeVar

from . import ring_down

_A = TypeVar("_A", bound=Any)


def found(
    groups: Sequence[Sequence[Any]], labels: Sequence[str]
) -> tuple[list[frozenset[str]], list[Any], list[str]]:
    """``(sources, rings, notes)``: per condition, the names of its recordings to leave out as ringing (as
    :func:`.ring_down.left_out` matches them to the prepared experiments; none where every one rings, as
    diagnose leaves none out then); every ring, its source prefixed by its condition's label; and
    diagnose's note on each (one TransientWarning each, as diagnose gives)."""
    sources: list[frozenset[str]] = []
    rings: list[Any] = []
    notes: list[str] = []
    for items, label in zip(groups, labels):
        got, words = ring_down.rings(items)
        every = len(got) >= len(items)  # (a measurement's segments: each one an experiment)
        sources.append(frozenset() if every else frozenset(r.source for r in got))
        rings += [replace(r, source=f"{label}: {r.source}") for r in got]
        notes += [f"{label}: {note}" for note in words]
    return sources, rings, notes


def said(out: _A, rings: list[Any], notes: Sequence[str], total: int, n: int, left: bool) -> _A:
    """``out`` (an AcrossDiagnosis of ``n`` conditions) with the rings' ``notes`` (and which lab segments
    were not checked), and, when most of the
    ``total`` experiments ring, diagnose's "not settled" verdict with nothing named (its terms, partial
    terms and the steps' alternatives cleared: a loop that has not settled names no physics); unless
    ``out`` is "adequate" and no ringing record was ``left`` out (module docstring)."""
    out = replace(out, notes=(*out.notes, *notes)) if notes else out
    verdict = ring_down.not_settled(rings, total)
    if not verdict or (out.status == "adequate" and not left):
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


__all__ = ["found", "said"]
