"""The adequacy test's reading at one condition of the diagnosis across conditions: diagnose's statistic.

:func:`chi2` is the statistic :func:`~bouc_wen_id.diagnosis.diagnose`'s adequacy test reads
(:func:`.adequacy_chi2.statistic`: each harmonic weighed by its own noise level where the condition's noise
is coloured, the fit's own cost where it is white), :func:`p_of` its p-value. The joint selection read the
fit's cost alone, which divides every harmonic by the largest band's level (the noise floor under a red
noise, data.noise_colour): under AR(1) noise (phi 0.5) its final chi2/dof read 0.22-0.27 at every condition
while each condition's own diagnosis read about 1, and its plain model passed the gate (p = 1) where
diagnose's failed (review 43). The gate, the stop rule, the status and the conditions' table read these
(across_verdict.py, across_step.py, across_place.py, across.py).
"""

from __future__ import annotations

from typing import Any

from . import adequacy_chi2
from .locate import adequacy_p
from .select import dof_of


def chi2(g: Any, fit: Any) -> float:
    """The adequacy test's chi-square of ``fit`` at condition ``g`` (its experiments ``g.exps`` give the
    noise's levels; none known: the fit's own cost)."""
    weights = adequacy_chi2.relative_weights(getattr(g, "exps", ()))
    if not any(w is not None for w in weights):
        return float(fit.cost)
    return adequacy_chi2.statistic(weights, g.sx, fit.outputs, fit.cost)


def p_of(g: Any, fit: Any) -> float:
    """The adequacy p of ``fit`` at condition ``g`` (:func:`chi2`, its dof and noise dof), as diagnose's."""
    return adequacy_p(chi2(g, fit), dof_of(g.sx, fit), g.noise_dof)


__all__ = ["chi2", "p_of"]
