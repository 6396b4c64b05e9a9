"""The branch-shape test of Dahl friction (issue 18: a name users can trust blind).

Dahl's element claims more than one level and one pre-sliding stiffness shared by all experiments (the law
test, :func:`select.law_test`): it claims the shape of each branch, an exponential approach to its level
over the travel from a reversal. Dahl (1968) wrote the branch with an exponent, ``dF/dv = sigma |1 - s F /
Fc|^n``; the library's element is ``n = 1``. Other hysteresis families give other branches: a distribution
of elastic-perfectly-plastic stops (Iwan, Prandtl-Ishlinskii, Masing) a piecewise-linear one that reaches
its level after a finite travel (as ``n < 1`` does), Dahl's brittle exponent ``n = 2`` a slower one. Such a
loop is fitted by the ``n = 1`` element with the misfit in the harmonics the branch's curvature fills.

:func:`shape_test` is a Wald test of ``n = 1``: the column ``dF/dn`` at ``n = 1`` (:func:`exponent_column`,
the steady branch under each experiment's sine, solved here in NumPy: ``g = 1 - s F / Fc`` obeys ``dg/dxi
= -r g^n`` over the travel ``xi`` in units of the amplitude, ``r = sigma |a| / Fc``, with the steady
condition ``g(2) = 2 - g(0)``) added beside every parameter of the fit (the shared ones, each experiment's
own |G| and phase), one Gauss-Newton step, its coefficient against its sandwich variance whose meat is each
experiment's residual spectrum (:func:`spectral_meat`, as the law test's), chi-square(1).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..augmented import AugExperiment, AugFit, augmented_output
from ..errors import BudgetExceededError
from ..terms import TERMS, Place
from . import free_dc

FloatArray = NDArray[np.float64]

#: Half-width, in harmonics, of the window that smooths a residual's periodogram in the law test.
LAW_WINDOW = 2
#: Step in the exponent of the central difference of :func:`exponent_column`.
EXPONENT_STEP = 1e-3


def spectral_meat(x: FloatArray, r: FloatArray, scale: float) -> FloatArray:
    """``X^T Sigma X`` for one experiment whose residual ``r`` over its period is a stationary periodic
    process: Sigma is circulant, its eigenvalues the periodogram of ``r`` smoothed over
    ``+-``:data:`LAW_WINDOW` harmonics, times ``scale`` (the fit's degrees of freedom), and never below
    the noise floor (1 in weighted units)."""
    p = r.size
    power = np.abs(np.fft.fft(r)) ** 2 / p * scale
    lam = sum(np.roll(power, o) for o in range(-LAW_WINDOW, LAW_WINDOW + 1)) / (2 * LAW_WINDOW + 1)
    f = np.fft.fft(x, axis=0)
    return np.asarray(np.real((f.conj().T * np.maximum(lam, 1.0)) @ f) / p, dtype=np.float64)


def _branch(xi: FloatArray, r: float, n: float) -> FloatArray:
    """``g(xi)`` of the steady branch with exponent ``n`` (``g(0)`` solved from ``g(2) = 2 - g(0)``)."""
    q = 1.0 - n

    def g_of(g0: float, x: FloatArray) -> FloatArray:
        if abs(q) < 1e-12:
            return np.asarray(g0 * np.exp(-r * x), dtype=np.float64)
        base = np.maximum(g0**q - q * r * x, 0.0)
        return np.asarray(np.where(base > 0.0, base ** (1.0 / q), 0.0), dtype=np.float64)

    lo, hi = 1.0, 2.0  # g(2) + g0 - 2 rises with g0: <= 0 at 1, >= 0 at 2
    two = np.array([2.0])
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if float(g_of(mid, two)[0]) + mid - 2.0 > 0.0:
            hi = mid
        else:
            lo = mid
    return g_of(0.5 * (lo + hi), xi)


def exponent_column(a: float, psi0: float, fc: float, sigma: float, p: int) -> FloatArray:
    """``dF/dn`` at ``n = 1`` of the steady Dahl loop on the P-point grid (the grid and branches of
    ``reference/dahl.py``: ``v_j = a cos(psi_j)``, ``psi_j = 2 pi j / P + psi0``); zeros where the element
    is absent (``Fc = 0``) or dry (``sigma`` infinite)."""
    aa = abs(a)
    if not (fc > 0.0 and sigma >= 0.0 and math.isfinite(sigma * aa / fc)):
        return np.zeros(p)
    r = sigma * aa / fc
    shift = math.pi if a < 0.0 else 0.0
    psi = np.mod(2.0 * math.pi * np.arange(p) / p + psi0 + shift, 2.0 * math.pi)
    falling = psi <= math.pi
    s = np.where(falling, -1.0, 1.0)
    xi = np.where(falling, 1.0 - np.cos(psi), 1.0 + np.cos(psi))
    h = EXPONENT_STEP
    dg = (_branch(xi, r, 1.0 + h) - _branch(xi, r, 1.0 - h)) / (2.0 * h)
    return np.asarray(-s * fc * dg, dtype=np.float64)


def has_branch(term: str) -> bool:
    """Whether ``term`` is a two-parameter element (Dahl friction) whose branch shape :func:`shape_test`
    tests beside its law."""
    cls = TERMS.get(term)
    return cls is not None and bool(cls.companion)


def shape_test(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> float:
    """p-value of Dahl friction's branch shape (exponent 1) at ``fit`` (module docstring); NaN for a term
    without a branch (not a two-parameter element), an absent element, or a model the core cannot
    differentiate."""
    par = fit.params
    if not has_branch(term):
        return math.nan
    cls = TERMS[term]
    if term not in par.terms or cls.companion not in par.terms:
        return math.nan
    fc = float(par.values[par.terms.index(term)])
    sigma = float(par.values[par.terms.index(cls.companion)])
    cols = []
    for i, e in enumerate(exps):
        if cls.acts_on == Place.X:
            a, psi0 = e.amplitude * float(par.gains[i]), -float(par.phases[i])
        else:
            a, psi0 = e.amplitude, e.grid_phase
        cols.append(exponent_column(a, psi0, fc, sigma, e.ybar.size)[:, None])
    return extra_wald(exps, fit, substeps, cols)


def extra_wald(
    exps: Sequence[AugExperiment], fit: AugFit, substeps: int, extra: Sequence[FloatArray]
) -> float:
    """p-value of the Wald test that the k columns ``extra[i]`` (per experiment, shape (P_i, k)) add
    nothing at ``fit``: added beside every parameter of the fit (the shared ones, each experiment's own
    |G| and phase), one Gauss-Newton step, their k coefficients against their sandwich covariance whose
    meat is each experiment's residual spectrum (:func:`spectral_meat`), chi-square(k). NaN for a model
    the core cannot differentiate or columns that are all zero."""
    k = int(extra[0].shape[1]) if extra else 0
    got = sandwich_step(exps, fit, substeps, extra)
    if got is None or k < 1:
        return math.nan
    step, cov = got
    return wald_p(step[-k:], cov[-k:, -k:])


def sandwich_step(
    exps: Sequence[AugExperiment], fit: AugFit, substeps: int, extra: Sequence[FloatArray]
) -> tuple[FloatArray, FloatArray] | None:
    """One Gauss-Newton step at ``fit`` of its parameters (shared ``[beta, gamma, mu, terms]``, then each
    experiment's |G| and phase) and the extra columns ``extra[i]`` (per experiment, (P_i, k)), with the
    step's sandwich covariance (meat: each experiment's residual spectrum, :func:`spectral_meat`), in the
    parameters' own units; None for a model the core cannot differentiate or extra columns all zero."""
    par = fit.params
    m, ns = len(exps), 3 + len(par.terms)
    k = int(extra[0].shape[1]) if extra else 0
    xs, res = [], []
    try:
        for i, e in enumerate(exps):
            out = augmented_output(e, par, i, substeps=substeps, jacobian=True)
            x = np.zeros((e.ybar.size, ns + 2 * m + k))
            x[:, :ns] = out.jacobian
            x[:, ns + 2 * i : ns + 2 * i + 2] = out.own_jacobian
            x[:, ns + 2 * m :] = extra[i]
            sw = math.sqrt(e.weight)
            xs.append(sw * free_dc.centred(e, x))  # a free DC (free_dc.py), as select.law_test
            res.append(sw * free_dc.centred(e, e.ybar - out.y))
    except BudgetExceededError:
        raise  # the user's budget is theirs
    except Exception:  # noqa: BLE001 - a model the core cannot differentiate: the shape is not tested
        return None
    xa, r = np.vstack(xs), np.concatenate(res)
    if k < 1 or not (np.all(np.isfinite(xa)) and np.all(np.isfinite(r))) or not np.any(xa[:, -k:]):
        return None
    scale = np.linalg.norm(xa, axis=0) + 1e-300
    xa = xa / scale
    sv = np.linalg.svd(xa, compute_uv=False)
    rank = int(np.sum(sv > 1e-10 * sv[0])) + free_dc.count(exps)  # + the centred DCs' dof
    if r.size - rank < 1:
        return None
    beta = np.linalg.lstsq(xa, r, rcond=1e-10)[0]
    bread = np.linalg.pinv(xa.T @ xa, rcond=1e-12)
    meat = np.zeros_like(bread)
    start = 0
    for x in xs:
        sl = slice(start, start + x.shape[0])
        meat += spectral_meat(xa[sl], r[sl] - xa[sl] @ beta, r.size / (r.size - rank))
        start += x.shape[0]
    cov = bread @ meat @ bread
    return beta / scale, cov / np.outer(scale, scale)


def wald_p(b: FloatArray, cov: FloatArray) -> float:
    """Wald p-value of ``b = 0`` with covariance ``cov``, chi-square(rank)."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    if not (np.all(np.isfinite(cov)) and np.all(np.diag(cov) > 0)):
        return math.nan
    # Scaled to unit diagonal before the pseudo-inverse (the columns' units differ by orders).
    d = np.sqrt(np.diag(cov))
    c = cov / np.outer(d, d)
    stat = float((b / d) @ np.linalg.pinv(c, rcond=1e-12, hermitian=True) @ (b / d))
    ev = np.abs(np.linalg.eigvalsh(c))  # the rank at the pseudo-inverse's own cutoff: the directions it keeps
    df = int(np.sum(ev > 1e-12 * ev.max())) if ev.size else 0
    if df < 1 or not math.isfinite(stat):
        return math.nan
    return float(chdtrc(df, max(stat, 0.0)))


__all__ = ["exponent_column", "extra_wald", "sandwich_step", "shape_test", "spectral_meat"]
