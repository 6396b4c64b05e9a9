"""``fit_transfer_function``: the points, every candidate order fitted, one chosen, its uncertainty."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Literal, Optional, Union

import numpy as np
from numpy.typing import ArrayLike

from ..errors import InsufficientDataError, InvalidParameterError
from ..model import TransferFunction
from ..validation import count, nonnegative_number, real_number
from ._checks import findings
from ._model import _Model
from ._points import _Points, _points, _whiten
from ._refine import _criteria, _Fit, _fit_one
from ._result import OrderCandidate, TransferFunctionFit
from ._select import UNPINNED, _explain, _resonance_warnings, _select, _shapes

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..result import IdentificationResult

#: Highest denominator degree tried by the automatic order selection (issue #11: orders 0..4).
MAX_ORDER = 4


def fit_transfer_function(
    result: Optional[IdentificationResult] = None,
    *,
    omega: Optional[ArrayLike] = None,
    response: Optional[ArrayLike] = None,
    covariance: Optional[ArrayLike] = None,
    order: Union[None, int, tuple[int, int]] = None,
    delay: Union[None, bool, float] = None,
    max_order: int = MAX_ORDER,
    criterion: Literal["aicc", "bic"] = "aicc",
    confidence: Optional[float] = None,
) -> TransferFunctionFit:
    """Fit a stable, proper ``G(s) = exp(-delay s) num(s)/den(s)`` to frequency-response points.

    Parameters
    ----------
    result : IdentificationResult, optional
        The identified points ``G(j omega_i) = |G_i| exp(-j phi_i)`` (alpha-normalised) and their
        covariance: the ``(|G_i|, phi_i)`` blocks of ``result.covariance`` (``method="refined"``), else
        the per-experiment ``gain_se``/``phase_se``.  Without either the points are weighted by their
        relative error and the parameter covariance comes from the residual scatter.
    omega, response, covariance : array_like, optional
        The same given explicitly (instead of ``result``): frequencies in rad/s (> 0; the points of one
        frequency, e.g. two amplitudes, are pooled: G is linear, one value per frequency), complex
        ``G(j omega_i)`` with the library's convention ``G = |G| exp(-j phi)`` (that is, the ordinary
        complex frequency response), and optionally the ``(k, 2, 2)`` covariances of ``(|G_i|, phi_i)``.
    order : int or (int, int), optional
        ``n`` (denominator degree; the numerator degree is then selected in 0..n) or ``(m, n)``.  Default:
        selected over ``0 <= m <= n <= max_order``.
    delay : None, bool or float
        None (default): with and without a fitted delay, selected; True: always fitted; False: none;
        a number >= 0: a known delay in seconds, held fixed.
    max_order : int
        Highest denominator degree of the automatic selection (0..8; default 4).
    criterion : {"aicc", "bic"}
        The information criterion of the selection (on the weighted chi-square).
    confidence : float, optional
        Confidence level of the intervals (default: the result's, else 0.95).

    Returns
    -------
    TransferFunctionFit

    Raises
    ------
    NonFiniteError
        NaN or infinity in the points or their covariance.
    InvalidParameterError
        Non-positive frequencies, a zero |G| point, a covariance that is not positive
        definite, a bad ``order``/``delay``/``criterion``.
    InsufficientDataError
        Fewer than 2 distinct frequencies, or no candidate model with fewer parameters than real equations.

    Warns
    -----
    PoorFitWarning
        When the chosen model's own residuals refute it: a chi-square p-value below
        :data:`~bouc_wen_id.tfit._checks.POOR_FIT_P` (points with a covariance), or a root-mean-square
        relative error above :data:`~bouc_wen_id.tfit._checks.POOR_FIT_RELATIVE` (points without); the
        message says when the points look like an unstable G.
    IdentifiabilityWarning
        When the chosen model has at least as many parameters as real equations (2 per point), a fitted
        resonance peak lies where no point pins it down, a pole sits at the origin (as far as the band can
        tell) or a zero cancels a pole.
    """
    if criterion not in ("aicc", "bic"):
        raise InvalidParameterError(f"criterion must be 'aicc' or 'bic', got {criterion!r}")
    max_order = count("max_order", max_order, 0, 8)
    points = _points(result, omega, response, covariance)
    if confidence is None:
        confidence = result.confidence if result is not None else 0.95
    confidence = real_number("confidence", confidence)
    if not 0.0 < confidence < 1.0:
        raise InvalidParameterError(f"confidence must be in (0, 1), got {confidence}")
    w0 = float(np.exp(np.mean(np.log(points.omega))))  # geometric mean: the scaled s' is O(1)
    shapes = _shapes(order, max_order)
    delays = _delay_options(delay, w0)
    forced = len(shapes) * len(delays) == 1
    fits, rows = _fit_candidates(points, w0, shapes, delays, forced)
    best, key = _choose(points, fits, rows, criterion, forced)
    chosen = fits[best]
    assert chosen is not None
    rows[best] = replace(rows[best], chosen=True)
    selection = _explain(rows, key, best, criterion, forced)
    out = _finish(points, chosen, w0, delays, tuple(rows), selection, criterion, confidence)
    found = findings(points, chosen, out.transfer_function, out.p_value)
    for msg, category in found:
        warnings.warn(msg, category, stacklevel=2)
    return replace(out, warnings=tuple(msg for msg, _ in found))


def _delay_options(delay: Union[None, bool, float], w0: float) -> list[tuple[bool, float]]:
    """(fitted, fixed scaled delay) of each delay option the candidates are fitted with."""
    if delay is None:
        return [(False, 0.0), (True, 0.0)]
    if isinstance(delay, (bool, np.bool_)):
        return [(bool(delay), 0.0)]
    tau = nonnegative_number("delay", delay)
    return [(False, tau * w0)]


def _fit_candidates(
    points: _Points, w0: float, shapes: list[tuple[int, int]], delays: list[tuple[bool, float]], forced: bool
) -> tuple[list[Optional[_Fit]], list[OrderCandidate]]:
    """Every candidate (m, n, delay) fitted, with its row of the selection table (None: not fitted)."""
    s = np.asarray(1j * points.omega / w0, dtype=np.complex128)
    eqs = 2 * points.omega.size
    fits: list[Optional[_Fit]] = []
    rows: list[OrderCandidate] = []
    for m, n in shapes:
        for fitted, tau in delays:
            k = (m + 1) + n + (1 if fitted else 0)
            if not forced and k >= eqs:
                rows.append(
                    OrderCandidate(m, n, fitted, k, math.nan, math.inf, math.inf, error="k >= equations")
                )
                fits.append(None)
                continue
            try:
                f = _fit_one(points, s, m, n, fitted, tau)
            except (np.linalg.LinAlgError, ValueError, OverflowError, FloatingPointError) as exc:
                rows.append(
                    OrderCandidate(m, n, fitted, k, math.nan, math.inf, math.inf, error=str(exc)[:60])
                )
                fits.append(None)
                continue
            with np.errstate(over="ignore", invalid="ignore"):  # judged just below
                den = _Model(m, n, fitted, tau).den_coeffs(f.theta)
            if not (np.all(np.isfinite(den)) and math.isfinite(f.chi2)):
                # A fit that ran off to inf/NaN (issue 19 sweep: purely real points) is no candidate.
                rows.append(
                    OrderCandidate(m, n, fitted, k, math.nan, math.inf, math.inf, error="non-finite fit")
                )
                fits.append(None)
                continue
            aicc, bic = _criteria(f.chi2, k, eqs, points.weighted)
            unpinned = bool(_resonance_warnings(np.real(den), points.omega / w0))
            rows.append(
                OrderCandidate(m, n, fitted, k, f.chi2, aicc, bic, error=UNPINNED if unpinned else "")
            )
            fits.append(f)
    return fits, rows


def _choose(
    points: _Points, fits: list[Optional[_Fit]], rows: list[OrderCandidate], criterion: str, forced: bool
) -> tuple[int, list[float]]:
    """Index of the chosen candidate and the criterion of each; InsufficientDataError when none fits."""
    key = [
        (r.aicc if criterion == "aicc" else r.bic) if fits[i] is not None else math.inf
        for i, r in enumerate(rows)
    ]
    if forced:
        best = 0 if fits[0] is not None else -1
    else:
        best = _select(rows, key)
    if best < 0:
        raise InsufficientDataError(
            f"{points.omega.size} points ({2 * points.omega.size} real equations) support no candidate "
            "model: " + "; ".join(f"m={r.m} n={r.n} delay={r.delay}: {r.error}" for r in rows)
        )
    return best, key


@dataclass(frozen=True)
class _Reported:
    """The reported parameters of a fit (unscaled num, den after its leading 1, delay), their covariance
    and the internal parameters' covariance."""

    values: Any
    covariance: Any
    theta_cov: Any


def _reported(points: _Points, f: _Fit, model: _Model, w0: float) -> _Reported:
    """The delta method from the Hurwitz parameters to the reported ones; the map is holomorphic in
    theta, so a complex step gives its Jacobian exactly."""
    k = model.size
    dof = 2 * points.omega.size - k
    theta_cov = np.linalg.pinv(f.jac.T @ f.jac)
    if not points.weighted and dof > 0:
        theta_cov = theta_cov * (f.chi2 / dof)  # variance of the relative errors, from their scatter

    def reported(theta: Any) -> Any:
        b, _, _, tau = model.split(theta)
        den = model.den_coeffs(theta)
        n, m = f.n, f.m
        num_s = np.asarray([b[i] * w0 ** (n - m + i) for i in range(m + 1)])
        den_s = np.asarray([den[i] * w0**i for i in range(1, n + 1)])
        parts = [num_s, den_s]
        if f.delay:
            parts.append(np.asarray([tau / w0]))
        return np.concatenate(parts)

    values = np.real(reported(f.theta.astype(np.complex128)))
    h = 1e-30
    jmap = np.empty((values.size, k))
    for i in range(k):
        t = f.theta.astype(np.complex128)
        t[i] += 1j * h
        jmap[:, i] = np.imag(reported(t)) / h
    return _Reported(values, jmap @ theta_cov @ jmap.T, theta_cov)


def _finish(
    points: _Points,
    f: _Fit,
    w0: float,
    delays: list[tuple[bool, float]],
    rows: tuple[OrderCandidate, ...],
    selection: str,
    criterion: str,
    confidence: float,
) -> TransferFunctionFit:
    """The result of the chosen candidate ``f`` (its warnings are added by the caller)."""
    from scipy.stats import chi2 as chi2_dist  # type: ignore[import-untyped]

    fixed_tau = 0.0 if f.delay else next(t for d, t in delays if not d)
    model = _Model(f.m, f.n, f.delay, fixed_tau)
    dof = 2 * points.omega.size - model.size
    rep = _reported(points, f, model, w0)
    values = rep.values
    num = values[: f.m + 1]
    den = np.concatenate([[1.0], values[f.m + 1 : f.m + 1 + f.n]])
    tau = float(values[-1]) if f.delay else fixed_tau / w0
    names = tuple(
        [f"b{i}" for i in range(f.m + 1)]
        + [f"a{i}" for i in range(1, f.n + 1)]
        + (["delay"] if f.delay else [])
    )
    residuals = _whiten(
        points, model.response(f.theta, np.asarray(1j * points.omega / w0, dtype=np.complex128)) - points.g
    )
    notes: list[str] = []
    if f.reflected:
        notes.append(
            f"{f.reflected} unstable pole(s) of the Sanathanan-Koerner start reflected into the left half "
            "plane; the refinement is constrained to stable poles"
        )
    if not points.weighted:
        notes.append("the points carry no uncertainty: relative weights, intervals from the residual scatter")
    return TransferFunctionFit(
        transfer_function=TransferFunction(num, den, tau),
        m=f.m,
        n=f.n,
        delay_fitted=f.delay,
        parameter_names=names,
        parameters=values,
        covariance=rep.covariance,
        omega=points.omega,
        response=points.g,
        residuals=residuals,
        chi2=f.chi2,
        dof=dof,
        p_value=float(chi2_dist.sf(f.chi2, dof)) if points.weighted and dof > 0 else None,
        weighted=points.weighted,
        criterion=criterion,
        candidates=rows,
        selection=selection,
        notes=tuple(notes),
        confidence=confidence,
        _theta=f.theta,
        _theta_cov=rep.theta_cov,
        _w0=w0,
        _fixed_delay=fixed_tau / w0,
    )
