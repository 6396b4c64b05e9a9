"""A named viscous damping's rate caveat across conditions (diagnosis/rate_rival.py, as diagnose says it).

``diagnose`` says of a named viscous damping whose per-experiment values do not refuse a rate-independent
loop's 1/omega law that it may stand for such a loop (:func:`.rate_rival.rate_text`). ``diagnose_across``
named the same term across conditions without it, so a user taking that path was told less than one taking
the per-level one. Here the same test runs at each condition where the named damping is present, on that
condition's final fit of the joint structure (its own experiments, per-experiment values and amplitudes:
the rival loop may differ between conditions, as a damper's loop does with its current); the clause is said
when some condition does not refuse the rival, naming those conditions, and not when every condition that
can test it refuses it (there the viscous law is told from such a loop).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .rate_rival import clause, not_refused


def text(named: Sequence[Any], groups: Sequence[Any]) -> str:
    """The clause for each named term (:class:`.across.TermAcross`: ``term``, ``present`` per condition) that
    is a viscous damping not refused as a rate-independent loop at some condition where it is present (each
    of ``groups`` with its final scaled experiments ``sx``, final fit ``current``, ``substeps`` and
    ``label``): the largest p, the frequencies and the labels of those conditions."""
    out = ""
    for t in named:
        present = tuple(getattr(t, "present", ())) or (True,) * len(groups)
        got = [
            (g, p)
            for g, pr in zip(groups, present)
            if pr and (p := not_refused(g.sx, g.current, t.term, g.substeps)) is not None
        ]
        if not got:
            continue
        where = "condition" + ("s " if len(got) > 1 else " ") + ", ".join(str(g.label) for g, _ in got)
        freqs = [float(e.frequency) for g, _ in got for e in g.sx]
        out += clause(t.term, max(p for _, p in got), freqs, where)
    return out


__all__ = ["text"]
