"""The steady selection from a start model, in one call: :func:`.after_named.select` (the forward
selection, targeted after a named term or drift correction), then :func:`.rival_revisit.after` (a named
single term whose later lead or rival failed its law). run.py calls it once, and again when the drift value
is re-estimated beside the named steady terms (run._rejoint: the periods it corrects are new data, review
rv36m F1). Last, every named term must still pass its own test in the final model (:mod:`.final_terms`).
The step is targeted after a named term or a named drift term (after_named.py), not on short
records (centre_decay.py)."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

from ..augmented import AugExperiment, AugFit
from . import after_named, final_terms, rival_revisit
from .select import ALPHA, Step


def select(
    fsx: list[AugExperiment],
    start: AugFit,
    steady: Sequence[str],
    adequate: Callable[[AugFit], bool],
    p_of: Callable[[AugFit], float],
    substeps: int,
    t: tuple[bool, bool],
    kw: dict[str, Any],
) -> tuple[AugFit, list[Step]]:
    """``(final, steps)`` from ``start`` on ``fsx``; ``t`` after_named.select's (targeted, again)
    flags, ``kw`` its keywords (alpha, held-out, cache, pair step, progress)."""
    final, steps = after_named.select(fsx, start, steady, adequate, p_of, substeps, *t, **kw)
    final, steps = rival_revisit.after(fsx, start, final, steps, adequate, substeps, **kw)
    return final_terms.check(fsx, final, steps, substeps, kw.get("alpha", ALPHA))  # each named term needed
