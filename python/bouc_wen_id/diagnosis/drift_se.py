"""The drift term's standard error with the steady fit's own uncertainty carried into it.

The drift-space estimate ``d = num / den`` (drift.py) is linear in the block deviations for a given
regressor ``d E_i t_b J_i``, and its quoted variance ``1 / den`` is that of the deviations' noise alone.
But ``E_i`` (the fitted loop's energy per period) and ``J_i`` (or ``K_i``) come from the steady model fitted
to the averaged periods of the same record: its beta, gamma, mu, gains and phases are estimates too, and
``d`` moves with them (a loop area 1.5 % larger gives a d 1.5 % smaller). The averaged periods' noise is
independent of the block deviations' (these are the blocks less their mean), so the two variances add:

    var d = var_blocks d + g' C g,    g = dd/dtheta at the given deviations,

with ``C`` the steady fit's covariance and ``g`` by central differences along C's principal axes (``h``
standard deviations each: the estimate is smooth there). Measured before this (review 33, degr_2p, two-pole
G, 8 white-noise draws): the first-order d scattered 2.4 times its quoted se, and 1.08 times it with E and J
held at one draw's fit: the deviations' noise model was right; the regressor's uncertainty was missing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit
from ..errors import BoucWenIdError, BudgetExceededError
from .data import DiagExperiment
from .drift import DEGRADATION, DriftData, _sums, corrected, drift_data, strengths
from .fitting import fit_from

#: The step of the central differences, in standard deviations of each principal axis of the covariance.
STEP_SD = 0.1


def _shifted(fit: AugFit, delta: np.ndarray) -> Optional[AugFit]:
    """``fit`` with its parameters moved by ``delta`` (the covariance's order: beta, gamma, mu, the term
    values, then gain and phase per experiment); None when the moved parameters are not admissible."""
    par = fit.params
    t = len(par.terms)
    m = len(par.gains)
    try:
        new = replace(
            par,
            beta=par.beta + float(delta[0]),
            gamma=par.gamma + float(delta[1]),
            mu=par.mu + float(delta[2]),
            values=np.asarray(par.values, dtype=np.float64) + delta[3 : 3 + t],
            gains=np.asarray(par.gains, dtype=np.float64) + delta[3 + t : 3 + t + 2 * m : 2],
            phases=np.asarray(par.phases, dtype=np.float64) + delta[4 + t : 3 + t + 2 * m : 2],
        )
    except (ValueError, ArithmeticError):
        return None
    return replace(fit, params=new)


def _estimate(data: Sequence[DriftData], regs: Sequence[DriftData], term: str) -> float:
    """The drift-space ``d`` of ``data``'s deviations against ``regs``' regressors (same experiments)."""
    num = den = 0.0
    for dd, rr in zip(data, regs):
        moved = replace(rr, dev=dd.dev, t=dd.t, w=dd.w)
        _, n, d = _sums(moved, term)
        num += n
        den += d
    return num / den if den > 0 else math.nan


def regressor_variance(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    data: Sequence[DriftData],
    deg: Any,
    y_scale: float,
    substeps: int,
    strength: Optional[Sequence[float]] = None,
) -> float:
    """``g' C g``: the variance (scaled units, as ``d``) that the steady fit's covariance ``C`` puts into the
    drift-space estimate of ``deg`` (a :class:`.drift.DegradationTest`) through its regressor. ``data`` are
    the drift data formed at ``fit`` and ``strength`` (each loop's strength relative to ``fit``'s, as
    :func:`.drift.drift_data` takes it); 0 when the covariance is not finite (a direction
    the averaged data do not fix: nothing can be added honestly, and the caller keeps the blocks' variance).
    """
    term = deg.term
    cov = np.asarray(fit.covariance, dtype=np.float64)
    if not data or cov.size == 0 or not np.all(np.isfinite(cov)):
        return 0.0
    lam, vec = np.linalg.eigh(0.5 * (cov + cov.T))
    keep = lam > 0
    axes = vec[:, keep] * np.sqrt(lam[keep])[None, :]
    index = [dd.index for dd in data]
    total = 0.0
    for k in range(axes.shape[1]):
        got = []
        for sign in (1.0, -1.0):
            moved = _shifted(fit, sign * STEP_SD * axes[:, k])
            if moved is None:
                break
            try:
                regs = drift_data(exps, sx, moved, y_scale, substeps, strength=strength)
            except BudgetExceededError:  # a limit the user set
                raise
            except BoucWenIdError:  # a moved loop the core cannot solve: this axis adds nothing
                break
            if [dd.index for dd in regs] != index:
                break
            got.append(_estimate(data, regs, term))
        if len(got) == 2 and all(math.isfinite(v) for v in got):
            total += ((got[0] - got[1]) / (2.0 * STEP_SD)) ** 2
    return total


#: The relative step of d in :func:`feedback`'s central difference.
FEEDBACK_STEP = 0.03
#: The largest feedback gain taken: beyond it the passes would not settle, and the linearisation is void.
FEEDBACK_MAX = 0.5


def feedback(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    data: Sequence[DriftData],
    deg: Any,
    y_scale: float,
    substeps: int,
) -> float:
    """``F'(d)``: how much one correction pass moves the drift-space estimate per unit of the ``d`` it
    corrected with (strength degradation: the averaged periods brought back to the virgin strength at d,
    the virgin fit re-estimated, the regressor formed at each loop's mean strength under d). The passes
    settle on ``d = F(d)``, so a noise moving F by ``e`` moves the settled d by ``e / (1 - F')``
    (measured on review 33's degr_2p: F' = 0.16, 0.16 on two draws). 0 for stiffness degradation (its d
    is the plain fit's) or when a pass fails (measured once: a refit at d + 3 % ran to mu = 1, beta = gamma
    on a 30x bench case, whose loop the core could not solve); clipped to :data:`FEEDBACK_MAX`."""
    if deg.term != DEGRADATION or not deg.d > 0:
        return 0.0
    out = []
    for sign in (1.0, -1.0):
        dv = deg.d * (1.0 + sign * FEEDBACK_STEP)
        try:
            _, fsx = corrected(exps, sx, fit, dv, y_scale, substeps, deg.term)
            moved = fit_from(fsx, fit.params, substeps)
            if moved is None:
                return 0.0
            regs = drift_data(exps, sx, moved, y_scale, substeps, strength=strengths(len(exps), data, dv))
        except BudgetExceededError:  # a limit the user set
            raise
        except BoucWenIdError:  # a pass the core cannot solve (a fit run to mu = 1, beta = gamma): no gain
            return 0.0
        if [dd.index for dd in regs] != [dd.index for dd in data]:
            return 0.0
        out.append(_estimate(data, regs, deg.term))
    gain = (out[0] - out[1]) / (2.0 * FEEDBACK_STEP * deg.d)
    return min(max(gain, 0.0), FEEDBACK_MAX) if math.isfinite(gain) else 0.0


def spread(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    data: Sequence[DriftData],
    deg: Any,
    y_scale: float,
    substeps: int,
) -> tuple[float, float]:
    """``(regressor_variance, feedback)`` of ``deg`` at ``fit``, the fit ``data`` were formed at (strength
    degradation: at each loop's mean strength under ``deg.d``; stiffness degradation: the plain fit)."""
    args = (exps, sx, fit, data, deg, y_scale, substeps)
    strength = strengths(len(exps), data, deg.d) if deg.term == DEGRADATION else None
    return regressor_variance(*args, strength), feedback(*args)


def added(deg: Any, extra: float, gain: float, y_scale: float) -> Any:
    """``deg`` with the regressor's variance ``extra`` (scaled, from :func:`regressor_variance`) added to
    its standard error (physical units, 1/[y]^2) and the sum amplified by the passes' feedback ``gain``
    (:func:`feedback`)."""
    if not (extra >= 0 and math.isfinite(deg.standard_error)):
        return deg
    var = deg.standard_error**2 + extra / y_scale**4
    return replace(deg, standard_error=math.sqrt(var) / (1.0 - gain))
