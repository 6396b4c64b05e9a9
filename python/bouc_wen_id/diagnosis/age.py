"""The unrecorded age of a degrading specimen: how far each experiment had degraded before its record.

A strength degradation (``nu = 1 + delta_nu e``, ``e`` the dissipated energy) is corrected on the averaged
periods by simulating each experiment from the virgin state through its declared settling
(``DiagExperiment.lead_periods``) and its recorded periods (``drift.corrected``). A lab that drove the
specimen before recording (a settling it does not declare, earlier runs on the same specimen) hands over
records that start already aged, each by its own energy ``e0_i``: the averaged loops then sit at strengths
``1 + delta_nu (e0_i + ...)`` that differ between experiments by more than the drift over a record, which
shared beta and gamma cannot follow, and the steady fit is left with "unexplained structure".

Which ages the record can tell (the parameterisation):

* A **common** age (the same ``e0`` for every experiment) is exactly a different virgin state: with
  ``nu = (1 + delta_nu e0)(1 + delta_nu' (e - e0))``, ``delta_nu' = delta_nu / (1 + delta_nu e0)``, beta and
  gamma absorb the first factor. It is not identifiable, so the youngest experiment is taken as the virgin
  state and the values (beta, gamma, delta_nu) are those at its first recorded period.
* The **differences** are: each experiment's loop shows its own strength through its saturation level,
  which its own gain and phase (G free per experiment) do not absorb. So the model carries one age per
  experiment beyond the youngest, ``m - 1`` parameters, each ``>= 0`` relative to the youngest, kept only
  when their F-test on the steady fit passes (else the records start as declared, as before).
* One shared count of unrecorded periods (``e0_i = N E_i``) or ages accumulated over experiments run in
  a known order on one specimen are special cases of these free ages, tied to a history the files do not
  say (a lab's settling is often a time, not a number of periods; the recording order is rarely given).
  The free ages are the honest general case; their values say which history fits.

Stiffness degradation has no such parameter: its first-order effect on an averaged loop is the loop at the
gain ``|G_i| / eta_i``, which each experiment's own free gain already absorbs.

The ages are fitted by the same simulation as the correction: an age of ``a_i`` periods is ``a_i`` more
periods of the experiment's own drive simulated before its record (fractional ages between the two whole
counts), so the energy follows the degrading loop exactly as the term does. Each pass projects the steady
fit's residual onto the per-experiment strength columns ``J_i = dy/d ln nu`` beside the shared and own
columns (Gauss-Newton; the common direction is the null space above) and converts the strength differences
to periods through the energy per period, ``a_i = Delta ln nu_i / (d E_i)``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..augmented import AugExperiment, AugFit, augmented_output
from ..terms import Asymmetry
from . import free_dc
from .data import DiagExperiment
from .drift import DEGRADATION, DegradationTest, corrected, regressors
from .fitting import best_of, fit_from
from .result import Diagnosis
from .select import dof_of

FloatArray = NDArray[np.float64]

#: Gauss-Newton passes of the ages (each: correct, refit, project), and the change in periods that ends them.
AGE_PASSES = 5
AGE_TOL = 0.25
#: Largest standard error of an age (in energy, in periods of the most dissipative experiment's drive) that
#: is said and may anchor the youngest record: below saturation a loop hardly shows its strength (measured:
#: 48-62 of its own periods at x = 0.8 of saturation in tests/test_unrecorded_age.py; 0.4 periods of the
#: most dissipative drive for our bench's low stroke, studies/unrecorded_age.py, which is determined).
AGE_SE_MAX = 1.0
#: Smallest age span kept, in periods of the most dissipative experiment's drive (see :func:`estimate`).
AGE_MIN_SPAN = 1.5
#: Kill switch (tests compare with and without).
ENABLED = True


def _eligible(e: DiagExperiment) -> bool:
    """Experiments ``drift.corrected`` simulates (a block record and a known lead)."""
    return e.blocks >= 2 and math.isfinite(e.lead_periods)


def _strength_steps(
    fsx: Sequence[AugExperiment], fit: AugFit, keep: Sequence[int], substeps: int
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(Delta ln nu_i, E_i, se_i)`` for the experiments ``keep``: the residual's per-experiment strength
    coefficients (least squares beside the shared and own columns; their common part is arbitrary, the
    virgin strength's), each loop's energy per period (scaled units) and each coefficient's standard
    error against its own experiment's gain and phase."""
    par = fit.params
    m = len(keep)
    n_shared = 3 + len(par.terms)
    cols_n = n_shared + 2 * m + m
    rows_a, rows_b, energies = [], [], []
    for k, i in enumerate(keep):
        a = fsx[i]
        out = augmented_output(a, par, i, substeps=substeps, jacobian=True)
        jac = out.jacobian
        strength = par.beta * jac[:, 0] + par.gamma * jac[:, 1]
        if Asymmetry.kind in par.terms:
            t = par.terms.index(Asymmetry.kind)
            strength = strength + float(par.values[t]) * jac[:, 3 + t]
        block = np.zeros((a.ybar.size, cols_n))
        block[:, :n_shared] = jac
        block[:, n_shared + 2 * k : n_shared + 2 * k + 2] = out.own_jacobian
        block[:, n_shared + 2 * m + k] = strength
        root = math.sqrt(a.weight)
        rows_a.append(root * free_dc.centred(a, block))
        rows_b.append(root * free_dc.centred(a, a.ybar - out.y))
        energies.append(regressors(a, fit, i, substeps)[2])
    mat = np.vstack(rows_a)
    scale = np.linalg.norm(mat, axis=0)
    scale[scale == 0] = 1.0
    sol = np.linalg.lstsq(mat / scale, np.concatenate(rows_b), rcond=1e-10)[0] / scale
    c = sol[n_shared + 2 * m :]
    # Each strength's standard error against its own experiment's gain and phase (the noise at 1 in these
    # units): below saturation the loop hardly shows its strength, and its age is not determined.
    se = np.empty(m)
    for k, rows in enumerate(rows_a):
        own = rows[:, [n_shared + 2 * k, n_shared + 2 * k + 1]]
        col = rows[:, n_shared + 2 * m + k]
        resid = col - own @ np.linalg.lstsq(own, col, rcond=None)[0]
        norm = float(np.linalg.norm(resid))
        se[k] = 1.0 / norm if norm > 0 else math.inf
    return c, np.asarray(energies, dtype=np.float64), se


def estimate(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    deg: DegradationTest,
    y_scale: float,
    substeps: int,
    alpha: float,
) -> Optional[tuple[list[DiagExperiment], AugFit, DegradationTest]]:
    """The experiments with their unrecorded ages (``age_periods``), the fit of their corrected periods and
    ``deg`` carrying the ages, when the ages' F-test passes; else None (the ages tried are in ``deg`` only
    through :func:`tried`).

    ``fit`` is the virgin-strength fit of the periods corrected as declared (ages 0), ``deg`` the named
    strength degradation (its scaled ``d``).
    """
    keep = [i for i, e in enumerate(exps) if _eligible(e)]
    # A drifting output gain fits the drift as well (gain_drift.py): a gain that differs between records
    # gives the strength differences the ages fit, so they are not read as ageing.
    if not ENABLED or deg.term != DEGRADATION or len(keep) < 2 or not deg.d > 0 or deg.gain_alternative:
        return None
    ages = np.zeros(len(exps))
    sd = np.full(len(exps), math.inf)
    per = np.zeros(len(exps))
    best, cost0 = fit, fit.cost
    aged = list(exps)
    for _ in range(AGE_PASSES):
        aged = [replace(e, age_periods=float(a)) for e, a in zip(exps, ages)]
        _, fsx = corrected(aged, sx, best, deg.d, y_scale, substeps, deg.term)
        refit = best_of([fit_from(fsx, best.params, substeps)])
        if refit is None:
            return None
        best = refit
        dln, energy, se = _strength_steps(fsx, best, keep, substeps)
        ok = energy > 0
        idx = np.asarray(keep)[ok]
        step = np.zeros(len(exps))
        step[idx] = dln[ok] / (deg.d * energy[ok])
        sd = np.full(len(exps), math.inf)
        # In energy, in units of the most dissipative drive's period: a low-amplitude loop dissipates little
        # per period, so its age in its own periods is uncertain though its energy is well determined.
        # At the noise level, not inflated by the fit's misfit: the misfit before the ages are fitted is the
        # ages' own (blind degradation:30:5, chi2/dof 60 at the start, left no age determined).
        sd[idx] = se[ok] / deg.d / float(np.max(energy[ok]))
        sure = [i for i in keep if sd[i] <= AGE_SE_MAX]
        if not sure:
            return None
        # Anchored in energy, not in periods: the null direction is one common energy (a common number of
        # periods is not, the energy per period differs between experiments).
        per = np.zeros(len(exps))
        per[idx] = energy[ok]
        e0 = (ages + step) * per
        e0 = bounded(np.maximum(e0 - float(np.min(e0[sure])), 0.0), sure)
        moved = np.zeros(len(exps))
        moved[idx] = e0[idx] / per[idx] - ages[idx]
        ages[idx] = e0[idx] / per[idx]
        if float(np.max(np.abs(moved[sure]))) < AGE_TOL:
            break
    aged = [replace(e, age_periods=float(a)) for e, a in zip(exps, ages)]
    _, fsx = corrected(aged, sx, best, deg.d, y_scale, substeps, deg.term)
    final = best_of([fit_from(fsx, best.params, substeps)])
    if final is None:
        return None
    p = _f_p(cost0, final.cost, len(keep) - 1, dof_of(fsx, final) - (len(keep) - 1))
    # Material: the oldest determined record at least AGE_MIN_SPAN periods of the most dissipative drive
    # beyond the youngest. Below that an age is within the correction's own approximation (first order in
    # the strength change): on our bench's fresh records at 30x (delta_nu 2.4e-3) ages of at most 0.6 such
    # periods passed the F-test (p 1.5e-7) and said "the specimen had aged" of records that had not.
    big = float(np.max(per)) if np.any(per > 0) else 0.0
    span = max((float(ages[i] * per[i]) for i in range(len(exps)) if sd[i] <= AGE_SE_MAX), default=0.0)
    material = big > 0 and span >= AGE_MIN_SPAN * big
    if not (math.isfinite(p) and p < alpha and final.cost < cost0 and material):
        return list(exps), fit, replace(deg, age_p_value=p)
    # The energy of those periods, at the virgin loop's energy per period (first order).
    unit = [regressors(fsx[i], final, i, substeps)[2] if ages[i] > 0 else 0.0 for i in range(len(exps))]
    energy_phys = tuple(float(a) * float(e) * y_scale**2 for a, e in zip(ages, unit))
    said = clause(exps, ages, energy_phys, p, sd <= AGE_SE_MAX)
    ages_t = tuple(float(a) for a in ages)
    sure_t = tuple(bool(v <= AGE_SE_MAX) for v in sd)
    got = replace(
        deg, age_periods=ages_t, age_energy=energy_phys, age_determined=sure_t, age_p_value=p, age_clause=said
    )
    return aged, final, got


def bounded(e0: FloatArray, sure: Sequence[int]) -> FloatArray:
    """The anchored ages in energy ``e0`` with those not determined (not in ``sure``) at most the oldest
    determined one's.

    A loop below saturation hardly shows its strength: its Gauss-Newton step is noise, and over its small
    energy per period it reads as an absurd number of periods. Review 44 (nu-10-C-3, a loop at half its
    saturation): 0.083 +- 0.114 in ln nu at 1.4e-3 energy per period put 796551 periods before the record,
    whose simulation asked for 2e8 samples (the determined records spanned 2.5 periods, e0 = 15.6). The
    record says nothing of such an age, so it is not extrapolated beyond the history the determined records
    show (0 when none is older than the youngest).
    """
    out = np.array(e0, dtype=np.float64)
    cap = float(np.max(out[list(sure)])) if len(sure) else 0.0
    loose = np.ones(out.size, dtype=bool)
    loose[list(sure)] = False
    out[loose] = np.minimum(out[loose], cap)
    return out


def _f_p(c0: float, c1: float, k: int, dof1: int) -> float:
    """P-value of the nested F-test of ``k`` added parameters (the residual variance per dof never below the
    noise floor, 1 in these units, as ``select.f_test``)."""
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    if k < 1 or dof1 < 1 or not (math.isfinite(c0) and math.isfinite(c1)) or c1 <= 0 or c0 <= c1:
        return 1.0 if math.isfinite(c0) and math.isfinite(c1) else math.nan
    f = (c0 - c1) / k / max(c1 / dof1, 1.0)
    return float(fdtrc(k, dof1, f))


def clause(
    exps: Sequence[DiagExperiment],
    ages: FloatArray,
    energy: Sequence[float],
    p: float,
    sure: NDArray[np.bool_],
) -> str:
    """The verdict's clause of adopted ages: what the fit assumed of the specimen's history (the ages not
    determined, of loops that hardly show their strength, named apart)."""
    young = min((i for i, e in enumerate(exps) if sure[i]), key=lambda i: float(ages[i]))
    parts = [
        f"{e.source} by {a:.3g} (e = {en:.3g} [y]^2)"
        for e, a, en, ok in zip(exps, ages, energy, sure)
        if ok and a > 0
    ]
    loose = [e.source for e, ok in zip(exps, sure) if not ok and _eligible(e)]
    vague = (
        f"; the age of {', '.join(loose)} is not determined (a loop below saturation hardly shows its "
        "strength)"
        if loose
        else ""
    )
    return (
        "; the specimen had aged before the first recorded period (an unrecorded age fitted per experiment, "
        f"F-test p = {p:.2g}), in periods of each experiment's own drive beyond {exps[young].source}'s: "
        f"{', '.join(parts) or 'none'}{vague}; {exps[young].source} is taken as the virgin state (a common "
        "age cannot be told from the virgin strength): the values are those at its first recorded period; "
        "an output gain that differed between the records (a sensor's calibration) shifts the loops' "
        "strengths alike, which the averaged loops cannot tell from an age (the drift within each record is "
        "degradation's beyond a drifting gain)"
    )


def with_clause(d: Diagnosis) -> Diagnosis:
    """``d`` with the ages' clause after its verdict when it names the strength degradation with ages."""
    deg = d.degradation
    if deg is None or not getattr(deg, "age_clause", "") or all(t.term != DEGRADATION for t in d.named):
        return d
    return replace(d, verdict=d.verdict + deg.age_clause)


__all__ = ["estimate", "bounded", "clause", "with_clause", "AGE_PASSES", "AGE_TOL", "AGE_MIN_SPAN", "ENABLED"]
