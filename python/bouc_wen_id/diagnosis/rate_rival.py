"""Whether a named viscous damping could be a rate-independent loop (issue 18: a name users can trust blind).

Viscous damping claims a force ``c v``: one ``c`` at every frequency. A loop outside the library that does not
depend on the rate (a Prandtl-Ishlinskii or Iwan distribution of stops, dry friction spread over travel)
dissipates the same energy per cycle at every frequency; a viscous term fitted to it takes its quadrature
part, so the value it needs at experiment ``i`` falls as ``1 / omega_i`` (``1 / (omega_i |g_i|)`` when the
loop acts on u and the damping is named on x, whose velocity is ``omega |g| U``), with a factor of its own at
each amplitude (the loop's area need not grow as the amplitude squared). The law test asks only "one value
for every experiment" against every direction at once (m - 1 degrees of freedom); with the per-experiment
values a few standard errors wide it passes (review 33, ``pi_u_10``: a PI loop on u, 10x, first-order G with
a delay, three frequencies x two amplitudes: viscous damping on x named, law p = 0.11, the final model
adequate at p = 0.98). This module asks the converse: do the per-experiment values (the law test's own
step, :func:`.law.freed_step`) refuse the rate-independent law? When they do not, at :data:`LAW_ALPHA`, the
verdict says the frequencies tested do not tell the viscous term from such a loop, and which experiment
would (frequencies further apart). Said only, never a change of name: a true viscous damping over
frequencies a factor 4 apart refuses the rival (its values are one, the rival's fall by 4).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Optional

import numpy as np

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS, Viscous, ViscousX
from .law import freed_step, law_rows
from .result import NamedTerm
from .select import LAW_ALPHA

#: The words that mark the rate caveat in a verdict.
RATE_MARK = "a rate-independent loop"


def rival_p_values(
    exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int
) -> Optional[tuple[float, float]]:
    """p-values of the rate-independent law for the damping ``term`` of ``fit``: its per-experiment values
    ``c_i = b_a / (omega_i s_i)``, one ``b_a`` per input amplitude, ``s_i = 1`` (a loop on the term's own
    variable) and ``s_i = |g_i|`` (a loop on u seen by a damping on x) or ``1 / |g_i|`` (a loop on x seen by
    one on u); a generalised least-squares fit with
    the law test's sandwich covariance, its residual chi-square on ``m - (number of amplitudes)`` degrees of
    freedom. None when the values cannot be had or no amplitude has two frequencies (nothing to compare)."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    step = freed_step(exps, fit, term, substeps)
    if step is None or term not in fit.params.terms:
        return None
    beta, cov, scale, cols = step
    rows = law_rows(exps, term)
    c = cols[0][rows]
    value = float(fit.params.values[fit.params.terms.index(term)])
    vals = value + beta[c] / scale[c]
    vcov = cov[np.ix_(c, c)] / np.outer(scale[c], scale[c])
    om = np.array([exps[i].frequency for i in rows])
    amp = np.array([exps[i].amplitude for i in rows])
    groups = _groups(amp)
    if not any(len(set(np.round(om[g], 6))) >= 2 for g in groups):
        return None
    gains = np.abs(np.asarray(fit.params.gains, dtype=float))[rows]
    w, vec = np.linalg.eigh(vcov)
    keep = w > 1e-10 * float(w.max())
    if not np.any(keep):
        return None
    # whitening of the values by the kept eigen-directions (a pseudo-inverse GLS)
    wh = (vec[:, keep] / np.sqrt(w[keep])).T
    out = []
    # the loop at the other place: on u for a damping named on x (its velocity omega |g| U), on x for one
    # named on u (the loop's amplitude |g| U)
    other = gains if term == ViscousX.kind else 1.0 / gains
    for s in (np.ones_like(om), other):
        x = np.zeros((om.size, len(groups)))
        for j, g in enumerate(groups):
            x[g, j] = 1.0 / (om[g] * s[g])
        a, r = wh @ x, wh @ vals
        coef = np.linalg.lstsq(a, r, rcond=None)[0]
        chi2 = float(np.sum((r - a @ coef) ** 2))
        df = int(np.count_nonzero(keep)) - np.linalg.matrix_rank(a)
        out.append(float(chdtrc(df, chi2)) if df > 0 and math.isfinite(chi2) else math.nan)
    return out[0], out[1]


def _groups(amp: np.ndarray) -> list[np.ndarray]:
    """Indices of the experiments at each input amplitude (equal within 1 %)."""
    out: list[np.ndarray] = []
    used = np.zeros(amp.size, dtype=bool)
    for i in range(amp.size):
        if used[i]:
            continue
        g = np.flatnonzero(~used & (np.abs(amp - amp[i]) <= 0.01 * abs(amp[i])))
        used[g] = True
        out.append(g)
    return out


def rate_text(named: Sequence[NamedTerm], exps: Sequence[AugExperiment], fit: AugFit, substeps: int) -> str:
    """The verdict's word on a named viscous damping whose per-experiment values do not refuse the
    rate-independent law (:func:`rival_p_values`, either reading, at :data:`LAW_ALPHA`): what the data could
    not exclude, and the experiment that would. Empty otherwise."""
    out = ""
    for t in named:
        p = not_refused(exps, fit, t.term, substeps)
        if p is not None:
            out += clause(t.term, p, [float(e.frequency) for e in exps])
    return out


def not_refused(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> Optional[float]:
    """The larger p of :func:`rival_p_values` when ``term`` is a viscous damping of ``fit`` whose values do
    not refuse the rate-independent law (either reading, at :data:`LAW_ALPHA`); None otherwise."""
    if term not in (Viscous.kind, ViscousX.kind) or term not in fit.params.terms:
        return None
    ps = rival_p_values(exps, fit, term, substeps)
    if ps is None or not any(math.isfinite(p) and p >= LAW_ALPHA for p in ps):
        return None
    return max(v for v in ps if math.isfinite(v))


def clause(term: str, p: float, frequencies: Sequence[float], where: str = "") -> str:
    """The verdict's clause on a viscous ``term`` whose values do not refuse the rival (:func:`not_refused`'s
    ``p``) over the ``frequencies`` tested; ``where``: the conditions where they do not (across)."""
    om = sorted({round(float(w), 6) for w in frequencies})
    at = f" at {where}" if where else ""
    return (
        f"; {TERMS[term].place_label()} may stand for {RATE_MARK} outside the library (a "
        "Prandtl-Ishlinskii or Iwan distribution of stops, friction spread over travel): such a loop "
        "dissipates alike at every frequency, so the damping value it needs falls as 1/frequency, and "
        f"the values per experiment{at} do not refuse that (p = {p:.2g}) over the frequencies tested "
        f"({om[0]:.3g}-{om[-1]:.3g} rad/s); experiments over a wider frequency range (a factor 10 or "
        "more) at one amplitude would separate them (a viscous value stays one, the loop's falls)"
    )


__all__ = ["RATE_MARK", "clause", "not_refused", "rate_text", "rival_p_values"]
