"""The Hurwitz parameterisation of ``G(s') = exp(-tau' s') N(s') / D(s')`` and the start poles' clean-up.

The denominator is a product of sections ``s'^2 + e^p s' + e^q`` and (odd degree) ``s' + e^r`` in the scaled
frequency ``s' = s / w0``: each is Hurwitz for every real ``p, q, r``, so the refinement cannot leave the
stable models.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

#: A reflected or axis pole is moved to damping ratio at least this, so its log-parameters stay finite.
MIN_START_DAMPING = 1e-3
#: Smallest delay (scaled, tau w0) of a start: the delay is fitted as exp(t), so 0 is approached, not held.
MIN_START_DELAY = 1e-3
#: Bound on the log-coefficients of the denominator sections (in the scaled frequency s' = s / w0).
LOG_BOUND = 40.0


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
