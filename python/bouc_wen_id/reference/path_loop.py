"""NumPy reference of ``rust/path_loop.rs``: the steady hysteresis loop along the input path (design.md 9.2).

Generalised Bouc-Wen with alpha = 1 and the ``sgn(w)`` asymmetry term of Song & Der Kiureghian (J. Eng.
Mech. 132(6), 2006), driven through a play (backlash) operator of half-width ``b``::

    wdot = xpdot [1 - |w|^mu (beta sgn(xpdot w) + gamma + delta sgn(w))],   xp = Play_b[x]

with ``x = A cos(theta - phi)``.  Rate independence lets the loop be integrated in ``xp`` from node to node
(the P samples and the two reversals of x): each segment is RK4 on ``dw/dsigma = dx h(w, s)``,
``sigma in [0, 1]``, with the forward sensitivities riding along, and the steady state is the fixed point
of one cycle of segment maps, found by Newton shooting on the top value safeguarded by bisection.

This is the plain, step-by-step version (one chain, a 7-component RK4 state per segment) that the Rust
core :func:`bouc_wen_id._core.path_loop` is held to; the core reaches the same discrete fixed point by a
faster route (multiple shooting, derivatives summed in reverse), so the two agree to the shooting tolerance,
not bit for bit, and their ``iterations`` counts differ.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Union

import numpy as np
from numpy.typing import NDArray

from ..errors import (
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    NotConvergedError,
    ZeroAmplitudeError,
)
from ..validation import finite_scalar as _finite_scalar
from .steady import bracketed_newton, next_iteration
from .terms import PINCHING_CENTRE, PINCHING_WIDTH

FloatArray = NDArray[np.float64]

__all__ = [
    "path_loop",
    "path_loop_distorted",
    "PD_BETA",
    "PD_GAMMA",
    "PD_MU",
    "PD_AMPLITUDE",
    "PD_PHI",
    "PD_DELTA",
    "PD_PLAY",
    "PD_DISTORT",
    "PD_PINCH",
]

#: Columns of the Jacobian returned by :func:`path_loop` (as ``rust/path_loop.rs``);
#: :func:`path_loop_distorted` adds ``PD_DISTORT``, ``d w / d lambda``.
PD_BETA, PD_GAMMA, PD_MU, PD_AMPLITUDE, PD_PHI, PD_DELTA, PD_PLAY, PD_DISTORT = range(8)
#: :func:`path_loop_pinched` adds ``d w / d zeta1``.
PD_PINCH = 8

#: Pinching of :func:`path_loop_pinched`: ``(zeta1, w_u, d w_u / d(beta, gamma, mu))``, or None.
_Pinch = tuple[float, float, tuple[float, float, float]]

#: Newton (or bisection) updates of the top value allowed.
PATH_SHOOT_MAX_ITER = 60
#: Periodicity tolerance ``|W(w_0) - w_0| <= PATH_SHOOT_RTOL * w_b``.
PATH_SHOOT_RTOL = 1e-13

# A node: (xp, d xp / d(A, phi, b)).
_Node = tuple[float, tuple[float, float, float]]
#: A node of either input: the pure sine's (d/d(A, phi, b)) or the distorted one's (and d/d lambda).
_AnyNode = Union[_Node, tuple[float, FloatArray]]


def _rate(
    beta: float,
    gamma: float,
    mu: float,
    delta: float,
    s: float,
    dx: float,
    y: FloatArray,
    pin: _Pinch | None = None,
) -> FloatArray:
    """Rate in sigma of ``[w, dw/dw_a, dw/d dx, dw/d beta, dw/d gamma, dw/d mu, dw/d delta, dw/d zeta1]``.

    With pinching, ``h`` is the Bouc-Wen ``h_b`` times Foliente's ``P = 1 - zeta1 exp(-z^2)``,
    ``z = (w s - q w_u) / (zeta2 w_u)``, differentiated through ``w_u(beta, gamma, mu)`` too.
    """
    w = float(y[0])
    aw = abs(w)
    sw = float(np.sign(w))
    if aw > 0.0:
        lnw = float(np.log(aw))
        wmu = float(np.exp(mu * lnw))
        wmu1 = wmu / aw
    else:
        lnw = wmu = wmu1 = 0.0
    c = gamma + (beta * s + delta) * sw
    hb = 1.0 - wmu * c
    # d/dw |w|^mu = mu |w|^(mu-1) sgn(w); d/dw sgn(w) |w|^mu = mu |w|^(mu-1).
    hbw = -mu * wmu1 * (gamma * sw + beta * s + delta)
    if pin is None:
        pf, hw, q_extra, q_z = 1.0, hbw, (0.0, 0.0, 0.0), 0.0
    else:
        zeta1, w_u, dwu = pin
        width = PINCHING_WIDTH * w_u
        z = (w * s - PINCHING_CENTRE * w_u) / width
        g = float(np.exp(-z * z))
        pf = 1.0 - zeta1 * g
        p_dz = 2.0 * zeta1 * g * z
        hw = hbw * pf + hb * p_dz * s / width
        p_wu = -p_dz * w * s / (w_u * width)
        q_extra = (dx * hb * p_wu * dwu[0], dx * hb * p_wu * dwu[1], dx * hb * p_wu * dwu[2])
        q_z = -dx * hb * g
    h = hb * pf
    fw = dx * hw
    return np.array(
        [
            dx * h,
            fw * y[1],
            fw * y[2] + h,
            fw * y[3] - dx * wmu * s * sw * pf + q_extra[0],
            fw * y[4] - dx * wmu * pf + q_extra[1],
            fw * y[5] - dx * wmu * lnw * c * pf + q_extra[2],
            fw * y[6] - dx * wmu * sw * pf,
            fw * y[7] + q_z,
        ]
    )


def _segment(
    beta: float,
    gamma: float,
    mu: float,
    delta: float,
    s: float,
    dx: float,
    w: float,
    substeps: int,
    pin: _Pinch | None = None,
) -> FloatArray:
    """The segment map and its sensitivities: RK4 from ``[w, 1, 0, 0, 0, 0, 0, 0]`` over sigma in [0, 1]."""
    y = np.array([w, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    hs = 1.0 / substeps
    for _ in range(substeps):
        k1 = _rate(beta, gamma, mu, delta, s, dx, y, pin)
        k2 = _rate(beta, gamma, mu, delta, s, dx, y + 0.5 * hs * k1, pin)
        k3 = _rate(beta, gamma, mu, delta, s, dx, y + 0.5 * hs * k2, pin)
        k4 = _rate(beta, gamma, mu, delta, s, dx, y + hs * k3, pin)
        y = y + hs / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    return y


def _play_node(a: float, sa: float, b: float, zeta: float, descending: bool) -> _Node:
    """``xp`` at cycle phase ``zeta`` (0 at the top of x) and its derivatives on the active branch."""
    x = a * np.cos(zeta)
    dxa, dxphi = sa * np.cos(zeta), a * np.sin(zeta)
    if descending:
        # After the top, xp dwells at a - b until x has come down by 2b, then follows x + b.
        if x < a - 2.0 * b:
            return float(x + b), (float(dxa), float(dxphi), 1.0)
        return a - b, (sa, 0.0, -1.0)
    if x > -a + 2.0 * b:
        return float(x - b), (float(dxa), float(dxphi), -1.0)
    return -a + b, (-sa, 0.0, 1.0)


def _segments(amplitude: float, phi: float, b: float, p: int) -> list[tuple[float, FloatArray, float, int]]:
    """The P + 2 segments ``(dx, d dx/d(A, phi, b, lambda), s, sample or -1)`` of one cycle, from the top."""
    a = abs(amplitude)
    sa = float(np.sign(amplitude))
    # Cycle phase of sample j as a fraction of the period: frac(j/P - phi'/(2 pi)),
    # phi' = phi (+ pi for A < 0, whose top is at theta - phi = pi).
    shift = 0.5 if amplitude < 0.0 else 0.0
    r = (phi / (2.0 * np.pi) + shift) % 1.0
    top: _Node = (a - b, (sa, 0.0, -1.0))
    bottom: _Node = (-a + b, (-sa, 0.0, 1.0))

    def node_at(j: int, uj: float, descending: bool) -> _Node:
        return _play_node(a, sa, b, 2.0 * np.pi * uj, descending)

    return _cycle_segments(r, 0.5, p, top, bottom, node_at, pad=True)


def _cycle_segments(
    r: float,
    ub: float,
    p: int,
    top: _AnyNode,
    bottom: _AnyNode,
    node_at: Callable[[int, float, bool], _AnyNode],
    pad: bool,
) -> list[tuple[float, FloatArray, float, int]]:
    """The segments ``(dx, d dx/dq, s, sample or -1)`` of one cycle from the top reversal, whose cycle phase
    is ``r`` (a fraction of the period on the sample grid), through the samples' nodes ``node_at(j, u_j,
    descending)`` (``u_j`` the sample's cycle phase; descending up to the bottom reversal at ``ub``) and the
    bottom one, back to the top; ``pad`` appends the ``lambda`` column a pure sine does not have."""
    u = np.arange(p) / p - r
    u = np.where(u < 0.0, u + 1.0, u)
    j0 = int(np.argmin(u))
    nodes: list[tuple[_AnyNode, float, int]] = []
    passed_bottom = False
    for m in range(p):
        j = (j0 + m) % p
        descending = bool(u[j] <= ub)
        if not descending and not passed_bottom:
            nodes.append((bottom, -1.0, -1))
            passed_bottom = True
        nodes.append((node_at(j, float(u[j]), descending), -1.0 if descending else 1.0, j))
    if not passed_bottom:
        nodes.append((bottom, -1.0, -1))
    nodes.append((top, 1.0, -1))
    segs = []
    prev = top
    for node, s, j in nodes:
        d = np.subtract(node[1], prev[1])
        segs.append((node[0] - prev[0], np.append(d, 0.0) if pad else d, s, j))
        prev = node
    return segs


def _check_loop(amplitude: float, beta: float, gamma: float, mu: float, delta: float, play: float) -> float:
    """The checks :func:`path_loop` and :func:`path_loop_distorted` share, in the core's order: ``mu > 1``,
    ``beta + gamma - |delta| > 0`` (returned), ``A != 0``, ``play >= 0``."""
    if mu <= 1.0:
        raise InvalidParameterError(f"mu = {mu} must be > 1 in the identification model")
    margin = beta + gamma - abs(delta)
    if margin <= 0.0:
        raise InvalidParameterError(
            f"beta + gamma - |delta| = {margin} must be > 0: otherwise one side of the loop is unbounded"
        )
    if amplitude == 0.0:
        raise ZeroAmplitudeError("the amplitude of x is 0: the loop is a point")
    if play < 0.0:
        raise InvalidParameterError(f"play = {play} must be >= 0")
    return margin


def path_loop(
    amplitude: float,
    beta: float,
    gamma: float,
    mu: float,
    delta: float,
    play: float,
    phi: float,
    samples_per_period: int,
    substeps: int,
    *,
    pinch: float | None = None,
) -> tuple[FloatArray, FloatArray, int]:
    """Steady loop of the generalised Bouc-Wen behind a play, along the path of ``x = A cos(theta - phi)``.

    With ``pinch`` (``zeta1`` in ``[0, 1)``; the core's ``path_loop_pinched``) ``h`` is multiplied by
    Foliente's factor and ``jac`` has all 9 columns, ``PD_PINCH`` the last.

    Parameters
    ----------
    amplitude : float
        ``A``, the amplitude of x (units of x; may be negative, its top is then at ``theta - phi = pi``).
    beta, gamma, delta : float
        Shape parameters (``1/[w]^mu``); ``delta`` is the asymmetry. ``beta + gamma - |delta| > 0``.
    mu : float
        Exponent, ``> 1``.
    play : float
        Half-width ``b`` of the play before the hysteresis (units of x), ``0 <= b < |A|``.
    phi : float
        Phase of x (rad) on the grid ``theta_j = 2 pi j / P``.
    samples_per_period : int
        ``P >= 4``.
    substeps : int
        RK4 steps per segment between nodes, ``>= 1``.

    Returns
    -------
    w : ndarray, shape (P,)
        The steady loop at the samples (units of w).
    jac : ndarray, shape (P, 7)
        ``d w_j / d(beta, gamma, mu, A, phi, delta, b)`` (columns ``PD_*``).
    iterations : int
        Newton (or bisection) updates of the top value.

    Raises
    ------
    NonFiniteError, InvalidParameterError, ZeroAmplitudeError, InsufficientDataError, NotConvergedError
        As :func:`bouc_wen_id._core.path_loop`.
    """
    for name, v in (
        ("amplitude", amplitude),
        ("beta", beta),
        ("gamma", gamma),
        ("mu", mu),
        ("delta", delta),
        ("play", play),
        ("phi", phi),
    ):
        _finite_scalar(name, v)
    margin = _check_loop(amplitude, beta, gamma, mu, delta, play)
    if play >= abs(amplitude):
        raise ZeroAmplitudeError(
            f"play = {play} >= |amplitude| = {abs(amplitude)}: no motion reaches the hysteresis"
        )
    p = int(samples_per_period)
    if p < 4:
        raise InsufficientDataError(f"samples_per_period = {p}: at least 4 are needed")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")

    pin = _pinch(beta, gamma, mu, pinch)
    jac, iterations, w = _solve(
        _segments(amplitude, phi, play, p), beta, gamma, mu, delta, margin, p, substeps, pin
    )
    return w, (jac[:, :7] if pin is None else jac), iterations


def _pinch(beta: float, gamma: float, mu: float, pinch: float | None) -> _Pinch | None:
    """``(zeta1, w_u, d w_u / d(beta, gamma, mu))`` for :func:`_rate`, after the core's check of zeta1."""
    if pinch is None:
        return None
    _finite_scalar("zeta1", pinch)
    if not 0.0 <= pinch < 1.0:
        raise InvalidParameterError(f"pinching zeta1 = {pinch} must be in [0, 1)")
    bg = beta + gamma
    w_u = float(bg ** (-1.0 / mu))
    d_bg = -w_u / (mu * bg)
    return float(pinch), w_u, (d_bg, d_bg, w_u * float(np.log(bg)) / (mu * mu))


def _solve(
    segs: list[tuple[float, FloatArray, float, int]],
    beta: float,
    gamma: float,
    mu: float,
    delta: float,
    margin: float,
    p: int,
    substeps: int,
    pin: _Pinch | None = None,
) -> tuple[FloatArray, int, FloatArray]:
    """Single shooting on the cycle of segments: ``(jac (P, 9), iterations, w)``."""
    with np.errstate(over="ignore", divide="ignore"):
        bound = float(np.float64(1.0) / margin) ** (1.0 / mu)
    if not (np.isfinite(bound) and bound > 0.0):
        raise InvalidParameterError(f"the bound (beta + gamma - |delta|)^(-1/mu) = {bound} is unusable")
    w = np.zeros(p)
    t_rows = np.zeros((p, 9))
    phis = np.zeros(p)

    def cycle(w0: float) -> tuple[float, float, FloatArray]:
        """One cycle from ``w0``: ``W``, ``dW/dw0``, ``dW/dq`` at fixed ``w0``; records the samples."""
        wc, ph, t = w0, 1.0, np.zeros(9)
        for dx, ddx, s, j in segs:
            y = _segment(beta, gamma, mu, delta, s, dx, wc, substeps, pin)
            # Chain rule through the segment: T <- Psi_w T + Psi_q (+ Psi_dx d dx/dq for A, phi, b).
            t = y[1] * t
            t[[PD_BETA, PD_GAMMA, PD_MU, PD_DELTA, PD_PINCH]] += y[3:8]
            t[[PD_AMPLITUDE, PD_PHI, PD_PLAY, PD_DISTORT]] += y[2] * ddx
            ph *= y[1]
            wc = float(y[0])
            if j >= 0:
                w[j], t_rows[j], phis[j] = wc, t, ph
        return wc, ph, t

    lo, hi = -bound, bound
    w0 = 0.0
    iterations = 0
    while True:
        # A runaway cycle overflows to inf/NaN, which the residual test below turns into NotConvergedError.
        with np.errstate(over="ignore", invalid="ignore"):
            wn, dw, t_end = cycle(w0)
        g = wn - w0
        if not np.isfinite(g):
            raise NotConvergedError(f"the path-loop shooting diverged (w reached {wn} within one cycle)")
        if abs(g) <= PATH_SHOOT_RTOL * bound:
            break
        failure = f"the path-loop shooting found no periodic loop in {PATH_SHOOT_MAX_ITER}"
        iterations = next_iteration(iterations, PATH_SHOOT_MAX_ITER, failure, g)
        # g = W(w0) - w0 is positive at -w_b and negative at w_b: -g increases, with slope 1 - dW/dw0.
        w0, lo, hi = bracketed_newton(w0, -g, 1.0 - dw, lo, hi)
    # dw_0/dq = (dW/dq) / (1 - dW/dw_0); every sample T_j + Phi_j dw_0/dq.
    jac = t_rows + phis[:, None] * (t_end / (1.0 - dw))[None, :]
    if not (np.all(np.isfinite(w)) and np.all(np.isfinite(jac))):
        raise NonFiniteError("the path loop or its sensitivities overflowed; rescale the data")
    return jac, iterations, w


# --------------------------------------------------------------------------------------------------------
# A measured, non-sinusoidal input (design.md 9.5): x = A xi(theta - phi), xi = cos + lambda d.

#: Grid points per period (at least, and per highest harmonic) bracketing the reversals (as the core).
REVERSAL_GRID_MIN = 64
REVERSAL_GRID_PER_HARMONIC = 8


def waveform(zeta: float, lam: float, harmonics: FloatArray) -> tuple[float, float, float, float]:
    """``(xi, xi', xi'', d)`` at ``zeta``; ``harmonics = [Re c_2, Im c_2, Re c_3, ...]``."""
    c = np.asarray(harmonics, dtype=np.float64).reshape(-1, 2)
    k = np.arange(2, 2 + c.shape[0], dtype=np.float64)
    cz, sz = np.cos(k * zeta), np.sin(k * zeta)
    v = c[:, 0] * cz - c[:, 1] * sz
    d = float(np.sum(v))
    d1 = float(np.sum(-k * (c[:, 0] * sz + c[:, 1] * cz)))
    d2 = float(np.sum(-k * k * v))
    return (
        float(np.cos(zeta)) + lam * d,
        -float(np.sin(zeta)) + lam * d1,
        -float(np.cos(zeta)) + lam * d2,
        d,
    )


def reversals(lam: float, harmonics: FloatArray) -> list[float]:
    """Roots of ``xi'`` in ``[0, 2 pi)``: sign changes on a grid, each refined by bisection to rounding."""
    n_h = np.asarray(harmonics).size // 2
    m = max(REVERSAL_GRID_MIN, REVERSAL_GRID_PER_HARMONIC * (n_h + 1))
    h = 2.0 * np.pi / m
    roots = []
    for i in range(m):
        lo, hi = i * h, (i + 1) * h
        flo, fhi = waveform(lo, lam, harmonics)[1], waveform(hi, lam, harmonics)[1]
        if flo == 0.0:
            roots.append(lo)
            continue
        if flo * fhi >= 0.0:
            continue
        for _ in range(200):  # plain bisection: slower than the core's Newton, the same root
            mid = 0.5 * (lo + hi)
            fm = waveform(mid, lam, harmonics)[1]
            if fm == 0.0 or hi - lo <= 4.0 * np.finfo(float).eps * (1.0 + mid):
                break
            if (fm < 0.0) == (flo < 0.0):
                lo = mid
            else:
                hi = mid
        roots.append(0.5 * (lo + hi))
    return roots


def _check_distorted(
    amplitude: float,
    beta: float,
    gamma: float,
    mu: float,
    delta: float,
    play: float,
    lam: float,
    harmonics: FloatArray,
    samples_per_period: int,
) -> tuple[FloatArray, float, int]:
    """The arguments of :func:`path_loop_distorted` checked as the core does: ``(harmonics, beta + gamma -
    |delta|, P)``."""
    harmonics = np.asarray(harmonics, dtype=np.float64)
    for name, v in (("amplitude", amplitude), ("beta", beta), ("gamma", gamma), ("mu", mu), ("lambda", lam)):
        _finite_scalar(name, v)
    if harmonics.size % 2 or not np.all(np.isfinite(harmonics)):
        raise InvalidParameterError("the waveform's harmonics must be finite (re, im) pairs")
    margin = _check_loop(amplitude, beta, gamma, mu, delta, play)
    p = int(samples_per_period)
    if p < 4:
        raise InsufficientDataError(f"samples_per_period = {p}: at least 4 are needed")
    return harmonics, margin, p


def path_loop_distorted(
    amplitude: float,
    beta: float,
    gamma: float,
    mu: float,
    delta: float,
    play: float,
    phi: float,
    lam: float,
    harmonics: FloatArray,
    samples_per_period: int,
    substeps: int,
    *,
    pinch: float | None = None,
) -> tuple[FloatArray, FloatArray, int]:
    """:func:`path_loop` along ``x = A xi(theta - phi)``, ``xi(zeta) = cos(zeta) + lam d(zeta)``.

    Parameters
    ----------
    lam : float
        ``lambda``, the scale of the measured distortion (1: the measured waveform; 0: the pure sine).
    harmonics : ndarray, shape (2 K,)
        ``[Re c_2, Im c_2, Re c_3, Im c_3, ...]``, ``d(zeta) = sum_k Re(c_k e^{i k zeta})``.
    others : as :func:`path_loop` (``play`` below the half travel of x; ``pinch`` adds ``PD_PINCH``).

    Returns
    -------
    w : ndarray, shape (P,)
    jac : ndarray, shape (P, 8)
        ``d w_j / d(beta, gamma, mu, A, phi, delta, b, lambda)``.
    iterations : int

    Raises
    ------
    InvalidParameterError
        As :func:`path_loop`, and for a waveform with more than one maximum per period.
    """
    harmonics, margin, p = _check_distorted(
        amplitude, beta, gamma, mu, delta, play, lam, harmonics, samples_per_period
    )
    # x = |A| xi(theta - phi'), phi' = phi (+ pi for A < 0); d/dA = sgn(A) d/d|A| (as the core).
    sa = 1.0 if amplitude > 0.0 else -1.0
    if amplitude < 0.0:
        amplitude, phi = -amplitude, phi + np.pi
    roots = reversals(lam, harmonics)
    if len(roots) != 2:
        raise InvalidParameterError(
            f"the input waveform has {len(roots)} reversals per period: one maximum and one minimum supported"
        )
    e = [waveform(z, lam, harmonics) for z in roots]
    top_first = amplitude * (e[0][0] - e[1][0]) > 0.0
    (zt, et), (zb, eb) = (
        ((roots[0], e[0]), (roots[1], e[1])) if top_first else ((roots[1], e[1]), (roots[0], e[0]))
    )
    xt, xb = amplitude * et[0], amplitude * eb[0]
    b = play
    if b >= 0.5 * (xt - xb):
        raise ZeroAmplitudeError(f"play = {b} >= the half travel {0.5 * (xt - xb)} of x")
    top: tuple[float, FloatArray] = (xt - b, np.array([sa * et[0], 0.0, -1.0, amplitude * et[3]]))
    bottom: tuple[float, FloatArray] = (xb + b, np.array([sa * eb[0], 0.0, 1.0, amplitude * eb[3]]))
    r = ((phi + zt) / (2.0 * np.pi)) % 1.0
    ub = ((zb - zt) / (2.0 * np.pi)) % 1.0

    def node_at(j: int, uj: float, descending: bool) -> tuple[float, FloatArray]:
        xi, dxi, _, d = waveform(2.0 * np.pi * j / p - phi, lam, harmonics)
        x = amplitude * xi
        # Descending: xp = min(x_top - b, x + b); ascending: xp = max(x_bot + b, x - b).
        if descending:
            return (
                (x + b, np.array([sa * xi, -amplitude * dxi, 1.0, amplitude * d]))
                if x < xt - 2.0 * b
                else top
            )
        return (
            (x - b, np.array([sa * xi, -amplitude * dxi, -1.0, amplitude * d]))
            if x > xb + 2.0 * b
            else bottom
        )

    segs = _cycle_segments(r, ub, p, top, bottom, node_at, pad=False)
    pin = _pinch(beta, gamma, mu, pinch)
    jac, iterations, w = _solve(segs, beta, gamma, mu, delta, margin, p, substeps, pin)
    return w, (jac[:, :8] if pin is None else jac), iterations
