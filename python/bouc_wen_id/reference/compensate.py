"""NumPy reference of ``rust/compensate.rs``: the Bouc-Wen operator inverted along a sampled path, and the
actuator's rate limiter (issue 21, item 1; :mod:`bouc_wen_id.compensation`).

``h(w, s) = alpha - |w|^mu (beta s sgn w + gamma + delta sgn w)`` so that ``wdot = xdot h(w, sgn xdot)``;
over a sample interval where ``w`` moves monotonically from ``w_a`` to ``w_b``, ``x`` moves by
``int_{w_a}^{w_b} dw / h(w, sgn(w_b - w_a))`` (the element is rate-independent), by an 8-node
Gauss-Legendre rule split at ``w = 0``, on ``FINE_PANELS`` panels where ``h`` varies by more than
``FINE_RATIO`` over the interval.  Vectorised over the intervals, then a cumulative sum: the same rule, node
for node, as the Rust loop.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InvalidParameterError, NonFiniteError

__all__ = ["GL_NODES", "GL_WEIGHTS", "FINE_PANELS", "FINE_RATIO", "h_rate", "invert_path", "rate_limit"]

FloatArray = NDArray[np.float64]

#: Gauss-Legendre nodes and weights on [0, 1] (numpy's ``leggauss(8)`` mapped; the Rust core's literals).
GL_NODES = np.array(
    [
        0.019855071751231912,
        0.10166676129318664,
        0.2372337950418355,
        0.4082826787521751,
        0.5917173212478248,
        0.7627662049581645,
        0.8983332387068134,
        0.9801449282487681,
    ]
)
GL_WEIGHTS = np.array(
    [
        0.05061426814518853,
        0.11119051722668721,
        0.15685332293894344,
        0.18134189168918083,
        0.18134189168918083,
        0.15685332293894344,
        0.11119051722668721,
        0.05061426814518853,
    ]
)
FINE_PANELS = 16
FINE_RATIO = 1.2


def h_rate(
    w: FloatArray, s: FloatArray, alpha: float, beta: float, gamma: float, mu: float, delta: float
) -> FloatArray:
    """``h(w, s)``: ``wdot = xdot h(w, sgn xdot)``."""
    sw = np.sign(w)
    return np.asarray(alpha - np.abs(w) ** mu * (beta * s * sw + gamma + delta * sw))


def _integral(a: FloatArray, b: FloatArray, s: FloatArray, p: tuple[float, ...]) -> FloatArray:
    span = b - a
    nodes = a[:, None] + span[:, None] * GL_NODES[None, :]
    out = span * (GL_WEIGHTS[None, :] / h_rate(nodes, s[:, None], *p)).sum(axis=1)
    ha, hb = h_rate(a, s, *p), h_rate(b, s, *p)
    rough = np.flatnonzero(np.maximum(ha, hb) > FINE_RATIO * np.minimum(ha, hb))
    if rough.size:
        lo = a[rough, None] + span[rough, None] * (np.arange(FINE_PANELS) / FINE_PANELS)[None, :]
        width = span[rough, None] / FINE_PANELS
        fine = lo[:, :, None] + width[:, :, None] * GL_NODES[None, None, :]
        val = h_rate(fine, s[rough, None, None], *p)
        out[rough] = (width * (GL_WEIGHTS[None, None, :] / val).sum(axis=2)).sum(axis=1)
    return np.asarray(out)


def invert_path(
    w: ArrayLike, alpha: float, beta: float, gamma: float, mu: float, delta: float, w0: float, x0: float
) -> FloatArray:
    """The path ``x`` whose Bouc-Wen output is ``w`` at the samples, from the state ``(x0, w0)``.

    Raises NonFiniteError (a non-finite sample) and InvalidParameterError (an element with no invertible
    range, a sample at or beyond the saturation levels), as the Rust core.
    """
    ww = np.ascontiguousarray(w, dtype=np.float64)
    if not (alpha > 0 and mu >= 1 and beta + gamma - abs(delta) > 0 and beta >= gamma):
        raise InvalidParameterError(
            f"the element (alpha {alpha}, beta {beta}, gamma {gamma}, mu {mu}, delta {delta}) has no "
            "invertible range"
        )
    bad = np.flatnonzero(~np.isfinite(ww))
    if bad.size:
        raise NonFiniteError(f"w[{bad[0]}] = {ww[bad[0]]}")
    down = (alpha / (beta + gamma - delta)) ** (1.0 / mu)
    up = (alpha / (beta + gamma + delta)) ** (1.0 / mu)
    out = np.flatnonzero((ww >= up) | (ww <= -down))
    if out.size or not -down < w0 < up:
        k = int(out[0]) if out.size else 0
        raise InvalidParameterError(f"w[{k}] is outside the invertible range ({-down}, {up})")
    p = (alpha, beta, gamma, mu, delta)
    wa = np.concatenate(([w0], ww[:-1]))
    s = np.sign(ww - wa)
    cross = wa * ww < 0.0
    mid = np.where(cross, 0.0, ww)
    dx = _integral(wa, mid, s, p) + np.where(cross, _integral(mid, ww, s, p), 0.0)
    return np.asarray(x0 + np.cumsum(dx))


def rate_limit(target: ArrayLike, step: float, start: float) -> FloatArray:
    """The command moved toward ``target`` by at most ``step`` per sample, from ``start``."""
    if not (step > 0 and np.isfinite(step)):
        raise InvalidParameterError(f"the rate limit's step {step} must be finite and > 0")
    tt = np.asarray(target, dtype=np.float64)
    out = np.empty_like(tt)
    prev = float(start)
    for k in range(tt.size):
        prev = prev + min(max(float(tt[k]) - prev, -step), step)
        out[k] = prev
    return out
