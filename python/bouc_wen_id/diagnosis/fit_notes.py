"""What the diagnosis notes of its fits: one code for :func:`.run.diagnose` and
:func:`.across.diagnose_across` (issue 18: the house says the same thing whichever path the user takes).

- :func:`fit_notes`: a fit that stopped on a face of the admissible range (a value at its bound,
  :func:`..estimators.boundary_note`) or whose free DCs did not settle (:func:`.free_dc.note`), for the
  plain fit and the final one;
- :func:`condition_notes`: the same for every condition of the joint structure, with "below saturation"
  (:func:`.caveats.below_saturation`, on the final fit's latent levels as diagnose reads them), each note
  prefixed by its condition;
- :func:`centre_text`: the verdict's clause on loop centres that differ in sign between experiments
  (:func:`.run._centre_text`), at each condition where it holds.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..augmented import AugFit
from ..estimators import boundary_note
from . import free_dc
from .caveats import below_saturation
from .select import dof_of


def fit_notes(plain: AugFit, final: AugFit) -> list[str]:
    """The notes on the plain fit and the final one (one fit: "the fit"), as diagnose gives them."""
    fits = (
        ((plain, "the plain fit"), (final, "the final fit")) if final is not plain else ((plain, "the fit"),)
    )
    return [n for f, w in fits for n in (boundary_note(f.stop, f.active, w), free_dc.note(f, w)) if n]


def condition_notes(groups: Sequence[Any]) -> tuple[str, ...]:
    """Every condition's :func:`fit_notes` and below-saturation note (its final fit's levels), each as
    ``"<label>: <note>"``."""
    out = []
    for g in groups:
        said = (*fit_notes(g.plain, g.current), *below_saturation(g.sx, g.current))
        out += [f"{g.label}: {n}" for n in said]
    return tuple(out)


def centre_text(groups: Sequence[Any]) -> str:
    """The loop-centre clause (:func:`.run._centre_text`) at each condition where its residual DCs differ
    in sign beyond the noise (times the final fit's chi2/dof when above 1), said with the condition."""
    from .run import _centre_text

    text = ""
    for g in groups:
        if not g.exps:
            continue
        outs = [np.asarray(y) * g.scale.y for y in g.current.outputs]
        clause = _centre_text(g.exps, outs, max(1.0, g.current.cost / max(dof_of(g.sx, g.current), 1)))
        if clause:
            text += f"; at {g.label}: " + clause.removeprefix("; ")
    return text


__all__ = ["fit_notes", "condition_notes", "centre_text"]
