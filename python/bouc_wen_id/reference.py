"""NumPy reference implementation of every core routine.

Readable, unoptimised, and written line by line from ``docs/design.md`` and the seed paper's equations.  It
exists to hold the Rust core (:mod:`bouc_wen_id._core`) to account: the parity tests call both on the same
seeded random inputs and compare.  Signatures match the ``_core`` functions one for one, and errors are the
same named exceptions from :mod:`bouc_wen_id.errors`.

The functions are usable on their own (``identify(..., backend="numpy")`` runs the whole identification on
them), but they are slow: the RK4 loop is plain Python.

References
----------
*Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose equation
numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2): F. Ikhouane and
J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control using the Bouc-Wen Model*,
Wiley, 2007.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Callable, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import BoucWenIdError as BoucWenIdErrorBase
from .errors import (
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    NotConvergedError,
    SearchAtBoundError,
    SingularNormalMatrixError,
    ZeroAmplitudeError,
)
from .validation import MIN_AVERAGE_SAMPLES, check_transfer_function, routh_hurwitz_stable
from .validation import check_bouc_wen as _check_bouc_wen
from .validation import finite_array as _finite_array
from .validation import finite_scalar as _finite_scalar

__all__ = [
    "realize",
    "routh_hurwitz_stable",
    "simulate_sine",
    "simulate_sampled",
    "periodic_average",
    "phase_from_max",
    "spectral_derivative",
    "sls_regressor",
    "solve_normal",
    "sls_theta",
    "golden_section",
    "sls_search",
    "gain_estimate",
    "steady_loop",
    "profile_phase_sls",
    "profile_phase_gain",
    "refine",
]

FloatArray = NDArray[np.float64]

#: Conjugate golden ratio, (sqrt(5) - 1) / 2: the fraction of the bracket kept at each step.
GOLDEN_RATIO_CONJ = 0.6180339887498949
#: Smallest reciprocal condition number of the Jacobi-scaled normal matrix that we agree to solve.
RCOND_MIN = 1e-12
#: Largest |m_ij - m_ji| / sqrt(m_ii m_jj) solve_normal accepts (rust/solve.rs SYMMETRY_RTOL).
SYMMETRY_RTOL = 1e-10
#: Default iteration cap of the golden-section search (0.618**200 is far below any double tolerance).
GOLDEN_MAX_ITER = 200


# --------------------------------------------------------------------------------------------------
# 1. Linear part: validation and controllable canonical realisation
# --------------------------------------------------------------------------------------------------


def realize(
    num: ArrayLike, den: ArrayLike, delay: float = 0.0
) -> tuple[FloatArray, FloatArray, float, float]:
    """Validate G(s) = e^{-delay s} num/den and return its controllable canonical form.

    Returns ``(a, c, d, delay)`` where ``a`` holds the monic denominator's coefficients ``a_1..a_n`` (the
    companion matrix's first row is ``-a``), ``c`` the output row and ``d`` the feed-through.
    """
    b, a, delay = check_transfer_function(num, den, delay)
    n = a.size - 1
    an = a / a[0]
    bn = np.concatenate([np.zeros(n + 1 - b.size), b]) / a[0]
    d = float(bn[0])
    c = bn[1:] - d * an[1:]
    return an[1:].copy(), c, d, delay


def _bw_rate(xdot: float, w: float, alpha: float, beta: float, gamma: float, mu: float) -> float:
    """Bouc-Wen (2a): alpha xdot - beta |xdot| |w|^(mu-1) w - gamma xdot |w|^mu."""
    try:
        wmu = abs(w) ** mu
    except OverflowError:  # a blow-up: let it run to inf/NaN as the core does, and be reported at the end
        wmu = float("inf")
    return float(alpha * xdot - beta * abs(xdot) * np.sign(w) * wmu - gamma * xdot * wmu)


def _simulate(
    num: ArrayLike,
    den: ArrayLike,
    delay: float,
    bw: tuple[float, float, float, float, float],
    source: Callable[[float], tuple[float, float]],
    dt: float,
    n_samples: int,
    substeps: int,
) -> tuple[FloatArray, FloatArray]:
    a, c, d, delay = realize(num, den, delay)
    alpha, beta, gamma, mu, w0 = bw
    _check_bouc_wen(alpha, beta, gamma, mu, w0)
    dt = _finite_scalar("dt", dt)
    if dt <= 0.0:
        raise InvalidParameterError(f"dt = {dt} must be > 0")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")
    if n_samples < 1:
        raise InvalidParameterError(f"n_samples = {n_samples} must be >= 1")
    n = a.size

    def delayed(t: float) -> tuple[float, float]:
        if t - delay < 0.0:
            return 0.0, 0.0
        return source(t - delay)

    def rhs(t: float, z: FloatArray) -> FloatArray:
        v, vdot = delayed(t)
        xs = z[:n]
        dz = np.empty(n + 1)
        if n:
            dz[0] = -np.dot(a, xs) + v
            dz[1:n] = xs[: n - 1]
        xdot = float(np.dot(c, dz[:n])) + d * vdot
        dz[n] = _bw_rate(xdot, float(z[n]), alpha, beta, gamma, mu)
        return dz

    h = dt / substeps
    z = np.zeros(n + 1)
    z[n] = w0
    x_out = np.empty(n_samples)
    w_out = np.empty(n_samples)
    # A blow-up runs on to inf/NaN silently here and is reported, with the parameters, just below.
    with np.errstate(all="ignore"):
        for k in range(n_samples):
            t = k * dt
            x_out[k] = float(np.dot(c, z[:n])) + d * delayed(t)[0]
            w_out[k] = z[n]
            if k == n_samples - 1:
                break
            for s in range(substeps):
                ts = t + s * h
                k1 = rhs(ts, z)
                k2 = rhs(ts + 0.5 * h, z + 0.5 * h * k1)
                k3 = rhs(ts + 0.5 * h, z + 0.5 * h * k2)
                k4 = rhs(ts + h, z + h * k3)
                z = z + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
    bad = [int(np.argmax(~np.isfinite(v))) if not np.all(np.isfinite(v)) else None for v in (x_out, w_out)]
    if bad != [None, None]:
        # The model's blow-up, not the caller's data (rust/simulate.rs check_blow_up).
        name, k = min(((nm, kk) for nm, kk in zip(("x", "w"), bad) if kk is not None), key=lambda p: p[1])
        raise NonFiniteError(
            f"the simulation blew up: {name} is not finite from sample {k} (t = {k * dt:.6e} s) on; the "
            f"model parameters (alpha = {alpha:e}, beta = {beta:e}, gamma = {gamma:e}, mu = {mu}, "
            f"w0 = {w0:e}) or the input level make the Bouc-Wen state overflow; use parameters of "
            "moderate size, a smaller amplitude or a finer step (substeps)"
        )
    return x_out, w_out


def simulate_sine(
    num: ArrayLike,
    den: ArrayLike,
    delay: float,
    alpha: float,
    beta: float,
    gamma: float,
    mu: float,
    w0: float,
    amplitude: float,
    omega: float,
    dt: float,
    n_samples: int,
    substeps: int,
    *,
    terms: Optional[Mapping[str, float]] = None,
) -> Any:
    """RK4 simulation of the Wiener system driven by ``u(t) = amplitude cos(omega t)``, t >= 0.

    Returns ``(x, w)`` at the ``n_samples`` grid times ``k dt`` (s); ``omega`` in rad/s.  With ``terms``
    (design.md 9.4, ``{code name: value}``) returns ``(x, w, y)`` (:mod:`.reference_terms`).
    """
    amplitude = _finite_scalar("amplitude", amplitude)
    omega = _finite_scalar("omega", omega)
    if omega <= 0.0:
        raise InvalidParameterError(f"omega = {omega} rad/s must be > 0")
    if terms is not None:
        from . import reference_terms

        bw = (alpha, beta, gamma, mu, w0)
        args = (amplitude, omega, dt, n_samples, substeps, terms)
        return reference_terms.simulate_sine(
            np.asarray(num), np.asarray(den), delay, bw, *args, plain=(realize, _simulate)
        )

    def source(tau: float) -> tuple[float, float]:
        return amplitude * np.cos(omega * tau), -amplitude * omega * np.sin(omega * tau)

    return _simulate(num, den, delay, (alpha, beta, gamma, mu, w0), source, dt, n_samples, substeps)


def simulate_sampled(
    num: ArrayLike,
    den: ArrayLike,
    delay: float,
    alpha: float,
    beta: float,
    gamma: float,
    mu: float,
    w0: float,
    u: ArrayLike,
    dt: float,
    substeps: int,
    *,
    terms: Optional[Mapping[str, float]] = None,
) -> Any:
    """RK4 simulation driven by samples ``u`` on the grid ``k dt``, interpolated by Catmull-Rom cubics.

    With ``terms`` (design.md 9.4) returns ``(x, w, y)`` (:mod:`.reference_terms`).
    """
    uu = _finite_array("u", u)
    if uu.size < 2:
        raise InsufficientDataError("a sampled input needs at least 2 samples")
    dt_f = _finite_scalar("dt", dt)
    if dt_f <= 0.0:
        raise InvalidParameterError(f"dt = {dt_f} must be > 0")
    m = np.empty_like(uu)
    m[1:-1] = (uu[2:] - uu[:-2]) / (2.0 * dt_f)
    m[0] = (uu[1] - uu[0]) / dt_f
    m[-1] = (uu[-1] - uu[-2]) / dt_f
    if terms is not None:
        from . import reference_terms

        bw = (alpha, beta, gamma, mu, w0)
        args = (uu, m, dt_f, substeps, terms)
        return reference_terms.simulate_sampled(
            np.asarray(num), np.asarray(den), delay, bw, *args, plain=(realize, _simulate)
        )
    last = uu.size - 1

    def source(tau: float) -> tuple[float, float]:
        k = int(np.floor(tau / dt_f))
        if k >= last:
            return float(uu[last]), 0.0
        s = tau / dt_f - k
        h00 = 2 * s**3 - 3 * s**2 + 1
        h10 = s**3 - 2 * s**2 + s
        h01 = -2 * s**3 + 3 * s**2
        h11 = s**3 - s**2
        val = h00 * uu[k] + h10 * dt_f * m[k] + h01 * uu[k + 1] + h11 * dt_f * m[k + 1]
        d00 = 6 * s**2 - 6 * s
        d10 = 3 * s**2 - 4 * s + 1
        d01 = -6 * s**2 + 6 * s
        d11 = 3 * s**2 - 2 * s
        der = (d00 * uu[k] + d01 * uu[k + 1]) / dt_f + d10 * m[k] + d11 * m[k + 1]
        return float(val), float(der)

    return _simulate(num, den, delay, (alpha, beta, gamma, mu, w0), source, dt_f, uu.size, substeps)


# --------------------------------------------------------------------------------------------------
# 2-4. Averaging (4a-b), phase (9), spectral derivative
# --------------------------------------------------------------------------------------------------


def periodic_average(y: ArrayLike, samples_per_period: int, settle_periods: int, periods: int) -> FloatArray:
    """Periodic average (4a-b) over ``periods`` whole periods after ``settle_periods`` dropped ones."""
    yy = _finite_array("y", y)
    p, s, n = int(samples_per_period), int(settle_periods), int(periods)
    if p < MIN_AVERAGE_SAMPLES:
        raise InsufficientDataError(
            f"samples_per_period = {p}: at least {MIN_AVERAGE_SAMPLES} samples per period are needed"
        )
    if n < 1:
        raise InsufficientDataError(f"periods = {n}: at least one period must be averaged")
    if s < 0:
        raise InvalidParameterError(f"settle_periods = {s} must be >= 0")
    need = (s + n) * p
    if yy.size < need:
        raise InsufficientDataError(
            f"the recording has {yy.size} samples = {yy.size / p:.2f} periods, but {s} settling + {n} "
            f"averaged periods need {need}; record longer or ask for fewer periods"
        )
    out: FloatArray = yy[s * p : need].reshape(n, p).mean(axis=0)
    return out


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


# --------------------------------------------------------------------------------------------------
# 5. Separable least squares (18)-(24)
# --------------------------------------------------------------------------------------------------


def _sls_inputs(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    yb = _finite_array("ybar", ybar)
    yd = _finite_array("ydot", ydot)
    if yb.size != yd.size:
        raise InvalidParameterError(f"ybar ({yb.size}) and ydot ({yd.size}) must have the same length")
    if yb.size < MIN_AVERAGE_SAMPLES:
        raise InsufficientDataError(f"ybar needs at least {MIN_AVERAGE_SAMPLES} samples per period")
    amplitude = _finite_scalar("amplitude", amplitude)
    omega = _finite_scalar("omega", omega)
    phi = _finite_scalar("phi", phi)
    if amplitude == 0.0:
        raise ZeroAmplitudeError("the input amplitude U is 0: a zero input identifies nothing")
    if omega <= 0.0:
        raise InvalidParameterError(f"omega = {omega} rad/s must be > 0")
    p = yb.size
    dt = 2.0 * np.pi / omega / p
    t = np.arange(p) * dt
    s = amplitude * omega * np.sin(omega * t - phi)
    return yb, yd, s, dt


def sls_regressor(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float, nu: float
) -> FloatArray:
    """Regressor psi_N(nu, t) of (23), shape (P, 3)."""
    yb, yd, s, _ = _sls_inputs(ybar, ydot, amplitude, omega, phi)
    ynu = np.abs(yb) ** float(nu)
    return np.column_stack([-s, s * np.sign(yd) * np.sign(yb) * ynu, s * ynu])


def solve_normal(m: ArrayLike, r: ArrayLike) -> tuple[FloatArray, float]:
    """Solve the 3x3 normal equations ``m theta = r`` with Jacobi scaling; return ``(theta, rcond)``."""
    mm = np.asarray(m, dtype=np.float64)
    rr = np.asarray(r, dtype=np.float64)
    if mm.shape != (3, 3) or rr.shape != (3,):
        raise InvalidParameterError(f"expected a (3, 3) matrix and a (3,) vector, got {mm.shape}, {rr.shape}")
    if not (np.all(np.isfinite(mm)) and np.all(np.isfinite(rr))):
        raise NonFiniteError("the normal equations hold a non-finite entry")
    diag = np.diag(mm)
    if np.any(diag <= 0.0):
        raise SingularNormalMatrixError(
            "the normal matrix has a zero regressor column (rcond = 0): the data do not excite "
            "every term of the model"
        )
    dsq = np.sqrt(diag)
    # A normal matrix is symmetric (rust/solve.rs SYMMETRY_RTOL): refuse one that is not rather than
    # read one triangle of it.
    gap = np.abs(mm - mm.T) / np.outer(dsq, dsq)
    if not np.all(gap <= SYMMETRY_RTOL):
        i, j = np.unravel_index(int(np.argmax(np.where(np.isnan(gap), np.inf, gap))), gap.shape)
        raise InvalidParameterError(
            f"the normal matrix is not symmetric: m[{i}][{j}] = {mm[i, j]:e} but m[{j}][{i}] = {mm[j, i]:e} "
            f"(relative gap {gap[i, j]:.1e} > {SYMMETRY_RTOL:g}); pass Psi^T Psi"
        )
    sm = mm / np.outer(dsq, dsq)
    eig = np.linalg.eigvalsh(sm)
    rcond = float(eig[0] / eig[-1]) if eig[-1] > 0 else 0.0
    if rcond < RCOND_MIN:
        raise SingularNormalMatrixError(
            f"the normal matrix is singular or badly conditioned (rcond = {rcond:.3g} < {RCOND_MIN:g}): "
            "the regressor columns are (nearly) collinear"
        )
    chol = np.linalg.cholesky(sm)
    z = np.linalg.solve(chol, rr / dsq)
    theta = np.linalg.solve(chol.T, z) / dsq
    return theta, rcond


def sls_theta(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float, nu: float
) -> tuple[FloatArray, float]:
    """Theta_N(nu) of (22) and the cost I_N(nu) of (21)."""
    yb, yd, s, dt = _sls_inputs(ybar, ydot, amplitude, omega, phi)
    psi = sls_regressor(yb, yd, amplitude, omega, phi, nu)
    m = dt * psi.T @ psi
    r = dt * psi.T @ yd
    theta, _ = solve_normal(m, r)
    resid = yd - psi @ theta
    return theta, float(dt * np.sum(resid**2))


def golden_section(
    func: Callable[[float], float], lo: float, hi: float, tol: float, max_iter: int = GOLDEN_MAX_ITER
) -> tuple[float, float, int]:
    """Golden-section minimisation of ``func`` on ``[lo, hi]`` to a bracket width ``tol``.

    Returns ``(x, func(x), iterations)``.  Raises :class:`SearchAtBoundError` when the search never left
    one end of the bracket (the minimum is at or beyond the bound).
    """
    lo = _finite_scalar("lo", lo)
    hi = _finite_scalar("hi", hi)
    tol = _finite_scalar("tol", tol)
    if not lo < hi:
        raise InvalidParameterError(f"the bracket [{lo}, {hi}] is empty: lo must be < hi")
    if not 0.0 < tol < hi - lo:
        raise InvalidParameterError(f"tol = {tol} must be > 0 and smaller than the bracket width {hi - lo}")
    if max_iter < 1:
        raise InvalidParameterError(f"max_iter = {max_iter} must be >= 1")

    def f(x: float) -> float:
        v = float(func(x))
        if not np.isfinite(v):
            raise NonFiniteError(f"the objective returned {v} at x = {x}")
        return v

    a, b = lo, hi
    c = b - GOLDEN_RATIO_CONJ * (b - a)
    d = a + GOLDEN_RATIO_CONJ * (b - a)
    fc, fd = f(c), f(d)
    it = 0
    while b - a > tol and it < max_iter:
        if fc < fd:
            b, d, fd = d, c, fc
            c = b - GOLDEN_RATIO_CONJ * (b - a)
            fc = f(c)
        else:
            a, c, fc = c, d, fd
            d = a + GOLDEN_RATIO_CONJ * (b - a)
            fd = f(d)
        it += 1
    if a == lo or b == hi:
        raise SearchAtBoundError(
            f"the minimum lies at the {'lower' if a == lo else 'upper'} end "
            f"{lo if a == lo else hi} of the bracket [{lo}, {hi}] (tol {tol:g}); widen the bracket, "
            "or check that the data excite the hysteresis",
            bound=lo if a == lo else hi,
            lower=a == lo,
        )
    x = 0.5 * (a + b)
    return x, f(x), it


def sls_search(
    ybar: ArrayLike,
    ydot: ArrayLike,
    amplitude: float,
    omega: float,
    phi: float,
    lo: float,
    hi: float,
    tol: float,
    max_iter: int = GOLDEN_MAX_ITER,
) -> tuple[float, FloatArray, float, int]:
    """Estimator (24a-b): golden-section search of I_N(nu) on [lo, hi], then Theta_N at the minimiser.

    Returns ``(mu, theta, cost, iterations)``.
    """
    if lo < 1.0:
        raise InvalidParameterError(f"the mu bracket starts at {lo} < 1; the model needs mu > 1")
    yb, yd, _, _ = _sls_inputs(ybar, ydot, amplitude, omega, phi)
    mu, _, it = golden_section(
        lambda nu: sls_theta(yb, yd, amplitude, omega, phi, nu)[1], lo, hi, tol, max_iter
    )
    theta, cost = sls_theta(yb, yd, amplitude, omega, phi, mu)
    return mu, theta, cost, it


# --------------------------------------------------------------------------------------------------
# 6. Gain at the further frequencies (27b)
# --------------------------------------------------------------------------------------------------


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
    yb, yd, s, _ = _sls_inputs(ybar, ydot, amplitude, omega, phi)
    for name, v in (("beta", beta), ("gamma", gamma), ("mu", mu)):
        _finite_scalar(name, v)
    ymu = np.abs(yb) ** mu
    chi = s * (-1.0 + beta * np.sign(yd) * np.sign(yb) * ymu + gamma * ymu)
    den = float(np.sum(chi**2))
    if den == 0.0:
        raise SingularNormalMatrixError("the gain regressor chi of (27b) is identically zero")
    return float(np.sum(yd * chi) / den)


# --------------------------------------------------------------------------------------------------
# Beyond the paper: steady-state loop, profile-phase SLS, output-error refinement
# --------------------------------------------------------------------------------------------------

#: Newton iterations allowed for the shooting on w(0) of the steady loop.
SHOOT_MAX_ITER = 60
#: Relative tolerance of the periodicity condition |w(pi) + w(0)| <= tol * w_bound.
SHOOT_RTOL = 1e-13
#: Relative tolerance and iteration cap of the coarse shooting that starts the fine one (rust/steady.rs).
COARSE_RTOL = 1e-9
COARSE_MAX_ITER = 20


def _loop_rhs(a: float, beta: float, gamma: float, mu: float, theta: float, y: FloatArray) -> FloatArray:
    """Rate of [w, Phi, S_beta, S_gamma, S_mu, S_A] along theta for x = A cos(theta) (alpha = 1)."""
    sin_t = np.sin(theta)
    xt = -a * sin_t
    w = y[0]
    aw = abs(w)
    sw = np.sign(w)
    sx = np.sign(xt)
    if aw > 0.0:
        lnw = np.log(aw)
        wmu = np.exp(mu * lnw)
        wmu1 = wmu / aw
    else:
        lnw = wmu = wmu1 = 0.0
    bracket = 1.0 - beta * sx * sw * wmu - gamma * wmu
    fw = xt * (-beta * sx * mu * wmu1 - gamma * mu * wmu1 * sw)
    return np.array(
        [
            xt * bracket,
            fw * y[1],
            fw * y[2] - xt * sx * sw * wmu,
            fw * y[3] - xt * wmu,
            fw * y[4] + xt * (-beta * sx * sw - gamma) * wmu * lnw,
            fw * y[5] - sin_t * bracket,
        ]
    )


def steady_loop(
    amplitude: float, beta: float, gamma: float, mu: float, phi: float, samples_per_period: int, substeps: int
) -> tuple[FloatArray, FloatArray, float, int]:
    """Steady loop of (2b) under ``x = amplitude cos(omega t - phi)`` on P samples per period.

    Half a cycle of ``dw/dtheta`` by RK4 and Newton shooting on ``w(0)`` so that ``w(pi) = -w(0)``,
    with forward sensitivities.  Returns ``(w, jac, w_top, iterations)``, ``jac`` of shape (P, 5):
    ``d w / d(beta, gamma, mu, amplitude, phi)``.
    """
    for name, v in (("amplitude", amplitude), ("beta", beta), ("gamma", gamma), ("mu", mu), ("phi", phi)):
        _finite_scalar(name, v)
    if mu <= 1.0:
        raise InvalidParameterError(f"mu = {mu} must be > 1 in the identification model")
    if beta + gamma <= 0.0:
        raise InvalidParameterError(f"beta + gamma = {beta + gamma} must be > 0: the loop is unbounded")
    if amplitude == 0.0:
        raise ZeroAmplitudeError("the amplitude of x is 0: the loop is a point")
    p = int(samples_per_period)
    if p < MIN_AVERAGE_SAMPLES:
        raise InsufficientDataError(f"samples_per_period = {p}: at least {MIN_AVERAGE_SAMPLES} are needed")
    if substeps < 1:
        raise InvalidParameterError(f"substeps = {substeps} must be >= 1")
    phi = float(np.mod(phi, 2.0 * np.pi))
    # The sample phases theta_j = 2 pi j/P - phi fold, modulo pi, onto a lattice offset + k L.
    c, n_lat = (1, p // 2) if p % 2 == 0 else (2, p)
    spacing = np.pi / n_lat
    q = phi / spacing
    qf = np.floor(q)
    r = q - qf
    offset, shift = ((1.0 - r) * spacing, int(qf) + 1) if r > 0.0 else (0.0, int(qf))
    idx = c * np.arange(p) - shift
    half = np.floor_divide(idx, n_lat)
    lat = np.mod(idx, n_lat)
    sign = np.where(half % 2 == 0, 1.0, -1.0)

    def rk4(theta: float, y: FloatArray, h: float) -> FloatArray:
        k1 = _loop_rhs(amplitude, beta, gamma, mu, theta, y)
        k2 = _loop_rhs(amplitude, beta, gamma, mu, theta + 0.5 * h, y + 0.5 * h * k1)
        k3 = _loop_rhs(amplitude, beta, gamma, mu, theta + 0.5 * h, y + 0.5 * h * k2)
        k4 = _loop_rhs(amplitude, beta, gamma, mu, theta + h, y + h * k3)
        return y + h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)

    rec = np.zeros((n_lat, 6))

    def half_cycle(w_top: float, sub: int = substeps) -> FloatArray:
        y = np.array([w_top, 1.0, 0.0, 0.0, 0.0, 0.0])
        if offset > 0.0:
            h = offset / sub
            for s in range(sub):
                y = rk4(s * h, y, h)
        for k in range(n_lat):
            rec[k] = y
            start = offset + k * spacing
            length = np.pi - start if k + 1 == n_lat else spacing
            h = length / sub
            for s in range(sub):
                y = rk4(start + s * h, y, h)
        return y

    def coarse_top() -> Optional[float]:
        # Coarse to fine (as rust/steady.rs): the shooting with one RK4 step per lattice interval
        # proposes the fine shooting's start.
        c_lo, c_hi, top = -bound, bound, 0.0
        for _ in range(COARSE_MAX_ITER):
            end = half_cycle(top, 1)
            resid = float(end[0] + top)
            if not np.isfinite(resid):
                return None
            if abs(resid) <= COARSE_RTOL * bound:
                return top
            if resid > 0.0:
                c_hi = top
            else:
                c_lo = top
            newton = top - resid / (end[1] + 1.0)
            top = newton if c_lo < newton < c_hi and np.isfinite(newton) else 0.5 * (c_lo + c_hi)
        return None

    bound = (1.0 / (beta + gamma)) ** (1.0 / mu)
    lo, hi = -bound, bound
    w_top = (coarse_top() or 0.0) if substeps > 1 else 0.0
    iterations = 0
    while True:
        end = half_cycle(w_top)
        resid = end[0] + w_top
        if abs(resid) <= SHOOT_RTOL * bound:
            break
        iterations += 1
        if iterations > SHOOT_MAX_ITER:
            raise NotConvergedError(
                f"the steady-loop shooting did not converge in {SHOOT_MAX_ITER} iterations "
                f"(residual {resid:.3e})"
            )
        if resid > 0.0:
            hi = w_top
        else:
            lo = w_top
        newton = w_top - resid / (end[1] + 1.0)
        w_top = newton if lo < newton < hi and np.isfinite(newton) else 0.5 * (lo + hi)
    dtop = -end[2:6] / (1.0 + end[1])
    y = rec[lat]
    theta = offset + lat * spacing
    slope = np.array([_loop_rhs(amplitude, beta, gamma, mu, th, yy)[0] for th, yy in zip(theta, y)])
    w = sign * y[:, 0]
    jac = np.empty((p, 5))
    jac[:, :4] = sign[:, None] * (y[:, 2:6] + y[:, 1:2] * dtop[None, :])
    jac[:, 4] = -sign * slope
    return w, jac, float(w_top), iterations


def _phase_sign_inputs(
    ybar: ArrayLike, ydot: ArrayLike, amplitude: float, omega: float, phi: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, float]:
    """s_j and sgn(xdot_j) sgn(ybar_j) with sgn(xdot) = -sgn(s) from the candidate phase (Prop. 2)."""
    yb, yd, s, dt = _sls_inputs(ybar, ydot, amplitude, omega, phi)
    return yb, yd, s, -np.sign(s) * np.sign(yb), dt


def _sls_cost_signed(
    yb: FloatArray, yd: FloatArray, s: FloatArray, sgn: FloatArray, dt: float, nu: float
) -> tuple[FloatArray, float]:
    ynu = np.abs(yb) ** nu
    psi = np.column_stack([-s, s * sgn * ynu, s * ynu])
    theta, _ = solve_normal(dt * psi.T @ psi, dt * psi.T @ yd)
    return theta, float(dt * np.sum((yd - psi @ theta) ** 2))


def _profile_at(
    ybar: FloatArray,
    ydot: FloatArray,
    amplitude: float,
    omega: float,
    phi: float,
    lo: float,
    hi: float,
    tol: float,
) -> Optional[tuple[float, FloatArray, float, Optional[bool]]]:
    """``(mu, theta, cost, at_bound)`` at phi; a search ending on the bracket gives the bound's cost."""
    yb, yd, s, sgn, dt = _phase_sign_inputs(ybar, ydot, amplitude, omega, phi)
    if lo < 1.0:
        raise InvalidParameterError(f"the mu bracket starts at {lo} < 1; the model needs mu > 1")
    try:
        mu, _, _ = golden_section(lambda nu: _sls_cost_signed(yb, yd, s, sgn, dt, nu)[1], lo, hi, tol)
        theta, cost = _sls_cost_signed(yb, yd, s, sgn, dt, mu)
        return mu, theta, cost, None
    except SingularNormalMatrixError:
        return None
    except SearchAtBoundError as exc:
        assert exc.bound is not None
        try:
            theta, cost = _sls_cost_signed(yb, yd, s, sgn, dt, exc.bound)
        except SingularNormalMatrixError:
            return None
        return exc.bound, theta, cost, exc.lower


#: Final bracket width (rad) of the phase refinement.
PHASE_TOL = 1e-9
#: Default number of candidate phases of the coarse grid.
DEFAULT_PHASE_GRID = 48


def profile_phase_sls(
    ybar: ArrayLike,
    ydot: ArrayLike,
    amplitude: float,
    omega: float,
    lo: float,
    hi: float,
    tol: float,
    grid: int,
) -> tuple[float, float, float, float, float, float, int]:
    """Profile-phase SLS: the cost (21) minimised over (phi, nu, theta), sgn(xdot) from the phase.

    Returns ``(phi, mu, gain, beta, gamma, cost, skipped)``, canonical (gain > 0).
    """
    yb = _finite_array("ybar", ybar)
    yd = _finite_array("ydot", ydot)
    if grid < 3:
        raise InvalidParameterError(f"the phase grid needs at least 3 points, got {grid}")
    step = np.pi / grid
    best: Optional[tuple[int, float]] = None
    skipped = 0
    for k in range(grid):
        out = _profile_at(yb, yd, amplitude, omega, k * step, lo, hi, tol)
        if out is None:
            skipped += 1
        elif best is None or out[2] < best[1]:
            best = (k, out[2])
    if best is None:
        raise SingularNormalMatrixError(
            f"no candidate phase on a {grid}-point grid gave a solvable separable fit"
        )
    centre = best[0] * step

    def profiled(phi: float) -> float:
        out = _profile_at(yb, yd, amplitude, omega, phi, lo, hi, tol)
        return np.finfo(float).max if out is None else out[2]

    try:
        phi, _, _ = golden_section(profiled, centre - step, centre + step, PHASE_TOL)
    except SearchAtBoundError:
        phi = centre
    out = _profile_at(yb, yd, amplitude, omega, phi, lo, hi, tol)
    if out is None:
        out = _profile_at(yb, yd, amplitude, omega, centre, lo, hi, tol)
        if out is None:
            raise SingularNormalMatrixError("the refined phase gave no solvable fit")
    mu, theta, cost, at_bound = out
    if at_bound is not None:
        raise SearchAtBoundError(
            f"the minimum lies at the {'lower' if at_bound else 'upper'} end {mu} of the mu bracket "
            f"[{lo}, {hi}] (tol {tol:g}); widen the bracket, or check that the data excite the hysteresis",
            bound=mu,
            lower=at_bound,
        )
    gain, beta, gamma = theta[0], theta[1] / theta[0], theta[2] / theta[0]
    if gain < 0.0:
        gain, phi, beta = -gain, phi + np.pi, -beta
    return (
        float(np.mod(phi, 2 * np.pi)),
        float(mu),
        float(gain),
        float(beta),
        float(gamma),
        float(cost),
        skipped,
    )


def profile_phase_gain(
    ybar: ArrayLike,
    ydot: ArrayLike,
    amplitude: float,
    omega: float,
    beta: float,
    gamma: float,
    mu: float,
    grid: int,
) -> tuple[float, float, float]:
    """Gain and phase at a further frequency with the hysteresis known; returns ``(gain, phi, cost)``."""
    yb = _finite_array("ybar", ybar)
    yd = _finite_array("ydot", ydot)
    if grid < 3:
        raise InvalidParameterError(f"the phase grid needs at least 3 points, got {grid}")

    def fit(phi: float) -> Optional[tuple[float, float]]:
        _, _, s, sgn, dt = _phase_sign_inputs(yb, yd, amplitude, omega, phi)
        ymu = np.abs(yb) ** mu
        chi = s * (-1.0 + beta * sgn * ymu + gamma * ymu)
        den = float(np.sum(chi * chi))
        if den <= 0.0:
            return None
        g = float(np.sum(yd * chi) / den)
        return g, float(np.sum((yd - g * chi) ** 2) * dt)

    step = 2 * np.pi / grid
    best: Optional[tuple[int, float]] = None
    for k in range(grid):
        out = fit(k * step)
        if out is not None and out[0] > 0.0 and (best is None or out[1] < best[1]):
            best = (k, out[1])
    if best is None:
        raise SingularNormalMatrixError(
            "no candidate phase gave a positive gain for the identified hysteresis"
        )
    centre = best[0] * step

    def profiled(phi: float) -> float:
        out = fit(phi)
        return np.finfo(float).max if out is None else out[1]

    try:
        phi, _, _ = golden_section(profiled, centre - step, centre + step, PHASE_TOL)
    except SearchAtBoundError:
        phi = centre
    out = fit(phi)
    if out is None:
        raise SingularNormalMatrixError("the gain regressor chi is identically zero")
    g, c = out
    if g < 0.0:
        g, phi = -g, phi + np.pi
    return g, float(np.mod(phi, 2 * np.pi)), c


#: Levenberg-Marquardt damping schedule (relative to the diagonal of J^T W J).
LM_LAMBDA_START, LM_LAMBDA_DOWN, LM_LAMBDA_UP, LM_LAMBDA_MAX = 1e-3, 0.2, 10.0, 1e12
#: Smallest distance kept between mu and its lower limit 1.
LM_MU_MARGIN = 1e-9


def admissible_bouc_wen(par: FloatArray, mu_lo: float, mu_hi: float) -> bool:
    """The Bouc-Wen conditions of (2a) on ``par[:3] = (beta, gamma, mu)`` and the mu bracket."""
    return bool(
        par[2] > max(mu_lo, 1.0) + LM_MU_MARGIN
        and par[2] <= mu_hi
        and par[0] + par[1] > 0
        and par[0] >= par[1]
    )


def project_bouc_wen(trial: FloatArray, mu_lo: float, mu_hi: float) -> None:
    """In place: ``beta < gamma`` onto ``beta = gamma`` (same sum), mu clipped into its bracket."""
    if trial[0] < trial[1]:
        trial[0] = trial[1] = 0.5 * (trial[0] + trial[1])
    mu_min = max(mu_lo, 1.0) + 2.0 * LM_MU_MARGIN
    if np.isfinite(trial[2]):
        trial[2] = min(max(trial[2], mu_min), max(mu_hi, mu_min))


def levenberg_marquardt(
    params: FloatArray,
    cost_of: Callable[[FloatArray], tuple[float, Any]],
    linearize: Callable[[Any], tuple[FloatArray, FloatArray]],
    project: Callable[[FloatArray], None],
    admissible: Callable[[FloatArray], bool],
    *,
    max_iter: int,
    ftol: float,
    xtol: float,
) -> tuple[FloatArray, float, int, bool, FloatArray, Any]:
    """The one Levenberg-Marquardt of the reference (design.md 7.4), for the plain and the augmented model.

    ``cost_of(par) -> (cost, state)`` (raises a library error where the model has no loop),
    ``linearize(state) -> (J'WJ, J'Wr)`` at an accepted point, ``project(trial)`` in place onto the closed
    constraints, ``admissible(trial)``. Marquardt damping ``lambda diag(J'WJ)`` from 1e-3, x0.2 on success,
    x10 on failure, stop above 1e12; stop on a relative decrease below ``ftol`` or a step below
    ``xtol (|p| + xtol)``. Returns ``(params, cost, iterations, converged, J'WJ, state)``.
    """
    cost, state = cost_of(params)
    fisher, grad = linearize(state)
    lam = LM_LAMBDA_START
    it = 0
    converged = False
    while it < max_iter:
        it += 1
        damped = fisher + lam * np.diag(np.maximum(np.diag(fisher), np.finfo(float).tiny))
        try:
            delta = np.linalg.solve(damped, grad)
        except np.linalg.LinAlgError:
            lam *= LM_LAMBDA_UP
            if lam > LM_LAMBDA_MAX:
                converged = True
                break
            continue
        trial = params + delta
        small = bool(np.all(np.abs(delta) <= xtol * (np.abs(params) + xtol)))
        project(trial)
        out = None
        if admissible(trial):
            try:
                out = cost_of(trial)
            except BoucWenIdErrorBase:
                out = None
        if out is not None and out[0] <= cost:
            decrease = (cost - out[0]) / max(cost, np.finfo(float).tiny)
            params = trial
            cost, state = out
            fisher, grad = linearize(state)
            lam = max(lam * LM_LAMBDA_DOWN, 1e-15)
            if decrease < ftol or small:
                converged = True
                break
        else:
            if small:
                converged = True
                break
            lam *= LM_LAMBDA_UP
            if lam > LM_LAMBDA_MAX:
                converged = True
                break
    return params, cost, it, converged, fisher, state


def refine(
    ybars: Sequence[ArrayLike],
    amplitudes: ArrayLike,
    weights: ArrayLike,
    beta: float,
    gamma: float,
    mu: float,
    gains: ArrayLike,
    phases: ArrayLike,
    max_iter: int = 200,
    substeps: int = 4,
    ftol: float = 1e-12,
    xtol: float = 1e-10,
    mu_lo: float = 1.0,
    mu_hi: float = float("inf"),
) -> tuple[FloatArray, float, int, bool, FloatArray, list[FloatArray]]:
    """Joint output-error Levenberg-Marquardt over every experiment (Schur complement on the shared part).

    Parameters are ``[beta, gamma, mu, g_0, phi_0, g_1, phi_1, ...]``.  Returns
    ``(params, cost, iterations, converged, fisher, loops)``.
    """
    ys = [_finite_array(f"ybar[{i}]", y) for i, y in enumerate(ybars)]
    amps = np.asarray(amplitudes, dtype=np.float64)
    wts = np.asarray(weights, dtype=np.float64)
    m = len(ys)
    if m == 0:
        raise InsufficientDataError("the refinement needs at least one experiment")
    g0 = np.asarray(gains, dtype=np.float64)
    p0 = np.asarray(phases, dtype=np.float64)
    if not (amps.size == wts.size == g0.size == p0.size == m):
        raise InvalidParameterError(
            f"{m} experiments but {amps.size} amplitudes, {wts.size} weights, "
            f"{g0.size} gains and {p0.size} phases"
        )
    if np.any(wts <= 0) or not np.all(np.isfinite(wts)):
        raise InvalidParameterError("weights must be finite and > 0 (N / noise variance)")
    if max_iter < 1 or substeps < 1:
        raise InvalidParameterError("max_iter and substeps must be >= 1")
    params = np.concatenate([[beta, gamma, mu], np.column_stack([g0, p0]).ravel()])

    def admissible(par: FloatArray) -> bool:
        """The Bouc-Wen conditions of (2a) and the mu bracket."""
        return admissible_bouc_wen(par, mu_lo, mu_hi)

    if not admissible(params):
        raise InvalidParameterError(
            f"the starting point (beta = {beta}, gamma = {gamma}, mu = {mu}) must satisfy beta >= |gamma|, "
            f"beta + gamma > 0 and {max(mu_lo, 1.0)} < mu <= {mu_hi}"
        )

    def evaluate(par: FloatArray) -> tuple[float, list[FloatArray], list[FloatArray]]:
        cost, resid, jacs = 0.0, [], []
        for i in range(m):
            w, jac, _, _ = steady_loop(
                amps[i] * par[3 + 2 * i], par[0], par[1], par[2], par[4 + 2 * i], ys[i].size, substeps
            )
            r = ys[i] - w
            cost += wts[i] * float(np.sum(r * r))
            resid.append(r)
            jacs.append(jac)
        return cost, resid, jacs

    def blocks(resid: list[FloatArray], jacs: list[FloatArray]) -> tuple[FloatArray, FloatArray]:
        n = 3 + 2 * m
        fisher = np.zeros((n, n))
        grad = np.zeros(n)
        for i in range(m):
            full = np.zeros((ys[i].size, n))
            full[:, :3] = jacs[i][:, :3]
            full[:, 3 + 2 * i] = jacs[i][:, 3] * amps[i]
            full[:, 4 + 2 * i] = jacs[i][:, 4]
            fisher += wts[i] * full.T @ full
            grad += wts[i] * full.T @ resid[i]
        return fisher, grad

    def project(trial: FloatArray) -> None:
        # Project onto the closed constraints the step crossed: beta < gamma -> the nearest point of
        # beta = gamma (same beta + gamma), mu clipped into the bracket (beta + gamma <= 0 stays rejected).
        project_bouc_wen(trial, mu_lo, mu_hi)

    def linearize(state: tuple[list[FloatArray], list[FloatArray]]) -> tuple[FloatArray, FloatArray]:
        return blocks(*state)

    def trial_cost(par: FloatArray) -> tuple[float, tuple[list[FloatArray], list[FloatArray]]]:
        cost, resid, jacs = evaluate(par)
        return cost, (resid, jacs)

    params, cost, it, converged, fisher, (resid, _) = levenberg_marquardt(
        params, trial_cost, linearize, project, admissible, max_iter=max_iter, ftol=ftol, xtol=xtol
    )
    loops = [ys[i] - resid[i] for i in range(m)]
    return params, cost, it, converged, fisher, loops
