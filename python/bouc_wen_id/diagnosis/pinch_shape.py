"""The band test of pinching (issue 18: a name users can trust blind).

Pinching (Baber & Noori 1986, Foliente 1995) claims more than one ``zeta1`` shared by all experiments (the
law test, :func:`select.law_test`): it claims WHERE the loop slips, a band of w just past the zero crossing
after each reversal, centred at ``q = PINCHING_CENTRE`` and ``zeta2 = PINCHING_WIDTH`` wide (fractions of
the saturation level ``w_u``). A pinched loop is an S on each branch: the tangent stiffness falls in the
band and rises again behind it. Other loops the plain element misses are not: a distribution of stops
(Iwan, Prandtl-Ishlinskii) or a Dahl branch of another exponent turns once after each reversal, its
stiffness falling monotonically along the branch, and the bench named pinching on such loops with its law
holding (Iwan on x at 30x, 3 of 20 cases): the factor ``h`` taken out of the rate somewhere on the branch
removes part of a corner's misfit, with the band wherever it helps most, not where pinching puts it.

:func:`band_test` is a Wald test of the band's place and width at the library's values: the columns
``dw/dq`` and ``dw/dzeta2`` (the steady pinched loop under each experiment's sine, solved here in NumPy:
``dw/dx = h_b(w, s) (1 - zeta1 exp(-((w s - q w_u) / (zeta2 w_u))^2))`` along x, the branches odd-symmetric,
central differences in ``q`` and ``zeta2``) added beside every parameter of the fit (the shared ones, each
experiment's own |G| and phase), one Gauss-Newton step, the two coefficients against their sandwich
covariance whose meat is each experiment's residual spectrum (:func:`shape.extra_wald`, as the Dahl shape
test's), chi-square(2). A pinched loop fitted by the library's pinching leaves both at zero; a corner
fitted by a band pulls the band towards the corner (its centre) or spreads it (its width).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from ..augmented import AugExperiment, AugFit
from ..terms import (
    PINCHING_CENTRE,
    PINCHING_WIDTH,
    TERMS,
    Asymmetry,
    Degradation,
    Distortion,
    Pinching,
    Place,
    Play,
    SeriesDashpot,
    StiffnessDegradation,
)
from .shape import extra_wald

FloatArray = NDArray[np.float64]

#: RK4 steps along each branch of the NumPy loop (travel ``2 |A|``).
BAND_STEPS = 400
#: Relative steps of the central differences in the band's centre and width.
BAND_STEP = 1e-3
#: Terms whose presence beside pinching changes the loop this module solves (the path, the rate or the
#: branches' symmetry): with any of them the band is not tested (NaN).
_NOT_SOLVED = tuple(
    c.kind for c in (Asymmetry, Play, Distortion, SeriesDashpot, Degradation, StiffnessDegradation)
)


def is_pinching(term: str) -> bool:
    """Whether ``term`` is pinching, the term whose band :func:`band_test` tests beside its law."""
    return TERMS.get(term) is Pinching


def _rate(
    w: FloatArray, s: float, beta: float, gamma: float, mu: float, zeta1: float, c: FloatArray, wd: FloatArray
) -> FloatArray:
    """``dw/dx`` on a branch of direction ``s``; ``c``, ``wd``: the band's centre and width in units of w."""
    aw = np.abs(w)
    hb = 1.0 - aw**mu * (beta * s * np.sign(w) + gamma)
    z = (w * s - c) / wd
    return np.asarray(hb * (1.0 - zeta1 * np.exp(-z * z)), dtype=np.float64)


def _falling(
    w0: FloatArray,
    a: FloatArray,
    beta: float,
    gamma: float,
    mu: float,
    zeta1: float,
    c: FloatArray,
    wd: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """The falling branch from ``w0`` at ``x = |A|`` to ``x = -|A|``: ``w`` and ``dw/dx`` on the
    ``BAND_STEPS + 1`` nodes (rows), each column one loop (``a``: its |A|)."""
    n = BAND_STEPS
    hstep = -2.0 * a / n  # dx per step (x falls)
    ws = np.empty((n + 1, w0.size))
    fs = np.empty((n + 1, w0.size))
    w = w0.copy()
    for k in range(n):
        f1 = _rate(w, -1.0, beta, gamma, mu, zeta1, c, wd)
        ws[k], fs[k] = w, f1
        f2 = _rate(w + 0.5 * hstep * f1, -1.0, beta, gamma, mu, zeta1, c, wd)
        f3 = _rate(w + 0.5 * hstep * f2, -1.0, beta, gamma, mu, zeta1, c, wd)
        f4 = _rate(w + hstep * f3, -1.0, beta, gamma, mu, zeta1, c, wd)
        w = w + hstep * (f1 + 2.0 * f2 + 2.0 * f3 + f4) / 6.0
    ws[n], fs[n] = w, _rate(w, -1.0, beta, gamma, mu, zeta1, c, wd)
    return ws, fs


def pinched_loops(
    a: FloatArray, beta: float, gamma: float, mu: float, zeta1: float, centre: FloatArray, width: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """The steady falling branches of pinched Bouc-Wen loops (alpha = 1, no asymmetry), one per column:
    ``w`` and ``dw/dx`` on ``BAND_STEPS + 1`` equal steps of x from ``|A|`` down to ``-|A|``; the top ``w0``
    solves ``w(-|A|) = -w0`` (odd symmetry) by a safeguarded secant. ``centre`` and ``width`` are
    fractions of ``w_u``."""
    a = np.abs(np.asarray(a, dtype=np.float64))
    wu = (1.0 / (beta + gamma)) ** (1.0 / mu) if beta + gamma > 0 else 1.0
    c, wd = np.asarray(centre) * wu, np.asarray(width) * wu
    # F(w0) = w(-|A|; w0) + w0 rises with w0: < 0 at 0, >= 0 at min(|A|, 2 w_u); Illinois false position.
    lo, hi = np.zeros_like(a), np.minimum(a, 2.0 * wu) + 1e-12
    glo = _falling(lo, a, beta, gamma, mu, zeta1, c, wd)[0][-1] + lo
    ghi = _falling(hi, a, beta, gamma, mu, zeta1, c, wd)[0][-1] + hi
    side = np.zeros(a.size)
    w0 = hi
    for _ in range(80):
        w0 = np.where(ghi > glo, (lo * ghi - hi * glo) / np.where(ghi > glo, ghi - glo, 1.0), 0.5 * (lo + hi))
        g = _falling(w0, a, beta, gamma, mu, zeta1, c, wd)[0][-1] + w0
        if np.all(np.abs(g) <= 1e-12 * (1.0 + np.abs(w0))):
            break
        below = g < 0
        # Illinois: halve the value kept twice on the same side.
        ghi = np.where(below & (side < 0), 0.5 * ghi, ghi)
        glo = np.where(~below & (side > 0), 0.5 * glo, glo)
        lo, glo = np.where(below, w0, lo), np.where(below, g, glo)
        hi, ghi = np.where(below, hi, w0), np.where(below, ghi, g)
        side = np.where(below, -1.0, 1.0)
    return _falling(w0, a, beta, gamma, mu, zeta1, c, wd)


def _sample(ws: FloatArray, fs: FloatArray, a: float, psi: FloatArray) -> FloatArray:
    """``w`` at the phases ``psi`` of ``x = |A| cos(psi)`` (falling for ``psi`` in [0, pi], rising, the odd
    image, after), by cubic Hermite interpolation of the branch's nodes."""
    n = ws.size - 1
    psi = np.mod(psi, 2.0 * math.pi)
    falling = psi <= math.pi
    t = np.where(falling, 1.0 - np.cos(psi), 1.0 + np.cos(psi)) / 2.0 * n  # travel in steps
    k = np.clip(np.floor(t).astype(int), 0, n - 1)
    u = t - k
    h = -2.0 * abs(a) / n
    h00, h10 = 2 * u**3 - 3 * u**2 + 1, u**3 - 2 * u**2 + u
    h01, h11 = -2 * u**3 + 3 * u**2, u**3 - u**2
    w = h00 * ws[k] + h10 * h * fs[k] + h01 * ws[k + 1] + h11 * h * fs[k + 1]
    return np.asarray(np.where(falling, w, -w), dtype=np.float64)


def band_columns(
    amps: Sequence[float],
    psi0s: Sequence[float],
    sizes: Sequence[int],
    beta: float,
    gamma: float,
    mu: float,
    zeta1: float,
) -> list[FloatArray]:
    """Per loop (``x_j = a cos(2 pi j / P + psi0)`` on a P-point grid): ``w`` of the steady pinched loop and
    its columns ``dw/dq``, ``dw/dzeta2`` at the library's band (central differences), shape (P, 3); all
    loops solved at once."""
    dq, dz = BAND_STEP * PINCHING_CENTRE, BAND_STEP * PINCHING_WIDTH
    cs = PINCHING_CENTRE + np.array([0.0, dq, -dq, 0.0, 0.0])
    zs = PINCHING_WIDTH + np.array([0.0, 0.0, 0.0, dz, -dz])
    m = len(amps)
    a_all = np.repeat(np.asarray(amps, dtype=np.float64), 5)
    ws, fs = pinched_loops(a_all, beta, gamma, mu, zeta1, np.tile(cs, m), np.tile(zs, m))
    out = []
    for i, (a, psi0, p) in enumerate(zip(amps, psi0s, sizes)):
        shift = math.pi if a < 0.0 else 0.0
        psi = 2.0 * math.pi * np.arange(p) / p + psi0 + shift
        w = [_sample(ws[:, 5 * i + j], fs[:, 5 * i + j], a, psi) for j in range(5)]
        out.append(np.column_stack([w[0], (w[1] - w[2]) / (2 * dq), (w[3] - w[4]) / (2 * dz)]))
    return out


def band_test(exps: Sequence[AugExperiment], fit: AugFit, term: str, substeps: int) -> float:
    """p-value of pinching's band (centre and width at the library's values) at ``fit`` (module
    docstring); NaN for another term, pinching absent or at 0, or a model whose loop this module does not
    solve (asymmetry, play, a distorted input, a series dashpot or degradation beside it)."""
    par = fit.params
    if not is_pinching(term) or term not in par.terms or any(t in par.terms for t in _NOT_SOLVED):
        return math.nan
    zeta1 = float(par.values[par.terms.index(term)])
    beta, gamma, mu = float(par.beta), float(par.gamma), float(par.mu)
    if not (0.0 < zeta1 < 1.0 and beta + gamma > 0.0 and mu > 0.0) or TERMS[term].acts_on != Place.HYSTERESIS:
        return math.nan
    amps = [e.amplitude * float(g) for e, g in zip(exps, par.gains)]
    cols = band_columns(
        amps, [-float(v) for v in par.phases], [e.ybar.size for e in exps], beta, gamma, mu, zeta1
    )
    return extra_wald(exps, fit, substeps, [c[:, 1:] for c in cols])


__all__ = ["band_columns", "band_test", "is_pinching", "pinched_loops"]
