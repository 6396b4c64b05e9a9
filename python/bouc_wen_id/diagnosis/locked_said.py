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


def _where(spikes: Sequence[locked_spike.Spike]) -> str:
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
    where = _where(spikes)
    fixed = locked_spike.bridged(items, d, spikes)
    if fixed is None:
        clause = f"; read with {where} in (off every model: a disturbance locked to the excitation?)"
        return replace(d, verdict=d.verdict + clause, notes=(*notes, *d.notes))
    d2 = again(fixed)
    first = (
        f"with {where} left in, the diagnosis read: {d.status}: {d.headline} (final model's chi2/dof "
        f"{d.final.chi2_dof:.3g}); with them bridged (each period's samples on the line between their "
        f"neighbours): {d2.status} (chi2/dof {d2.final.chi2_dof:.3g})"
    )
    clause = f"; read with {where} bridged (off every model: a disturbance locked to the excitation?)"
    return replace(d2, verdict=d2.verdict + clause, notes=(*notes, first, *d2.notes))


__all__ = ["said"]
