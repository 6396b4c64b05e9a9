"""The diagnosis's word on a spike locked to the excitation (:mod:`.locked_spike`), and its second reading.

When :func:`.locked_spike.found` keeps a run, each is said in the notes (and so in the JSON), and the
diagnosis is run again on the records with those samples bridged in every period (the straight line between
their neighbours, :func:`.locked_spike.bridged`): the verdict returned is that second reading, with a clause
that says so, and a note gives the first (status, headline, chi2/dof), so a term fitted only to the spike is
not named without a word. When the records cannot be bridged (no raw Recording) the verdict is the first
one, with a clause that the spike is in it.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

from . import locked_spike


def where(spikes: Sequence[locked_spike.Spike]) -> str:
    """Where the spikes are, in words: each run's samples and its record's averaged period."""
    parts = []
    for s in spikes:
        run = f"sample {s.first}" if s.first == s.last else f"samples {s.first}..{s.last}"
        parts.append(f"{run} of {s.source}'s averaged period")
    return ", ".join(parts)


def said(d: Any, items: Sequence[Any], again: Callable[[list[Any]], Any]) -> Any:
    """``d`` with its locked spikes said; read again with them bridged when the records allow it."""
    spikes, limit = locked_spike.found(d, locked_spike.analysed_rows(items, d))
    if not spikes:
        return d
    notes = tuple(s.note(limit) for s in spikes)
    at = where(spikes)
    fixed = locked_spike.bridged(items, d, spikes)
    if fixed is None:
        return replace(d, verdict=d.verdict + clause(at, False), notes=(*notes, *d.notes))
    d2 = again(fixed)
    first = first_reading(at, (d.status, d.headline, d.final.chi2_dof), (d2.status, d2.final.chi2_dof))
    return replace(d2, verdict=d2.verdict + clause(at, True), notes=(*notes, first, *d2.notes))


def clause(at: str, bridged: bool) -> str:
    """The verdict's clause on the spikes ``at`` (:func:`where`): read with them bridged, or left in."""
    how = "bridged" if bridged else "in"
    return f"; read with {at} {how} (off every model: a disturbance locked to the excitation?)"


def first_reading(at: str, first: tuple[str, str, float], second: tuple[str, float]) -> str:
    """The note on the first reading: ``first`` (status, headline, chi2/dof) with the spikes ``at`` left in,
    ``second`` (status, chi2/dof) with them bridged."""
    return (
        f"with {at} left in, the diagnosis read: {first[0]}: {first[1]} (final model's chi2/dof "
        f"{first[2]:.3g}); with them bridged (each period's samples on the line between their "
        f"neighbours): {second[0]} (chi2/dof {second[1]:.3g})"
    )


__all__ = ["clause", "first_reading", "said", "where"]
