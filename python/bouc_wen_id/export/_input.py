"""The sampled input as the simulator sees it between samples (docs/design.md section 1, 9.4).

Cubic Hermite on ``[t_k, t_{k+1}]`` with Catmull-Rom slopes ``m_k = (u_{k+1} - u_{k-1}) / (2 dt)``
(one-sided at the ends), the last value with slope 0 after the last sample, 0 before ``t = 0``; the second
derivative is the cubic's right-hand one (0 past the end); ``Vmax`` is the interpolant's exact peak slope.
Written in the simulator's operation order, so that an exported model driven by it agrees with
:func:`bouc_wen_id.simulate_input` to rounding.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError
from ..validation import EXACT_GRID_RTOL, check_time_axis, finite_array

__all__ = ["SampledInput"]

FloatArray = NDArray[np.float64]


class SampledInput:
    """The Catmull-Rom interpolant of samples ``u`` on the grid ``t_k = t_0 + k dt`` (time from ``t_0``)."""

    def __init__(self, t: ArrayLike, u: ArrayLike) -> None:
        tt = finite_array("t", t)
        uu = finite_array("u", u)
        if tt.ndim != 1 or uu.ndim != 1 or tt.size != uu.size or tt.size < 2:
            raise InvalidParameterError(
                f"t and u must be 1-D of equal lengths >= 2, got shapes {tt.shape} and {uu.shape}"
            )
        check_time_axis(tt, rtol=EXACT_GRID_RTOL)
        #: The step, as :func:`bouc_wen_id.simulate_input` takes it (the mean of the differences).
        self.dt = float(np.mean(np.diff(tt)))
        self.u = uu.copy()
        n, dt = uu.size, self.dt
        m = np.zeros(n)
        for k in range(1, n - 1):
            m[k] = (uu[k + 1] - uu[k - 1]) / (2.0 * dt)
        m[0] = (uu[1] - uu[0]) / dt
        m[n - 1] = (uu[n - 1] - uu[n - 2]) / dt
        self.m = m

    def _locate(self, tau: float) -> tuple[int, float]:
        q = tau / self.dt
        kf = math.floor(q)
        return int(kf), q - kf

    def at(self, tau: float) -> tuple[float, float, float]:
        """``(u, udot, uddot)`` at ``tau`` (s from the first sample); 0 before it, held after the last."""
        if tau < 0.0:
            return 0.0, 0.0, 0.0
        last = self.u.size - 1
        if tau / self.dt >= last:  # compared as a float, as the simulator does
            return float(self.u[last]), 0.0, 0.0
        k, s = self._locate(tau)
        dt = self.dt
        u0, u1, m0, m1 = float(self.u[k]), float(self.u[k + 1]), float(self.m[k]), float(self.m[k + 1])
        s2, s3 = s * s, s * s * s
        h00 = 2.0 * s3 - 3.0 * s2 + 1.0
        h10 = s3 - 2.0 * s2 + s
        h01 = -2.0 * s3 + 3.0 * s2
        h11 = s3 - s2
        val = h00 * u0 + h10 * dt * m0 + h01 * u1 + h11 * dt * m1
        d00 = 6.0 * s2 - 6.0 * s
        d10 = 3.0 * s2 - 4.0 * s + 1.0
        d01 = -6.0 * s2 + 6.0 * s
        d11 = 3.0 * s2 - 2.0 * s
        der = (d00 * u0 + d01 * u1) / dt + d10 * m0 + d11 * m1
        second = ((12.0 * s - 6.0) * u0 + (6.0 - 12.0 * s) * u1) / (dt * dt) + (
            (6.0 * s - 4.0) * m0 + (6.0 * s - 2.0) * m1
        ) / dt
        return val, der, second

    def peak_rate(self) -> float:
        """``Vmax = max |udot|`` of the interpolant, exactly (its knots and the vertices of its slope)."""
        peak = 0.0
        u, m, dt = self.u, self.m, self.dt
        for k in range(u.size - 1):
            m0, m1 = float(m[k]), float(m[k + 1])
            slope = (float(u[k + 1]) - float(u[k])) / dt
            qa = 3.0 * (m0 + m1) - 6.0 * slope
            qb = 6.0 * slope - 4.0 * m0 - 2.0 * m1
            peak = max(peak, abs(m0), abs(m1))
            if qa != 0.0:
                s = -qb / (2.0 * qa)
                if 0.0 < s < 1.0:
                    peak = max(peak, abs(m0 + s * (qb + s * qa)))
        return peak
