"""diagnose's locked spike (locked_said.py) across conditions: a spike at the same sample of every period,
said, and the joint diagnosis read again with it bridged (session 47, across47).

``diagnose`` reads each experiment's averaged period against its plain and final models and keeps a run of
samples standing off both beyond the Bonferroni threshold over every sample (:func:`.locked_spike.found`);
it says it and reads the records again with the run bridged in every period (:func:`.locked_said.said`).
``diagnose_across`` did neither: a drive's EMI at 20 se in every period of one condition's records (the
tests' wiener_sim plant, two conditions) read "unexplained structure remains; nothing named", the other
condition adequate alone (tests/test_across_locked47.py). Here the same functions: every condition's
experiments and models are read as one set (the threshold over every sample of every condition: one
verdict's false-alarm budget, as diagnose's for its set), the spikes said in the notes with their
condition, and the records bridged (:func:`.locked_spike.bridged`) and read again by ``again``: the verdict
is that second reading with diagnose's clause, and a note gives the first.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import replace
from types import SimpleNamespace
from typing import Any, Optional, TypeVar

import numpy as np

from . import locked_said, locked_spike
from .verdict_text import headline

_A = TypeVar("_A", bound=Any)


def _view(groups: Sequence[Any]) -> Any:
    """Every condition's experiments and its plain and current models (in the experiments' units) as one
    diagnosis, as :func:`.locked_spike.found` reads it."""

    def outputs(attr: str) -> SimpleNamespace:
        outs = [np.asarray(y) * g.scale.y for g in groups for y in getattr(g, attr).outputs]
        return SimpleNamespace(outputs=tuple(outs))

    phases = [ph for g in groups for ph in g.current.params.phases]
    return SimpleNamespace(
        experiments=[e for g in groups for e in g.exps],
        plain=outputs("plain"),
        final=outputs("current"),
        final_fit=SimpleNamespace(params=SimpleNamespace(phases=phases)),
    )


def said(
    out: _A,
    groups: Sequence[Any],
    items: dict[str, Sequence[Any]],
    again: Callable[[dict[str, list[Any]]], _A],
) -> _A:
    """``out`` (an AcrossDiagnosis of the prepared ``groups``; ``items``: each condition's records by its
    label) with its locked spikes said; read again by ``again`` (the bridged records of the conditions that
    hold a spike, by label) when the records allow it."""
    view = _view(groups)
    labels = [g.label for g in groups for _ in g.exps]
    every = [it for g in groups for it in items.get(g.label, ())]
    whose = [g.label for g in groups for _ in items.get(g.label, ())]
    spikes, limit = locked_spike.found(view, locked_spike.analysed_rows(every, view))
    if not spikes:
        return out
    first_of = {lab: labels.index(lab) for lab in labels}  # each condition's first experiment in the set
    notes = tuple(
        f"{labels[s.index]}: {replace(s, index=s.index - first_of[labels[s.index]]).note(limit)}"
        for s in spikes
    )
    at = ", ".join(f"{locked_said.where([s])} at condition {labels[s.index]}" for s in spikes)
    fixed = locked_spike.bridged(every, view, spikes)
    if fixed is None:
        return replace(out, verdict=out.verdict + locked_said.clause(at, False), notes=(*notes, *out.notes))
    hit = {labels[s.index] for s in spikes}
    out2 = again({k: [x for x, w in zip(fixed, whose) if w == k] for k in hit})
    first = locked_said.first_reading(
        at, (out.status, headline(out.verdict), _worst(out)), (out2.status, _worst(out2))
    )
    return replace(
        out2, verdict=out2.verdict + locked_said.clause(at, True), notes=(*notes, first, *out2.notes)
    )


def _worst(out: Any) -> float:
    """The largest final chi2/dof over the conditions (NaN: none)."""
    vals = [c.final_chi2_dof for c in out.conditions if np.isfinite(c.final_chi2_dof)]
    return max(vals) if vals else float("nan")


def without(per_condition: Optional[Sequence[Any]], names: Sequence[str], bridged: set[str]) -> Any:
    """``per_condition`` without the own diagnoses of the ``bridged`` conditions (read from their records)."""
    if per_condition is None:
        return None
    return [None if n in bridged else d for d, n in zip(per_condition, names)]


__all__ = ["said", "without"]
