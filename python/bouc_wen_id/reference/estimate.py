"""NumPy reference of ``rust/estimate.rs``: the phase (9), the spectral derivative and the gain (27b) of the
seed paper.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
    SingularNormalMatrixError,
    ZeroAmplitudeError,
)
from ..validation import MIN_AVERAGE_SAMPLES
from ..validation import finite_array as _finite_array
from ..validation import finite_scalar as _finite_scalar
from .solve import sls_inputs

__all__ = ["phase_from_max", "max_harmonics", "spectral_derivative", "gain_estimate"]

FloatArray = NDArray[np.float64]


def phase_from_max(ybar: ArrayLike) -> float:
    """Phase estimator (9): ``omega * t_max = 2 pi j*/P`` with ``j*`` the first maximum of ``ybar``."""
    yb = _finite_array("ybar", ybar)
    if yb.size < MIN_AVERAGE_SAMPLES:
        raise InsufficientDataError(f"ybar needs at least {MIN_AVERAGE_SAMPLES} samples")
    if np.ptp(yb) == 0.0:
        raise ZeroAmplitudeError("the averaged output is constant: it has no maximum to time the phase by")
    return 2.0 * np.pi * int(np.argmax(yb)) / yb.size


def max_harmonics(samples_per_period: int) -> int:
    """Largest harmonic below Nyquist: floor((P - 1) / 2)."""
    return (int(samples_per_period) - 1) // 2


def spectral_derivative(ybar: ArrayLike, omega: float, harmonics: int) -> FloatArray:
    """Time derivative of the periodic signal ``ybar`` from its first ``harmonics`` Fourier harmonics."""
    yb = _finite_array("ybar", ybar)
    omega = _finite_scalar("omega", omega)
    p = yb.size
    k_max = max_harmonics(p)
    if not 1 <= harmonics <= k_max:
        raise InvalidParameterError(
            f"harmonics = {harmonics} must be in [1, {k_max}] for {p} samples per period (Nyquist excluded)"
        )
    if omega <= 0.0:
        raise InvalidParameterError(f"omega = {omega} rad/s must be > 0")
    coeffs = np.fft.rfft(yb) / p
    k = np.arange(coeffs.size)
    spec = np.where((k >= 1) & (k <= harmonics), 1j * k * omega * coeffs, 0.0)
    # irfft's normalisation divides by p and doubles the positive bins implicitly.
    return np.fft.irfft(spec * p, n=p)


def gain_estimate(
    ybar: ArrayLike,
    ydot: ArrayLike,
    amplitude: float,
    omega: float,
    phi: float,
    beta: float,
    gamma: float,
    mu: float,
) -> float:
    """|G(j omega)| from (27b), with the hysteresis parameters already estimated."""
    yb, yd, s, _ = sls_inputs(ybar, ydot, amplitude, omega, phi)
    for name, v in (("beta", beta), ("gamma", gamma), ("mu", mu)):
        _finite_scalar(name, v)
    ymu = np.abs(yb) ** mu
    chi = s * (-1.0 + beta * np.sign(yd) * np.sign(yb) * ymu + gamma * ymu)
    den = float(np.sum(chi**2))
    if den == 0.0:
        raise SingularNormalMatrixError("the gain regressor chi of (27b) is identically zero")
    return float(np.sum(yd * chi) / den)
