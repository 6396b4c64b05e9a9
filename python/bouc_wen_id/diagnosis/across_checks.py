"""Diagnose's checks that diagnose_across did not run, run through the same functions (session 46, ring46).

``diagnose`` takes a steady sinusoid not locked to the input (mains hum) out of the records before anything
(:func:`.lines.removed`) and says so in the verdict (:func:`.lines.clause`); it says a failed adequacy test
at a p-value within a factor :data:`.borderline.FACTOR` of ``alpha`` as weak evidence ("unexplained structure
may remain (p = ...; a right model is flagged so in ... % of cases)", :func:`.borderline.qualified_text`).
``diagnose_across`` ran neither: on test_diagnosis_lines.py's hum (a null plant, the line at 2 noise sd) at
two conditions it said "unexplained structure remains" with the hum left in the records; taken out, the
failed test that remains is at p = 0.015 at one condition, weak evidence, and said so
(tests/test_across_checks46.py). Here, the same functions and words:

- :func:`lines_removed`: each condition's records with their lines taken out (:func:`.lines.removed`, one
  search per condition at :data:`.lines.LINE_ALPHA` over ``K``: the search's false-alarm budget is the one
  verdict's, as diagnose's is its one set's; session 47, across47), and the notes prefixed by the
  condition;
- :func:`borderline_said`: when nothing but a failed adequacy test stands for what remains (no condition's
  loop drifting on its plain model, no law-failed candidate: :func:`.borderline.weak`'s ``drifting``) and
  every failing condition's p is weak, the verdict's "remains" says "may remain" with the smallest failing p
  and the rate at which a right model fails at one of the ``K`` conditions or more
  (:func:`.borderline.across_rate`: each is tested at ``alpha``).

The locked spike's second reading runs across in across_locked.py, dc_between's and dc_untested's rules in
across_dc.py (session 47). Not run across yet (diagnose's, left alone here): centre_decay.py (short records'
settling centre) and value_stability.py (a named value refitted on preprocessing variants).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any, TypeVar

from . import borderline, lines
from .across_adequacy import p_of

_A = TypeVar("_A", bound=Any)


def lines_removed(groups: Sequence[Sequence[Any]], labels: Sequence[str]) -> tuple[list[Any], list[str]]:
    """``(groups, notes)``: each condition's items with the lines :func:`.lines.removed` finds taken out (at
    :data:`.lines.LINE_ALPHA` shared by the ``K`` conditions), and its notes, each prefixed by the
    condition's label."""
    out, notes = [], []
    each = lines.LINE_ALPHA / max(1, len(groups))  # one verdict's budget, as diagnose's for one set
    for items, label in zip(groups, labels):
        kept, found = lines.removed(list(items), each)
        out.append(kept)
        notes += [f"{label}: {n}" for n in found]
    return out, notes


def lines_said(out: _A, notes: Sequence[str]) -> _A:
    """``out`` (an AcrossDiagnosis) with diagnose's clause on the lines taken out and their notes."""
    if not notes:
        return out
    return replace(out, verdict=out.verdict + lines.clause(notes), notes=(*notes, *out.notes))


def borderline_said(out: _A, groups: Sequence[Any], alpha: float) -> _A:
    """``out`` whose "unexplained structure remains" says "may remain" when the failed adequacy tests are the
    only, and weak, evidence at every condition where the joint structure fails (module docstring)."""
    if out.status not in ("unexplained", "partly explained") or not groups:
        return out
    fails = [p for g in groups if not ((p := p_of(g, g.current)) >= alpha)]
    other = any(getattr(g, "moved", False) for g in groups) or any(st.law_failed for st in out.steps)
    if not fails or not all(borderline.weak(p, alpha, other) for p in fails):
        return out
    rate = borderline.across_rate(alpha, len(groups))
    said = borderline.qualified_text(
        out.verdict, min(fails), alpha, rate, f"across {len(groups)} conditions: "
    )
    return out if said == out.verdict else replace(out, verdict=said)


__all__ = ["borderline_said", "lines_removed", "lines_said"]
