"""Output zeros that differ between recordings inside a condition, in diagnose-across (session 43).

``record_zeros.py`` (session 42) hooks into :func:`~bouc_wen_id.diagnosis.diagnose` alone: the joint
selection of :func:`~bouc_wen_id.diagnosis.across.diagnose_across` never reached it (its conditions are
prepared by ``across._group``, not by ``diagnose``), so a sensor re-zeroed between the recordings of a
condition (offsets a few % apart) had the output offset refused for its law (one value for a condition's
experiments) and the term whose own DC differs between experiments, an asymmetry, named in its place.

The same rule here, on the joint steps: :func:`triggered` when a joint step refused the output offset for
its law alone while it removed more of the summed misfit than the term named there (or none was named), the
joint structure is not adequate and no condition's zero wanders or drifts (those free their DCs already).
:func:`found` reads each condition's recordings' zeros off its plain model (``record_zeros.zeros_from``)
and keeps those whose common zero stands out of their spread (``RecordZeros.kept``: else the loop centres'
case). The conditions are then prepared again with those recordings' DCs free about their common one
(``record_zeros.freed``, ``free_dc.marked``), the joint selection run again, and :func:`chosen` keeps the
second reading when its final models fit better per degree of freedom (summed over the conditions), as
``record_zeros.chosen`` does. :func:`clause` says so, per condition.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Optional

from .record_zeros import OFFSET, RecordZeros, zeros_from
from .select import dof_of


def triggered(prepared: Sequence[Any], steps: Sequence[Any], status: str) -> bool:
    """Whether a joint step refused the output offset for its law alone while its summed improvement beat
    the chosen term's (or nothing was chosen), in a joint structure that is not adequate."""
    if status in ("adequate", "explained") or not any(_free(g) for g in prepared):
        return False
    for step in steps:
        if OFFSET not in step.law_failed:
            continue
        gain = {t.term: sum(t.improvements) for t in step.trials}
        chosen = gain.get(step.chosen, -float("inf")) if step.chosen else -float("inf")
        if gain.get(OFFSET, -float("inf")) > chosen:
            return True
    return False


def _free(g: Any) -> bool:
    """A condition of two or more experiments whose DCs are not freed already (a wander or a drift)."""
    return not (g.wander or g.drifts) and len(g.exps) >= 2


def found(prepared: Sequence[Any], level: float) -> Optional[list[Optional[RecordZeros]]]:
    """Per condition (by position), its recordings' zeros when their common zero stands out of their spread
    (``RecordZeros.kept``), else None; None when no condition has such zeros."""
    out: list[Optional[RecordZeros]] = []
    for g in prepared:
        z = None
        if _free(g):
            z = zeros_from(g.exps, [o * g.scale.y for o in g.plain.outputs], level)
        out.append(z if z is not None and z.kept else None)
    return out if any(z is not None for z in out) else None


def per_dof(prepared: Sequence[Any]) -> float:
    """The final models' cost per degree of freedom, summed over the conditions."""
    cost = sum(float(g.current.cost) for g in prepared)
    return cost / max(sum(dof_of(g.sx, g.current) for g in prepared), 1)


def chosen(first: Sequence[Any], second: Sequence[Any]) -> bool:
    """Whether the reading with the zeros free (``second``'s conditions) fits better per degree of freedom
    than the first (``first``'s)."""
    return per_dof(second) < per_dof(first)


def clause(prepared: Sequence[Any]) -> str:
    """The zeros' clause of each condition whose recordings' DCs were freed (``g.zeros``)."""
    return "".join(f"; at {g.label}:" + g.zeros.clause()[1:] for g in prepared if g.zeros is not None)


def notes(prepared: Sequence[Any]) -> tuple[str, ...]:
    """The zeros' note of each condition whose recordings' DCs were freed."""
    return tuple(f"at {g.label}: " + g.zeros.note() for g in prepared if g.zeros is not None)


__all__ = ["triggered", "found", "per_dof", "chosen", "clause", "notes"]
