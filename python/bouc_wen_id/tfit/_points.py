"""The frequency-response points of a fit: read, checked, sorted, and their whitening of ``(Re G, Im G)``."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InsufficientDataError, InvalidParameterError, NonFiniteError

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..result import IdentificationResult

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Two frequencies closer than this (relative) are one frequency tested twice: their points are pooled.
DUPLICATE_RTOL = 1e-9


@dataclass(frozen=True)
class _Points:
    omega: FloatArray  # rad/s, sorted
    g: ComplexArray
    white: FloatArray  # (k, 2, 2): L_i^-1, whitening of (Re, Im)
    weighted: bool


def _points(
    result: Optional[IdentificationResult],
    omega: Optional[ArrayLike],
    response: Optional[ArrayLike],
    covariance: Optional[ArrayLike],
) -> _Points:
    if result is not None:
        if omega is not None or response is not None or covariance is not None:
            raise InvalidParameterError("give either an identification result or omega/response, not both")
        w = result.frequencies
        g = result.frequency_response
        gains = result.gains
        cov: Optional[FloatArray] = None
        full = None if result.covariance is None else np.asarray(result.covariance, dtype=np.float64)
        # The plain refined layout [beta, gamma, mu, |G_0|, phi_0, ...]; any other (a model with terms)
        # falls back to the per-experiment standard errors.
        if full is not None and full.shape == (3 + 2 * w.size, 3 + 2 * w.size):
            cov = np.stack([full[3 + 2 * i : 5 + 2 * i, 3 + 2 * i : 5 + 2 * i] for i in range(w.size)])
        elif all(e.gain_se is not None and e.phase_se is not None for e in result.experiments):
            var = np.array([[e.gain_se or 0.0, e.phase_se or 0.0] for e in result.experiments]) ** 2
            cov = np.stack([np.diag(v) for v in var])
    else:
        if omega is None or response is None:
            raise InvalidParameterError("give an identification result, or omega and response")
        try:  # text, ragged lists and objects are the user's mistake, named as such
            w = np.asarray(omega, dtype=np.float64)
            g = np.asarray(response, dtype=np.complex128)
            cov = None if covariance is None else np.array(covariance, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise InvalidParameterError(
                f"omega, response and covariance must be numeric arrays: {exc}"
            ) from None
        if w.ndim != 1 or g.shape != w.shape:
            raise InvalidParameterError(
                f"omega and response must be 1-D of the same length, got shapes {w.shape} and {g.shape}"
            )
        gains = np.abs(g)
        if cov is not None and cov.shape != (w.size, 2, 2):
            raise InvalidParameterError(
                f"covariance must have shape (k, 2, 2) (of |G|, phi per point), got {cov.shape}"
            )
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(g))):
        raise NonFiniteError("the frequencies or the response points hold NaN or infinity")
    if np.any(w <= 0.0):
        raise InvalidParameterError("every frequency must be > 0 rad/s")
    if np.any(gains <= 0.0):
        raise InvalidParameterError("every |G| point must be > 0")
    order = np.argsort(w)
    w, g = w[order], g[order]
    white = np.empty((w.size, 2, 2))
    if cov is not None:
        cov = cov[order]
        if not np.all(np.isfinite(cov)):
            raise NonFiniteError("the covariance holds NaN or infinity")
        for i in range(w.size):
            gi, phi = abs(g[i]), -np.angle(g[i])
            # (Re, Im) = (|G| cos phi, -|G| sin phi): the delta method maps the (|G|, phi) covariance.
            jac = np.array([[math.cos(phi), -gi * math.sin(phi)], [-math.sin(phi), -gi * math.cos(phi)]])
            c = jac @ cov[i] @ jac.T
            c = 0.5 * (c + c.T)
            try:
                chol = np.linalg.cholesky(c)
            except np.linalg.LinAlgError:
                raise InvalidParameterError(
                    f"the covariance of point {i} (omega = {w[i]:g}) is not positive definite"
                ) from None
            white[i] = np.linalg.inv(chol)
    else:
        for i in range(w.size):
            white[i] = np.eye(2) / abs(g[i])  # relative error: each point counts alike
    w, g, white = _pool(w, g, white)
    if w.size < 2:
        raise InsufficientDataError(
            f"a transfer function needs at least 2 distinct frequencies, got {w.size}"
        )
    return _Points(w, g, white, cov is not None)


def _pool(w: FloatArray, g: ComplexArray, white: FloatArray) -> tuple[FloatArray, ComplexArray, FloatArray]:
    """The points of one frequency (closer than :data:`DUPLICATE_RTOL`, e.g. two amplitudes of one design)
    pooled into one: G is linear, so the model holds one value per frequency; the pooled point is their
    inverse-covariance weighted mean in ``(Re, Im)`` and its information is the sum of theirs."""
    groups: list[list[int]] = []
    for i in range(w.size):
        if groups and w[i] - w[groups[-1][0]] <= DUPLICATE_RTOL * w[i]:
            groups[-1].append(i)
        else:
            groups.append([i])
    if len(groups) == w.size:
        return w, g, white
    ws, gs, whites = [], [], []
    for idx in groups:
        info = sum((white[i].T @ white[i] for i in idx), np.zeros((2, 2)))
        rhs = sum((white[i].T @ white[i] @ np.array([g[i].real, g[i].imag]) for i in idx), np.zeros(2))
        re, im = np.linalg.solve(info, rhs)
        ws.append(float(np.mean(w[idx])))
        gs.append(complex(re, im))
        whites.append(np.linalg.cholesky(info).T)
    return np.array(ws), np.array(gs, dtype=np.complex128), np.array(whites)


def _whiten(points: _Points, z: ComplexArray) -> FloatArray:
    """``(k, 2)`` whitened ``[Re, Im]`` of complex residuals (or Jacobian columns when z is (k, p))."""
    if z.ndim == 1:
        out: FloatArray = np.einsum("kij,kj->ki", points.white, np.stack([z.real, z.imag], axis=1))
        return out
    out = np.einsum("kij,kjp->kip", points.white, np.stack([z.real, z.imag], axis=1))
    return out
