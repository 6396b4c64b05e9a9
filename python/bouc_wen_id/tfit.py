"""A parametric, stable, proper ``G(s)`` fitted to the identified frequency-response points (issue #11).

The identification gives ``G(j omega_i) = |G_i| exp(-j phi_i)`` at the tested frequencies, each with the
2x2 covariance of ``(|G_i|, phi_i)``.  :func:`fit_transfer_function` turns them into a rational transfer
function with an optional pure delay,

    G(s) = exp(-tau s) (b_0 s^m + ... + b_m) / (s^n + a_1 s^(n-1) + ... + a_n),   m <= n <= 4,

in three steps:

1. **Start** (Sanathanan-Koerner): the linearised, re-weighted least squares
   ``min sum_i |w_i (N(s_i) - G_i D(s_i)) / D_(k-1)(s_i)|^2`` iterated a few times, for a few trial delays
   between 0 and the delay the high-frequency phase slope suggests; unstable poles of the start are
   reflected into the left half plane (``p -> -conj p``, which keeps ``|D(j omega)|``) and the numerator
   re-solved.  C. K. Sanathanan and J. Koerner, *Transfer function synthesis as a ratio of two complex
   polynomials*, IEEE Trans. Automatic Control 8 (1963) 56-58.
2. **Refinement**: covariance-weighted nonlinear least squares (``scipy.optimize.least_squares``) on the
   whitened complex residuals ``L_i^-1 [Re, Im](G(j omega_i) - G_i)``, ``L_i L_i^T`` the covariance of
   ``(Re G_i, Im G_i)`` mapped from that of ``(|G_i|, phi_i)`` by the delta method.  Stability is
   enforced by the parameterisation: the denominator is a product of sections ``s^2 + e^p s + e^q`` and
   (odd n) ``s + e^r``, each Hurwitz for every real ``p, q, r``; the delay is bounded below by 0.
3. **Order selection** over ``0 <= m <= n <= max_order`` (and with/without delay) by AICc (default) or
   BIC on the weighted chi-square; the table of every candidate is kept on the result.

The parameter covariance is the inverse Gauss-Newton information of the whitened residuals (scaled by the
residual variance when the points carry no uncertainty), and :meth:`TransferFunctionFit.predict` carries
it to untested frequencies by the delta method.

The points are those of the alpha-normalised model, so the fitted transfer function is ``alpha G``.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, Literal, Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import IdentifiabilityWarning, InsufficientDataError, InvalidParameterError, NonFiniteError
from .model import TransferFunction
from .validation import z_value

if TYPE_CHECKING:  # pragma: no cover - typing only
    from .result import IdentificationResult

__all__ = ["fit_transfer_function", "TransferFunctionFit", "FrequencyPrediction", "OrderCandidate"]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: Highest denominator degree tried by the automatic order selection (issue #11: orders 0..4).
MAX_ORDER = 4
#: Sanathanan-Koerner re-weighting iterations: the weights converge in a handful on clean data, and the
#: start only has to land in the refinement's basin.
SK_ITERATIONS = 12
#: Trial delays of the start, as fractions of the delay the high-frequency phase slope suggests: the slope
#: also holds the poles' phase lag, so the true delay is somewhere below it.
DELAY_FRACTIONS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: A reflected or axis pole is moved to damping ratio at least this, so its log-parameters stay finite.
MIN_START_DAMPING = 1e-3
#: Evaluations of the refinement: a model of the right order converges in a few tens; an over-sized one
#: (redundant poles and zeros) creeps along a flat valley, and its criterion is not helped by creeping on.
MAX_NFEV = 100
#: Smallest delay (scaled, tau w0) of a start: the delay is fitted as exp(t), so 0 is approached, not held.
MIN_START_DELAY = 1e-3
#: Two frequencies closer than this (relative) are one frequency tested twice: refused as duplicates.
DUPLICATE_RTOL = 1e-9
#: Candidates within this much of the lowest information criterion are "about as good" (a difference
#: below 2 is not evidence, Burnham and Anderson 2002, section 2.6); the simplest of them is chosen.
PARSIMONY = 2.0
#: What the selection table says of a candidate set aside for an unpinned resonance.
UNPINNED = "resonance not pinned down"
#: Bound on the log-coefficients of the denominator sections (in the scaled frequency s' = s / w0).
LOG_BOUND = 40.0
#: A complex pole pair with damping ratio below 1/sqrt(2) has a peak in |G(j omega)|; the peak is pinned
#: down only if a point lies inside its half-power band ``omega_n (1 +- zeta)``.
PEAK_DAMPING = 1.0 / math.sqrt(2.0)


@dataclass(frozen=True)
class OrderCandidate:
    """One row of the order-selection table: numerator degree ``m``, denominator degree ``n``, delay.

    ``chi2`` is the weighted residual sum of squares (whitened; when the points carry no uncertainty,
    the relative-error sum of squares), ``parameters`` the number of real parameters, ``aicc``/``bic``
    the information criteria (inf when undefined: too few equations).
    """

    m: int
    n: int
    delay: bool
    parameters: int
    chi2: float
    aicc: float
    bic: float
    chosen: bool = False
    error: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {
            "m": self.m,
            "n": self.n,
            "delay": self.delay,
            "parameters": self.parameters,
            "chi2": _num(self.chi2),
            "aicc": _num(self.aicc),
            "bic": _num(self.bic),
            "chosen": self.chosen,
            "error": self.error,
        }


@dataclass(frozen=True, eq=False)
class FrequencyPrediction:
    """``G(j omega)`` predicted by a fitted transfer function, with delta-method standard errors.

    ``phase`` follows the paper, ``phi = -angle G``, in [0, 2 pi) as the result's phases (an interval
    near 0 or 2 pi is meant modulo 2 pi).  ``covariance[k]`` is the 2x2 covariance of
    ``(Re G, Im G)`` at ``omega[k]``; the intervals are ``+- z se`` at ``confidence``.
    """

    omega: FloatArray
    response: ComplexArray
    gain: FloatArray
    phase: FloatArray
    gain_se: FloatArray
    phase_se: FloatArray
    covariance: FloatArray = field(repr=False)
    confidence: float = 0.95

    @property
    def gain_interval(self) -> FloatArray:
        """``(k, 2)`` array of the lower and upper ends of |G|'s interval."""
        z = z_value(self.confidence)
        return np.stack([self.gain - z * self.gain_se, self.gain + z * self.gain_se], axis=1)

    @property
    def phase_interval(self) -> FloatArray:
        """``(k, 2)`` array of the lower and upper ends of phi's interval (rad)."""
        z = z_value(self.confidence)
        return np.stack([self.phase - z * self.phase_se, self.phase + z * self.phase_se], axis=1)


@dataclass(frozen=True, eq=False)
class TransferFunctionFit:
    """A stable, proper ``G(s)`` fitted to frequency-response points, with its uncertainty.

    Attributes
    ----------
    transfer_function : TransferFunction
        The fitted ``exp(-delay s) num(s)/den(s)``, ``den`` monic (the alpha-normalised G when fitted to
        an identification result).
    m, n : int
        Numerator and denominator degrees.
    delay_fitted : bool
        Whether the delay was a parameter (False: fixed at ``transfer_function.delay``).
    parameter_names : tuple of str
        Names of the reported parameters: ``b0..bm`` (num, highest power first), ``a1..an`` (den after
        its leading 1) and ``delay`` when fitted.
    parameters : ndarray
        Their values.
    covariance : ndarray
        Their covariance (delta method from the internal, Hurwitz parameterisation).
    omega, response : ndarray
        The points fitted (rad/s; complex ``G = |G| exp(-j phi)``).
    residuals : ndarray
        ``(k, 2)`` whitened residuals ``L_i^-1 [Re, Im](G_fit - G_i)`` of each point, in units of the
        point's own standard error (each row is one point's two real equations).
    chi2, dof, p_value : float, int, float or None
        ``sum(residuals^2)``, ``2k - parameters`` and the chi-square p-value (None when the points carry
        no uncertainty or dof = 0).
    weighted : bool
        Whether the points carried a covariance (else relative weights, covariance from the scatter).
    criterion : str
        ``"aicc"`` or ``"bic"``.
    candidates : tuple of OrderCandidate
        The order-selection table (one row when the order and delay were given).
    selection : str
        Why this order was chosen.
    warnings : tuple of str
        What the points cannot pin down (also issued as :class:`IdentifiabilityWarning`).
    notes : tuple of str
        Remarks on the fit (e.g. reflected start poles).
    """

    transfer_function: TransferFunction
    m: int
    n: int
    delay_fitted: bool
    parameter_names: tuple[str, ...]
    parameters: FloatArray
    covariance: FloatArray = field(repr=False)
    omega: FloatArray = field(repr=False)
    response: ComplexArray = field(repr=False)
    residuals: FloatArray = field(repr=False)
    chi2: float
    dof: int
    p_value: Optional[float]
    weighted: bool
    criterion: str
    candidates: tuple[OrderCandidate, ...] = field(repr=False)
    selection: str = ""
    warnings: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()
    confidence: float = 0.95
    # internal: the Hurwitz parameters, the frequency scale and the model pieces that predict() needs
    _theta: FloatArray = field(default_factory=lambda: np.zeros(0), repr=False)
    _theta_cov: FloatArray = field(default_factory=lambda: np.zeros((0, 0)), repr=False)
    _w0: float = field(default=1.0, repr=False)
    _fixed_delay: float = field(default=0.0, repr=False)

    @property
    def standard_errors(self) -> dict[str, float]:
        """Standard error of each reported parameter, by name."""
        se = np.sqrt(np.clip(np.diag(self.covariance), 0.0, None))
        return {k: float(v) for k, v in zip(self.parameter_names, se)}

    def poles(self) -> ComplexArray:
        """Poles of the fitted G (all with negative real part)."""
        out: ComplexArray = np.roots(self.transfer_function.den).astype(np.complex128)
        return out

    def zeros(self) -> ComplexArray:
        out: ComplexArray = np.roots(self.transfer_function.num).astype(np.complex128)
        return out

    def predict(self, omega: ArrayLike, confidence: Optional[float] = None) -> FrequencyPrediction:
        """``G(j omega)`` at any frequencies (rad/s), with delta-method standard errors and intervals.

        The uncertainty is that of the fitted parameters only: it does not hold the error of a model
        order that is too low (check ``p_value`` and the residuals).
        """
        w = np.atleast_1d(np.asarray(omega, dtype=np.float64))
        if w.ndim != 1 or not np.all(np.isfinite(w)):
            raise NonFiniteError("omega must be a 1-D array of finite frequencies")
        if np.any(w <= 0.0):
            raise InvalidParameterError("omega must be > 0 rad/s")
        model = _Model(self.m, self.n, self.delay_fitted, self._fixed_delay * self._w0)
        s = np.asarray(1j * w / self._w0, dtype=np.complex128)
        g, dg = model.response(self._theta, s, jacobian=True)
        cov = np.empty((w.size, 2, 2))
        gain_se = np.empty(w.size)
        phase_se = np.empty(w.size)
        for k in range(w.size):
            jr = np.vstack([dg[k].real, dg[k].imag])  # d(Re, Im)/d theta
            c = jr @ self._theta_cov @ jr.T
            cov[k] = c
            # (|G|, phi = -angle G) from (Re, Im): rows d|G| and dphi.
            x, y = g[k].real, g[k].imag
            r2 = x * x + y * y
            r = math.sqrt(r2)
            jp = np.array([[x / r, y / r], [y / r2, -x / r2]])
            cp = jp @ c @ jp.T
            gain_se[k] = math.sqrt(max(cp[0, 0], 0.0))
            phase_se[k] = math.sqrt(max(cp[1, 1], 0.0))
        phase = np.mod(-np.angle(g), 2.0 * np.pi)  # as the result's phases: in [0, 2 pi)
        return FrequencyPrediction(
            omega=w,
            response=g,
            gain=np.abs(g),
            phase=phase,
            gain_se=gain_se,
            phase_se=phase_se,
            covariance=cov,
            confidence=self.confidence if confidence is None else float(confidence),
        )

    def summary(self) -> str:
        """A plain-text report: the fitted G, its parameters, the fit to the points, the selection."""
        tf = self.transfer_function
        z = z_value(self.confidence)
        lines = [
            f"Transfer function fit: m = {self.m} zeros, n = {self.n} poles, "
            + (
                f"delay fitted = {tf.delay:.4g} s"
                if self.delay_fitted
                else (f"delay fixed = {tf.delay:.4g} s" if tf.delay > 0.0 else "no delay")
            )
        ]
        lines.append(
            f"  G(s) = ({_poly_str(tf.num)}) / ({_poly_str(tf.den)})"
            + (f" * exp(-{tf.delay:.4g} s)" if tf.delay > 0.0 else "")
        )
        head = f"  {'parameter':<10}{'estimate':>13}{'std.err':>11}{f'{self.confidence:.0%} interval':>26}"
        lines.append(head)
        for name, v, se in zip(self.parameter_names, self.parameters, self.standard_errors.values()):
            lines.append(f"  {name:<10}{v:>13.6g}{se:>11.3g}{f'[{v - z * se:.5g}, {v + z * se:.5g}]':>26}")
        poles = self.poles()
        if poles.size:
            lines.append("  poles: " + ", ".join(_cplx(p) for p in poles))
        lines.append("")
        lines.append(
            f"  {'omega':>9}{'|G| point':>11}{'|G| fit':>11}{'phi point':>11}{'phi fit':>10}{'res Re':>9}"
            f"{'res Im':>9}"
        )
        fitted = tf.freqresp(self.omega)
        for k, w in enumerate(self.omega):
            lines.append(
                f"  {w:>9.4g}{abs(self.response[k]):>11.5g}{abs(fitted[k]):>11.5g}"
                f"{_phi(self.response[k]):>11.4f}{_phi(fitted[k]):>10.4f}"
                f"{self.residuals[k, 0]:>9.2f}{self.residuals[k, 1]:>9.2f}"
            )
        unit = "its standard error" if self.weighted else "relative error, scatter-scaled"
        lines.append(f"  (residuals in units of {unit})")
        fit = f"  chi2 = {self.chi2:.4g} on {self.dof} dof"
        if self.p_value is not None:
            fit += f", p = {self.p_value:.3g}"
            if self.p_value < 0.01:
                fit += "  -> the model does not explain the points within their intervals"
        lines.append(fit)
        lines.append(f"  order selection ({self.criterion.upper()}): {self.selection}")
        if len(self.candidates) > 1:
            lines.append(f"    {'m':>3}{'n':>3}{'delay':>7}{'k':>4}{'chi2':>12}{'AICc':>12}{'BIC':>12}")
            for c in self.candidates:
                mark = "  <- chosen" if c.chosen else (f"  ({c.error})" if c.error else "")
                lines.append(
                    f"    {c.m:>3}{c.n:>3}{('yes' if c.delay else 'no'):>7}{c.parameters:>4}{c.chi2:>12.4g}"
                    f"{c.aicc:>12.4g}{c.bic:>12.4g}{mark}"
                )
        for note in self.notes:
            lines.append(f"  note: {note}")
        for w in self.warnings:
            lines.append(f"  warning: {w}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def __repr__(self) -> str:
        return (
            f"TransferFunctionFit(m={self.m}, n={self.n}, delay={self.transfer_function.delay:.4g}, "
            f"chi2={self.chi2:.4g}, dof={self.dof})"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description (format ``bouc_wen_id.tfit``, version 1)."""
        return {
            "format": "bouc_wen_id.tfit",
            "version": 1,
            "transfer_function": self.transfer_function.to_dict(),
            "m": self.m,
            "n": self.n,
            "delay_fitted": self.delay_fitted,
            "parameter_names": list(self.parameter_names),
            "parameters": self.parameters.tolist(),
            "covariance": self.covariance.tolist(),
            "omega": self.omega.tolist(),
            "response_real": self.response.real.tolist(),
            "response_imag": self.response.imag.tolist(),
            "phase_convention": "G = |G| exp(-j phi), phi = -angle G(j omega)",
            "residuals": self.residuals.tolist(),
            "chi2": self.chi2,
            "dof": self.dof,
            "p_value": self.p_value,
            "weighted": self.weighted,
            "criterion": self.criterion,
            "candidates": [c.to_dict() for c in self.candidates],
            "selection": self.selection,
            "warnings": list(self.warnings),
            "notes": list(self.notes),
            "confidence": self.confidence,
        }


# --------------------------------------------------------------------------------------------- model


class _Model:
    """``G(s') = exp(-tau' s') N(s') / prod sections(s')`` in the scaled frequency ``s' = s / w0``.

    ``theta = [b_0..b_m, (p_j, q_j) per second-order section, r (odd n), tau' (if fitted)]``.
    """

    def __init__(self, m: int, n: int, delay: bool, fixed_delay: float = 0.0) -> None:
        self.m, self.n, self.delay = m, n, delay
        self.fixed_delay = fixed_delay  # scaled: tau' = tau w0
        self.pairs = n // 2
        self.odd = n % 2 == 1
        self.size = (m + 1) + n + (1 if delay else 0)

    def split(self, theta: Any) -> tuple[Any, Any, Any, Any]:
        b = theta[: self.m + 1]
        sec = theta[self.m + 1 : self.m + 1 + 2 * self.pairs].reshape(self.pairs, 2)
        r = theta[self.m + 1 + 2 * self.pairs] if self.odd else None
        tau = _exp(theta[-1]) if self.delay else self.fixed_delay
        return b, sec, r, tau

    def den_coeffs(self, theta: Any) -> Any:
        """Monic denominator (highest power first); works on complex theta (for complex-step)."""
        _, sec, r, _ = self.split(theta)
        d: Any = np.ones(1, dtype=np.asarray(theta).dtype)
        for p, q in sec:
            d = np.convolve(d, np.array([1.0, np.exp(p), np.exp(q)], dtype=d.dtype))
        if r is not None:
            d = np.convolve(d, np.array([1.0, np.exp(r)], dtype=d.dtype))
        return d

    def response(self, theta: FloatArray, s: ComplexArray, jacobian: bool = False) -> Any:
        b, sec, r, tau = self.split(theta)
        num = np.polyval(b, s)
        secs = [s * s + _exp(p) * s + _exp(q) for p, q in sec]
        den = np.ones_like(s)
        for v in secs:
            den = den * v
        first = s + _exp(r) if r is not None else None
        if first is not None:
            den = den * first
        e = np.exp(-tau * s)
        g = num / den * e
        if not jacobian:
            return g
        cols = [s ** (self.m - k) / den * e for k in range(self.m + 1)]
        for (p, q), v in zip(sec, secs):
            cols.append(-g * _exp(p) * s / v)
            cols.append(-g * _exp(q) / v)
        if first is not None:
            cols.append(-g * _exp(r) / first)
        if self.delay:
            cols.append(-s * g * tau)  # d/dt of exp(-e^t s)
        return g, np.stack(cols, axis=1) if cols else np.zeros((s.size, 0), dtype=np.complex128)

    def theta_from(self, num: FloatArray, poles: ComplexArray, tau: float) -> FloatArray:
        """Internal parameters of numerator ``num`` (length m+1), left-half-plane ``poles`` and delay."""
        sections = _pair_poles(poles)
        theta: list[float] = list(num)
        quad = [sec for sec in sections if len(sec) == 3]
        lin = [sec for sec in sections if len(sec) == 2]
        for q in quad:
            theta += [math.log(q[1]), math.log(q[2])]
        for one in lin:
            theta.append(math.log(one[1]))
        if self.delay:
            theta.append(math.log(max(tau, MIN_START_DELAY)))
        return np.asarray(theta, dtype=np.float64)


def _exp(x: Any) -> Any:
    """``exp`` of a log-parameter, clipped so that a wandering iterate cannot overflow (the function is
    flat beyond the clip, which is far outside any sensible model in the scaled frequency)."""
    if isinstance(x, complex) or np.iscomplexobj(x):
        return np.exp(x)  # the complex-step derivative of the reported parameters
    return math.exp(min(max(float(x), -LOG_BOUND), LOG_BOUND))


def _pair_poles(poles: ComplexArray) -> list[tuple[float, ...]]:
    """Monic real sections of stable ``poles``: ``(1, a1, a0)`` per pair, ``(1, c)`` for a lone real one."""
    tol = 1e-9
    cplx = sorted((p for p in poles if p.imag > tol * max(abs(p), 1.0)), key=lambda p: p.real)
    reals = sorted(float(p.real) for p in poles if abs(p.imag) <= tol * max(abs(p), 1.0))
    out: list[tuple[float, ...]] = []
    for p in cplx:
        out.append((1.0, -2.0 * p.real, abs(p) ** 2))
    while len(reals) >= 2:
        p1, p2 = reals.pop(0), reals.pop(0)
        out.append((1.0, -(p1 + p2), p1 * p2))
    if reals:
        out.append((1.0, -reals[0]))
    return out


def _stabilise(poles: ComplexArray) -> tuple[ComplexArray, int]:
    """Reflect right-half-plane poles (``p -> -conj p``) and move axis poles to a minimum damping."""
    out = np.array(poles, dtype=np.complex128)
    reflected = int(np.sum(out.real > 0.0))
    out = np.where(out.real > 0.0, -np.conj(out), out)
    mag = np.maximum(np.abs(out), 1e-6)
    out = np.where(out.real > -MIN_START_DAMPING * mag, -MIN_START_DAMPING * mag + 1j * out.imag, out)
    return out, reflected


# ------------------------------------------------------------------------------------------ the data


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
        w = np.asarray(omega, dtype=np.float64)
        g = np.asarray(response, dtype=np.complex128)
        if w.ndim != 1 or g.shape != w.shape:
            raise InvalidParameterError(
                f"omega and response must be 1-D of the same length, got shapes {w.shape} and {g.shape}"
            )
        gains = np.abs(g)
        cov = None if covariance is None else np.array(covariance, dtype=np.float64)
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
    if np.any(np.diff(w) <= DUPLICATE_RTOL * w[1:]):
        raise InvalidParameterError("duplicate frequencies: average the points of one frequency first")
    if w.size < 2:
        raise InsufficientDataError(f"a transfer function needs at least 2 points, got {w.size}")
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
    return _Points(w, g, white, cov is not None)


def _whiten(points: _Points, z: ComplexArray) -> FloatArray:
    """``(k, 2)`` whitened ``[Re, Im]`` of complex residuals (or Jacobian columns when z is (k, p))."""
    if z.ndim == 1:
        out: FloatArray = np.einsum("kij,kj->ki", points.white, np.stack([z.real, z.imag], axis=1))
        return out
    out = np.einsum("kij,kjp->kip", points.white, np.stack([z.real, z.imag], axis=1))
    return out


# --------------------------------------------------------------------------------------------- fits


@dataclass
class _Fit:
    m: int
    n: int
    delay: bool
    theta: FloatArray
    chi2: float
    jac: FloatArray  # whitened (2k, p)
    reflected: int


def _sk_start(
    points: _Points, s: ComplexArray, m: int, n: int, tau: float
) -> tuple[FloatArray, ComplexArray]:
    """Sanathanan-Koerner fit of ``G exp(tau s)`` by ``N/D``; returns (num, den) in s', den monic."""
    g = points.g * np.exp(tau * s)
    prev: Any = np.ones_like(s)
    num: Any = np.zeros(m + 1)
    den: Any = np.ones(1)
    for _ in range(SK_ITERATIONS):
        cols = [s ** (m - k) / prev for k in range(m + 1)] + [
            -g * s ** (n - k) / prev for k in range(1, n + 1)
        ]
        a = np.stack(cols, axis=1) if cols else np.zeros((s.size, 0), dtype=np.complex128)
        y = g * s**n / prev
        aw = _whiten(points, a).reshape(2 * s.size, -1)
        yw = _whiten(points, y).reshape(-1)
        x, *_ = np.linalg.lstsq(aw, yw, rcond=None)
        num = x[: m + 1]
        den = np.concatenate([[1.0], x[m + 1 :]])
        new = np.polyval(den, s)
        if np.any(new == 0.0):
            break
        prev = new
    return num, den


def _numerator_for(points: _Points, s: ComplexArray, m: int, den: FloatArray, tau: float) -> FloatArray:
    """The weighted least-squares numerator for a fixed denominator and delay (linear in b)."""
    base = np.exp(-tau * s) / np.polyval(den, s)
    a = np.stack([s ** (m - k) * base for k in range(m + 1)], axis=1)
    aw = _whiten(points, a).reshape(2 * s.size, -1)
    yw = _whiten(points, points.g).reshape(-1)
    x, *_ = np.linalg.lstsq(aw, yw, rcond=None)
    out: FloatArray = np.asarray(x, dtype=np.float64)
    return out


def _phase_slope_delay(points: _Points, s: ComplexArray) -> float:
    """Delay (scaled) suggested by the slope of the unwrapped phase over the upper half of the points."""
    w = s.imag
    phi = -np.unwrap(np.angle(points.g))
    half = max(2, w.size // 2)
    ww, pp = w[-half:], phi[-half:]
    if ww.size < 2 or np.ptp(ww) == 0.0:
        return 0.0
    slope = float(np.polyfit(ww, pp, 1)[0])
    return max(slope, 0.0)


def _fit_one(points: _Points, s: ComplexArray, m: int, n: int, delay: bool, fixed_tau: float) -> _Fit:
    from scipy.optimize import least_squares  # type: ignore[import-untyped]

    model = _Model(m, n, delay, fixed_tau)
    taus = [fixed_tau] if not delay else [f * _phase_slope_delay(points, s) for f in DELAY_FRACTIONS]
    best: Optional[tuple[float, FloatArray, int]] = None
    poles: Any
    den: Any
    for tau in taus:
        if n > 0:
            _, den = _sk_start(points, s, m, n, tau)
            poles, reflected = _stabilise(np.roots(den).astype(np.complex128))
            den = np.real(np.poly(poles))
        else:
            poles, reflected, den = np.zeros(0, dtype=np.complex128), 0, np.ones(1)
        num = _numerator_for(points, s, m, den, tau)
        theta0 = model.theta_from(num, poles, tau)
        cost = float(np.sum(_whiten(points, model.response(theta0, s) - points.g) ** 2))
        if best is None or cost < best[0]:
            best = (cost, theta0, reflected)
    assert best is not None
    theta0, reflected = best[1], best[2]

    def fun(theta: FloatArray) -> FloatArray:
        out: FloatArray = _whiten(points, model.response(theta, s) - points.g).reshape(-1)
        return out

    def jac(theta: FloatArray) -> FloatArray:
        _, dg = model.response(theta, s, jacobian=True)
        out: FloatArray = _whiten(points, dg).reshape(2 * s.size, -1)
        return out

    sol = least_squares(
        # MINPACK's LM is the fastest here but needs at least as many residuals as parameters; an
        # over-parameterised fit (forced by the user, warned about) takes the trust-region solver.
        fun,
        theta0,
        jac=jac,
        method="lm" if 2 * s.size >= model.size else "trf",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=MAX_NFEV,
    )
    theta = np.asarray(sol.x, dtype=np.float64)
    return _Fit(m, n, delay, theta, float(np.sum(sol.fun**2)), jac(theta), reflected)


def _criteria(chi2: float, k: int, eqs: int, weighted: bool) -> tuple[float, float]:
    """(AICc, BIC) of a fit with ``k`` parameters on ``eqs`` real equations."""
    if weighted:
        fit = chi2  # -2 log L up to a constant, the variances known
    else:
        fit = eqs * math.log(max(chi2, 1e-300) / eqs)  # variance estimated from the residuals
    aic = fit + 2.0 * k
    aicc = aic + 2.0 * k * (k + 1) / (eqs - k - 1) if eqs - k - 1 > 0 else math.inf
    bic = fit + k * math.log(eqs)
    return aicc, bic


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
        The same given explicitly (instead of ``result``): frequencies in rad/s (> 0, distinct), complex
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
        Non-positive or duplicate frequencies, a zero |G| point, a covariance that is not positive
        definite, a bad ``order``/``delay``/``criterion``.
    InsufficientDataError
        Fewer than 2 points, or no candidate model with fewer parameters than real equations.

    Warns
    -----
    IdentifiabilityWarning
        When the chosen model has at least as many parameters as real equations (2 per point), or
        when a fitted resonance peak lies where no point pins it down.
    """
    if criterion not in ("aicc", "bic"):
        raise InvalidParameterError(f"criterion must be 'aicc' or 'bic', got {criterion!r}")
    if isinstance(max_order, bool) or not isinstance(max_order, (int, np.integer)) or not 0 <= max_order <= 8:
        raise InvalidParameterError(f"max_order must be an integer in 0..8, got {max_order!r}")
    points = _points(result, omega, response, covariance)
    if confidence is None:
        confidence = result.confidence if result is not None else 0.95
    if not 0.0 < confidence < 1.0:
        raise InvalidParameterError(f"confidence must be in (0, 1), got {confidence}")
    w0 = float(np.exp(np.mean(np.log(points.omega))))  # geometric mean: the scaled s' is O(1)
    s = np.asarray(1j * points.omega / w0, dtype=np.complex128)
    eqs = 2 * points.omega.size

    shapes = _shapes(order, max_order)
    if delay is None:
        delays: list[tuple[bool, float]] = [(False, 0.0), (True, 0.0)]
    elif isinstance(delay, (bool, np.bool_)):
        delays = [(bool(delay), 0.0)]
    else:
        tau = float(delay)
        if not math.isfinite(tau) or tau < 0.0:
            raise InvalidParameterError(f"delay must be None, a bool or a number >= 0 s, got {delay!r}")
        delays = [(False, tau * w0)]
    forced = len(shapes) * len(delays) == 1

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
            aicc, bic = _criteria(f.chi2, k, eqs, points.weighted)
            den = _Model(m, n, fitted, tau).den_coeffs(f.theta)
            unpinned = bool(_resonance_warnings(np.real(den), points.omega / w0))
            rows.append(
                OrderCandidate(m, n, fitted, k, f.chi2, aicc, bic, error=UNPINNED if unpinned else "")
            )
            fits.append(f)
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
            f"{points.omega.size} points ({eqs} real equations) support no candidate model: "
            + "; ".join(f"m={r.m} n={r.n} delay={r.delay}: {r.error}" for r in rows)
        )
    chosen = fits[best]
    assert chosen is not None
    rows[best] = replace(rows[best], chosen=True)
    selection = _explain(rows, key, best, criterion, forced)
    return _finish(points, chosen, w0, delays, rows, selection, criterion, confidence, eqs)


def _select(rows: list[OrderCandidate], key: list[float]) -> int:
    """Index of the chosen candidate, or -1.

    Candidates whose fitted resonance falls where no point pins it down are set aside (a narrow peak
    slipped between two points buys chi-square the data cannot confirm) unless every candidate has one;
    among the rest, the fewest parameters within ``PARSIMONY`` of the lowest criterion (ties: the lower).
    """
    ok = [i for i, k in enumerate(key) if math.isfinite(k) and rows[i].error != UNPINNED]
    if not ok:
        ok = [i for i, k in enumerate(key) if math.isfinite(k)]
    if not ok:
        return -1
    low = min(key[i] for i in ok)
    near = [i for i in ok if key[i] <= low + PARSIMONY]
    return min(near, key=lambda i: (rows[i].parameters, key[i]))


def _shapes(order: Union[None, int, tuple[int, int]], max_order: int) -> list[tuple[int, int]]:
    def bad() -> InvalidParameterError:
        return InvalidParameterError(f"order must be None, n or (m, n) with 0 <= m <= n <= 8, got {order!r}")

    if order is None:
        return [(m, n) for n in range(max_order + 1) for m in range(n + 1)]
    if isinstance(order, (int, np.integer)) and not isinstance(order, bool):
        if not 0 <= order <= 8:
            raise bad()
        return [(m, int(order)) for m in range(int(order) + 1)]
    if (
        isinstance(order, Sequence)
        and len(order) == 2
        and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool) for v in order)
    ):
        m, n = int(order[0]), int(order[1])
        if not 0 <= m <= n <= 8:
            raise bad()
        return [(m, n)]
    raise bad()


def _explain(rows: list[OrderCandidate], key: list[float], best: int, criterion: str, forced: bool) -> str:
    r = rows[best]
    what = f"m = {r.m}, n = {r.n}, " + ("delay fitted" if r.delay else "no fitted delay")
    if forced:
        return f"{what}: given by order=/delay=, not selected"
    name = criterion.upper()
    finite = [i for i in range(len(rows)) if math.isfinite(key[i])]
    others = sorted((key[i], i) for i in finite if i != best)
    if not others:
        return f"{what}: the only candidate the points support"
    set_aside = sum(rows[i].error == UNPINNED for i in finite)
    low = min(key[i] for i in finite if rows[i].error != UNPINNED or rows[best].error == UNPINNED)
    if key[best] > low:
        head = (
            f"{what}: the fewest parameters ({rows[best].parameters}) within {PARSIMONY:g} of the lowest "
            f"{name} ({key[best] - low:.3g} above it)"
        )
    else:
        head = f"{what}: lowest {name} of {len(finite)} candidates"
    runner_key, runner_i = (
        next((k, i) for k, i in others if rows[i].error != UNPINNED)
        if any(rows[i].error != UNPINNED for _, i in others)
        else others[0]
    )
    runner = rows[runner_i]
    gap = runner_key - key[best]
    strength = "decisive" if gap > 10 else ("strong" if gap > 6 else ("positive" if gap > 2 else "weak"))
    text = (
        f"{head}; the next (m = {runner.m}, n = {runner.n}, delay {'fitted' if runner.delay else 'none'}) is "
        f"{gap:.3g} {'higher' if gap >= 0 else 'lower'} "
        f"({strength if gap >= 0 else 'but has more parameters'})"
    )
    if set_aside:
        text += f"; {set_aside} candidate(s) set aside: a resonance no point pins down"
    return text


def _finish(
    points: _Points,
    f: _Fit,
    w0: float,
    delays: list[tuple[bool, float]],
    rows: list[OrderCandidate],
    selection: str,
    criterion: str,
    confidence: float,
    eqs: int,
) -> TransferFunctionFit:
    from scipy.stats import chi2 as chi2_dist  # type: ignore[import-untyped]

    fixed_tau = 0.0 if f.delay else next(t for d, t in delays if not d)
    model = _Model(f.m, f.n, f.delay, fixed_tau)
    k = model.size
    dof = eqs - k
    info = f.jac.T @ f.jac
    theta_cov = np.linalg.pinv(info)
    if not points.weighted and dof > 0:
        theta_cov = theta_cov * (f.chi2 / dof)  # variance of the relative errors, from their scatter

    # Reported parameters (unscaled num, den after its leading 1, delay) and their covariance by the
    # delta method; the map is holomorphic in theta, so a complex step gives its Jacobian exactly.
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
    cov = jmap @ theta_cov @ jmap.T
    num = values[: f.m + 1]
    den = np.concatenate([[1.0], values[f.m + 1 : f.m + 1 + f.n]])
    tau = float(values[-1]) if f.delay else fixed_tau / w0
    tf = TransferFunction(num, den, tau)
    names = tuple(
        [f"b{i}" for i in range(f.m + 1)]
        + [f"a{i}" for i in range(1, f.n + 1)]
        + (["delay"] if f.delay else [])
    )
    residuals = _whiten(
        points, model.response(f.theta, np.asarray(1j * points.omega / w0, dtype=np.complex128)) - points.g
    )
    p_value = float(chi2_dist.sf(f.chi2, dof)) if points.weighted and dof > 0 else None

    found: list[str] = []
    notes: list[str] = []
    if k >= eqs:
        found.append(
            f"{k} parameters from {eqs} real equations ({points.omega.size} points): the fit interpolates "
            "and its parameters are not determined; add frequencies or lower the order"
        )
    found += _resonance_warnings(tf.den, points.omega)
    if f.reflected:
        notes.append(
            f"{f.reflected} unstable pole(s) of the Sanathanan-Koerner start reflected into the left half "
            "plane; the refinement is constrained to stable poles"
        )
    if not points.weighted:
        notes.append("the points carry no uncertainty: relative weights, intervals from the residual scatter")
    for msg in found:
        warnings.warn(msg, IdentifiabilityWarning, stacklevel=3)
    return TransferFunctionFit(
        transfer_function=tf,
        m=f.m,
        n=f.n,
        delay_fitted=f.delay,
        parameter_names=names,
        parameters=values,
        covariance=cov,
        omega=points.omega,
        response=points.g,
        residuals=residuals,
        chi2=f.chi2,
        dof=dof,
        p_value=p_value,
        weighted=points.weighted,
        criterion=criterion,
        candidates=tuple(rows),
        selection=selection,
        warnings=tuple(found),
        notes=tuple(notes),
        confidence=confidence,
        _theta=f.theta,
        _theta_cov=theta_cov,
        _w0=w0,
        _fixed_delay=fixed_tau / w0,
    )


def _resonance_warnings(den: FloatArray, omega: FloatArray) -> list[str]:
    """Warnings for each under-damped pole pair of ``den`` whose half-power band holds none of ``omega``."""
    out = []
    for p in np.roots(den):
        if p.imag <= 0.0:
            continue
        wn = abs(p)
        zeta = -p.real / wn
        if zeta >= PEAK_DAMPING:
            continue
        lo, hi = wn * (1.0 - zeta), wn * (1.0 + zeta)
        if np.any((omega >= lo) & (omega <= hi)):
            continue
        where = "between two tested frequencies" if omega[0] < wn < omega[-1] else "outside the tested band"
        out.append(
            f"a resonance at {wn:.4g} rad/s (damping {zeta:.3g}) lies {where}, with no point in its "
            f"half-power band [{lo:.4g}, {hi:.4g}] rad/s: its peak is not pinned down; test a frequency there"
        )
    return out


def _num(v: float) -> Optional[float]:
    return None if not math.isfinite(v) else float(v)


def _poly_str(c: FloatArray) -> str:
    deg = c.size - 1
    terms = []
    for i, v in enumerate(c):
        p = deg - i
        terms.append(f"{v:.5g}" + ("" if p == 0 else (" s" if p == 1 else f" s^{p}")))
    return " + ".join(terms).replace("+ -", "- ")


def _cplx(p: complex) -> str:
    return f"{p.real:.4g}" if p.imag == 0 else f"{p.real:.4g}{p.imag:+.4g}j"


def _phi(g: complex) -> float:
    return float(np.mod(-np.angle(g), 2.0 * np.pi))
