"""Inputs that are not sines and outputs that are clipped, across conditions: the single diagnosis's
:mod:`.clean_value`, :mod:`.input_note` and :mod:`.output_clip` at each condition of
:func:`.across.diagnose_across` (issue 18, "nothing false said").

Three conditions of a viscous damping on u, two of five inputs clipped at the middle one: diagnosed one by
one, the middle condition said its input was not a sine (with the harmonic and where) and quoted values
fitted on its clean experiments; across, nothing of it. Here, at each condition:

- the joint structure's values (named or tested) are refitted on the condition's clean-input experiments
  (:func:`.clean_value.refit`, the set :func:`.clean_share.clean` gives), their standard errors inflated by
  the refit's ``sqrt(chi2/dof)`` when above 1 as :func:`.across._terms` inflates them, the smoothness in the
  condition recomputed on them, and the verdict says where they come from (:meth:`.CleanValues.text`);
- the verdict says the measured input is not a sine (:func:`.input_note.text` on the condition's final fit);
- the verdict says the measured output looks clipped (:func:`.output_clip.clipped` on the condition's
  recordings).

The one-shared-value test (:mod:`.shared`) stays the pooled one (refitted over every experiment).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from . import clean_value, input_note, output_clip
from .across_smooth import smoothness
from .clean_share import clean
from .fitting import physical, subset
from .result import NamedTerm
from .select import dof_of


def _as_named(t: Any, k: int) -> NamedTerm:
    return NamedTerm(t.term, t.symbol, t.values[k], t.standard_errors[k], t.unit)


def _at(label: Any, clause: str) -> str:
    return f"; at {label}: {clause.removeprefix('; ')}" if clause else ""


def _refit(
    g: Any, k: int, terms: Sequence[Any]
) -> tuple[dict[str, tuple[float, float]], clean_value.CleanValues]:
    """The values at condition ``g`` refitted on its clean experiments (term -> (value, se)) and what the
    verdict says of them; empty when every input there is a sine or the structure has no term."""
    idx = clean(g.sx)
    if not idx or not g.current.params.terms:
        return {}, clean_value.CleanValues()
    kept = tuple(g.sx[i].source for i in idx)
    left = tuple(e.source for i, e in enumerate(g.sx) if i not in idx)
    got = clean_value.refit(g.sx, g.current, g.substeps)
    if got is None:
        return {}, clean_value.CleanValues(kept, left, failed=True)
    fit, undetermined = got
    sub, _ = subset(g.sx, g.current.params, idx)
    inflate = math.sqrt(max(1.0, fit.cost / max(dof_of(sub, fit), 1)))
    new = {}
    for t in terms:
        if t.term in fit.params.terms:
            v, se = physical(fit, g.scale, t.term)
            new[t.term] = (v, se * inflate)
    pooled = tuple(_as_named(t, k) for t in terms if t.term in new)  # the values they replace
    return new, clean_value.CleanValues(kept, left, pooled, False, undetermined)


def _resmoothed(t: Any, groups: Sequence[Any], alpha: float) -> Any:
    ps = smoothness([g.condition for g in groups], t.values, t.standard_errors)
    return replace(t, smooth_p=ps, smooth_degree=next((d for d, p in enumerate(ps) if p >= alpha), None))


def values(
    terms: Sequence[Any], partial: Sequence[Any], groups: Sequence[Any], status: str, alpha: float
) -> tuple[tuple[Any, ...], tuple[Any, ...], str]:
    """``(terms, partial, text)``: the joint structure's terms (:class:`.across.TermAcross`) with their
    values at each condition with a clipped or distorted input refitted on its clean experiments, and the
    verdict's clause for each such condition."""
    every = [*terms, *partial]
    text = ""
    changed: dict[str, Any] = {t.term: t for t in every}
    moved: set[str] = set()
    for k, g in enumerate(groups):
        new, cv = _refit(g, k, every)
        for term, (v, se) in new.items():
            t = changed[term]
            vals, ses = list(t.values), list(t.standard_errors)
            vals[k], ses[k] = v, se
            changed[term] = replace(t, values=tuple(vals), standard_errors=tuple(ses))
            moved.add(term)
        quoted = [_as_named(changed[t.term], k) for t in every]
        text += _at(g.label, cv.text(status, quoted))
    out = {term: _resmoothed(t, groups, alpha) if term in moved else t for term, t in changed.items()}
    return tuple(out[t.term] for t in terms), tuple(out[t.term] for t in partial), text


def inputs_text(groups: Sequence[Any], status: str, named: Sequence[Any]) -> str:
    """The input clause (:func:`.input_note.text`) at each condition whose measured input is not a sine."""
    out = ""
    for k, g in enumerate(groups):
        as_named = [_as_named(t, k) for t in named]
        outputs = [np.asarray(y) * g.scale.y for y in g.current.outputs]  # in the data's units, as run.py's
        clause = input_note.text(status, as_named, g.exps, outputs)
        out += clause.replace(input_note.MARK, f"{input_note.MARK} at {g.label}", 1)
    return out


def outputs_text(labels: Sequence[Any], items: Sequence[Sequence[Any]]) -> str:
    """The clipped-output clause (:func:`.output_clip.clause`) at each condition whose recorded output has
    flat tops (``items``: each condition's recordings as given)."""
    out = ""
    for label, its in zip(labels, items):
        clause = output_clip.clause(list(its))
        out += clause.replace("; the measured output of ", f"; at {label}, the measured output of ", 1)
    return out


__all__ = ["inputs_text", "outputs_text", "values"]
