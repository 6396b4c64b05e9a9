"""What a chosen fit is checked for before it is returned: no model that fails its own fit goes out silently.

Each check gives a message and the warning it is issued as: :class:`PoorFitWarning` when the fit's own
residuals refute it (too large for the points' uncertainty, or for their scatter when they carry none; with
a hint when the points look like an unstable source), :class:`IdentifiabilityWarning` when the points
cannot pin down what the model claims (more parameters than equations, a resonance between points, a pole
at the origin, a pole and a zero that cancel).
"""

from __future__ import annotations

import math
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import IdentifiabilityWarning, PoorFitWarning
from ..model import TransferFunction
from ._points import _Points
from ._refine import _Fit
from ._select import _resonance_warnings

FloatArray = NDArray[np.float64]
Finding = tuple[str, type[Warning]]

#: Points with a covariance: a chi-square p-value below this refutes the model.  The points' covariance is
#: itself estimated (from N periods), so the chi-square of a right model has a heavier tail than nominal:
#: benches/tfit.py sees p ~ 3e-4 among a hundred right-order fits; a misfit gives p far below 1e-6.
POOR_FIT_P = 1e-4
#: Points without uncertainty: a root-mean-square relative error of the fit above this refutes it (the
#: identified points are good to a few per cent; a model 10 % off them does not describe them).
POOR_FIT_RELATIVE = 0.1
#: A real pole closer to the origin than this fraction of the lowest tested frequency acts as an
#: integrator over the band: the points cannot give its DC gain.
ORIGIN_RTOL = 0.01
#: A zero within this relative distance of a pole cancels it: the order is higher than the points need.
CANCEL_RTOL = 0.02


def findings(points: _Points, f: _Fit, tf: TransferFunction, p_value: Optional[float]) -> list[Finding]:
    """Every warning the chosen fit ``f`` (reported as ``tf``) earns on ``points``."""
    eqs = 2 * points.omega.size
    k = (f.m + 1) + f.n + (1 if f.delay else 0)
    out: list[Finding] = []
    if k >= eqs:
        msg = (
            f"{k} parameters from {eqs} real equations ({points.omega.size} points): the fit "
            "interpolates and its parameters are not determined; add frequencies or lower the order"
        )
        out.append((msg, IdentifiabilityWarning))
    poor = _poor_fit(points, f, p_value)
    if poor:
        out.append((poor, PoorFitWarning))
    out += [(msg, IdentifiabilityWarning) for msg in _resonance_warnings(tf.den, points.omega)]
    cancelling = _cancelling_pairs(tf)
    cancelled = [p for _, p in cancelling]
    out += [(msg, IdentifiabilityWarning) for msg in _origin_poles(tf, points.omega, cancelled)]
    out += [(msg, IdentifiabilityWarning) for msg, _ in cancelling]
    return out


def _poor_fit(points: _Points, f: _Fit, p_value: Optional[float]) -> str:
    """Why the fit's own residuals refute it ("" when they do not); when the unconstrained start of the
    chosen order had poles in the right half plane, the points may be those of an unstable G."""
    if points.weighted:
        if p_value is None or p_value >= POOR_FIT_P:
            return ""
        what = f"chi2 = {f.chi2:.4g} (p = {p_value:.2g}): the model misses the points beyond their intervals"
    else:
        rms = math.sqrt(f.chi2 / points.omega.size)
        if rms <= POOR_FIT_RELATIVE:
            return ""
        what = (
            f"the model misses the points by {rms:.0%} (root-mean-square relative error, over "
            f"{POOR_FIT_RELATIVE:.0%})"
        )
    hint = (
        "; its unconstrained start had right-half-plane poles: the points may come from an unstable G, "
        "which a stable fit cannot follow (and whose sine steady state does not exist)"
        if f.reflected
        else "; raise max_order, fit a delay, or check the points (one linear G?)"
    )
    return what + hint


def _origin_poles(tf: TransferFunction, omega: FloatArray, cancelled: list[complex]) -> list[str]:
    """A pole at the origin, as far as the band can tell (an integrator), unless a zero cancels it."""
    near = [
        p for p in np.roots(tf.den) if abs(p) < ORIGIN_RTOL * float(omega[0]) and complex(p) not in cancelled
    ]
    if not near:
        return []
    return [
        f"a pole at {abs(near[0]):.3g} rad/s from the origin, below {ORIGIN_RTOL:.0%} of the lowest tested "
        f"frequency ({float(omega[0]):.4g} rad/s): over the band the fit is an integrator (a pole at the "
        "origin), its DC gain is not pinned down, and an integrating G has no sine steady state the "
        "method can use; test lower frequencies"
    ]


def _cancelling_pairs(tf: TransferFunction) -> list[tuple[str, complex]]:
    """A zero on top of a pole (the message, the pole): the pair does nothing the points can see."""
    if tf.num.size < 2:
        return []
    out = []
    zeros = np.roots(tf.num)
    for p in np.roots(tf.den):
        if p.imag < 0.0:
            continue
        gap = np.abs(zeros - p)
        if gap.size and float(np.min(gap)) < CANCEL_RTOL * abs(p):
            z = complex(zeros[int(np.argmin(gap))])
            msg = (
                f"a zero at {_c(z)} cancels the pole at {_c(complex(p))} (within {CANCEL_RTOL:.0%}): the "
                "pair is not determined by the points; fit a lower order (order=)"
            )
            out.append((msg, complex(p)))
    return out


def _c(v: complex) -> str:
    return f"{v.real:.4g}" if v.imag == 0 else f"{v.real:.4g}{v.imag:+.4g}j"
