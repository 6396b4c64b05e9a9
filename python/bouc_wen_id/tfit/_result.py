"""What a transfer-function fit returns: the fitted G, its uncertainty, predictions and the order table."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._text import Summarised, with_warnings
from ..errors import InvalidParameterError
from ..model import TransferFunction
from ..validation import frozen_array, z_value
from ._model import _Model

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


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
class TransferFunctionFit(Summarised):
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
        try:
            raw = np.atleast_1d(omega)
        except ValueError as exc:  # a ragged list
            raise InvalidParameterError(f"omega must be a 1-D array of frequencies: {exc}") from None
        w = frozen_array("omega", raw)
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
        return with_warnings(lines, self.warnings)

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
