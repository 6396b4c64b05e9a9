"""Bouc-Wen in feedback on sine experiments (issue #20 item 2): the periodic steady state under a sine and
the fit of averaged periods.

The periodic state is found in Rust by Newton shooting on one period with the monodromy matrix
(``rust/feedback/periodic.rs``); its Jacobian w.r.t. the seven physical parameters is exact for the discrete
map (the implicit-function correction through the periodic initial state included), so the fit is the same
bounded Levenberg-Marquardt as on records (:mod:`._feedback`).

An experiment is ``(amplitude, frequency, ybar)``: the force ``u = amplitude cos(2 pi frequency t)`` and one
averaged steady period ``ybar`` of the displacement on the grid ``t_k = k / (frequency N)``, ``k < N``, phase
aligned with that cosine (what the library's sine averaging returns once the input's phase is removed).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace
from typing import Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._backend import feedback_part
from ..errors import InsufficientDataError, InvalidParameterError, NonFiniteError, NotConvergedError
from ..validation import count, finite_array, positive_number
from ._feedback import FEEDBACK_PARAMETERS, FeedbackFit, FeedbackModel
from ._feedback_adequacy import check_noise, sine_adequacy
from ._feedback_start import random_starts
from ._lm import LMResult, levenberg_marquardt

__all__ = ["SineExperiment", "fit_feedback_sines", "steady_period"]

FloatArray = NDArray[np.float64]
SineExperiment = tuple[float, float, ArrayLike]

#: Largest RK4 step (s) of the periodic state: the benchmark's 15 kHz.
MAX_STEP = 1.0 / 15000.0


def _substeps(frequency: float, samples: int, max_step: float = MAX_STEP) -> int:
    return max(1, math.ceil(1.0 / (frequency * samples) / max_step))


def steady_period(
    model: FeedbackModel,
    amplitude: float,
    frequency: float,
    samples: int,
    *,
    backend: str = "rust",
    max_step: float = MAX_STEP,
) -> FloatArray:
    """One period (``samples`` points from ``t = 0``) of the periodic displacement of ``model`` under
    ``amplitude cos(2 pi frequency t)``, RK4 steps at most ``max_step`` (default 1/15000 s)."""
    frequency = positive_number("frequency", frequency)
    samples = count("samples", samples, 4)
    max_step = positive_number("max_step", max_step)
    y, _, _, _ = feedback_part(backend).feedback_periodic(
        model.theta,
        float(amplitude),
        2 * math.pi * frequency,
        samples,
        _substeps(frequency, samples, max_step),
    )
    return y


def _checked(experiments: Sequence[SineExperiment]) -> list[tuple[float, float, FloatArray]]:
    if not isinstance(experiments, Sequence) or len(experiments) == 0:
        raise InvalidParameterError(
            "experiments must be a non-empty sequence of (amplitude, frequency, ybar)"
        )
    out = []
    for i, exp in enumerate(experiments):
        if not (isinstance(exp, tuple) and len(exp) == 3):
            raise InvalidParameterError(
                f"experiment {i} must be (amplitude, frequency, ybar), got {exp!r:.60}"
            )
        amp, freq, ybar = exp
        yb = finite_array(f"ybar of experiment {i}", ybar)
        if yb.size < 8:
            raise InsufficientDataError(f"experiment {i} has {yb.size} samples per period; give at least 8")
        out.append((float(amp), positive_number(f"frequency of experiment {i}", freq), yb))
    return out


def linear_start_sines(exps: list[tuple[float, float, FloatArray]]) -> FloatArray:
    """``[m, c, K/2, K/2, 0, 0, 1]`` from the first harmonics: ``A / Y1 = K - m w^2 + j c w`` fitted by least
    squares over the experiments (at least two frequencies)."""
    rows, rhs, damp = [], [], []
    for amp, freq, yb in exps:
        n = yb.size
        y1 = 2.0 / n * np.sum(yb * np.exp(-2j * np.pi * np.arange(n) / n))
        inv_h = amp / y1
        w = 2 * np.pi * freq
        rows.append([1.0, -(w**2)])
        rhs.append(inv_h.real)
        damp.append(inv_h.imag / w)
    if len({f for _, f, _ in exps}) < 2:
        raise InvalidParameterError("a start needs experiments at two frequencies at least; give theta0")
    (stiffness, m), *_ = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)
    if not (stiffness > 0 and m > 0):
        raise InvalidParameterError(
            f"the first harmonics do not look like a mass-spring-damper (K = {stiffness:.3g}, m = {m:.3g}); "
            "give theta0"
        )
    return np.array([m, max(float(np.mean(damp)), 0.0), stiffness / 2, stiffness / 2, 0.0, 0.0, 1.0])


def _residuals(
    exps: list[tuple[float, float, FloatArray]],
    theta_ref: FloatArray,
    free: list[int],
    scale: FloatArray,
    backend: str,
    pool: ThreadPoolExecutor,
    max_step: float = MAX_STEP,
) -> Callable[[FloatArray], tuple[FloatArray, FloatArray]]:
    part = feedback_part(backend)

    def fun(p: FloatArray) -> tuple[FloatArray, FloatArray]:
        theta = theta_ref.copy()
        theta[free] = p * scale

        def one(e: tuple[float, float, FloatArray]) -> tuple[FloatArray, FloatArray]:
            amp, freq, yb = e
            y, jac, _, _ = part.feedback_periodic(
                theta, amp, 2 * math.pi * freq, yb.size, _substeps(freq, yb.size, max_step)
            )
            return y - yb, jac[:, free] * scale

        try:
            parts = list(pool.map(one, exps))
        except (NonFiniteError, NotConvergedError):
            m = sum(yb.size for _, _, yb in exps)
            return np.full(m, np.nan), np.full((m, len(free)), np.nan)
        return np.concatenate([r for r, _ in parts]), np.vstack([j for _, j in parts])

    return fun


def fit_feedback_sines(
    experiments: Sequence[SineExperiment],
    *,
    theta0: Optional[ArrayLike] = None,
    beta: float = 1.0,
    fixed: Sequence[str] = (),
    starts: int = 6,
    seed: int = 0,
    max_iter: int = 60,
    noise_variance: Optional[float] = None,
    threads: int = 2,
    backend: str = "rust",
    max_step: float = MAX_STEP,
    noise: Optional[Sequence[tuple[float, int]]] = None,
) -> FeedbackFit:
    """Fit Bouc-Wen in feedback to averaged steady sine periods (module docstring).

    The same parameters, normalisation (``beta`` fixed: only ``beta*gamma`` and ``beta*delta`` are
    identifiable) and multi-start as :func:`~._feedback.fit_feedback`; the start comes from the first
    harmonics when ``theta0`` is not given.  The result's ``x0`` is empty and ``rmse`` is per experiment.
    ``max_step`` (s) is the largest RK4 step (default 1/15000 s, the benchmark's; the diagnosis passes a
    fraction of the shortest period, which keeps the cost independent of the time unit).

    ``noise`` (one ``(variance, dof)`` pair per experiment: the noise variance of the averaged period's
    samples, e.g. the period-to-period variance over the number of periods, and its degrees of freedom) or
    ``noise_variance`` (known, the same for every sample) runs the adequacy test: the residual power against
    that noise (``fit.adequacy``, an F or chi-square test, :mod:`._feedback_adequacy`).

    Raises
    ------
    InvalidParameterError, InsufficientDataError, NonFiniteError
        Bad experiments or arguments; no start could be simulated.
    """
    t_start = time.perf_counter()
    exps = _checked(experiments)
    beta = positive_number("beta", beta)
    noise_pairs = None if noise is None else check_noise(noise, len(exps))
    if noise_variance is not None:
        noise_variance = positive_number("noise_variance", noise_variance)
    max_step = positive_number("max_step", max_step)
    starts = count("starts", starts, 1)
    unknown = [f for f in fixed if f not in FEEDBACK_PARAMETERS]
    if unknown:
        raise InvalidParameterError(
            f"fixed names {unknown} are not parameters; choose among {FEEDBACK_PARAMETERS}"
        )
    theta_ref = linear_start_sines(exps) if theta0 is None else finite_array("theta0", theta0)
    if theta_ref.size != len(FEEDBACK_PARAMETERS):
        raise InvalidParameterError(f"theta0 must hold 7 values {FEEDBACK_PARAMETERS}")
    free = [i for i, name in enumerate(FEEDBACK_PARAMETERS) if name not in fixed]
    y_rms = float(np.sqrt(np.mean(np.concatenate([yb for _, _, yb in exps]) ** 2)))
    scale = np.where(np.abs(theta_ref) > 0, np.abs(theta_ref), 1.0)
    scale[4:6] = np.maximum(np.abs(theta_ref[4:6]), 1.0 / y_rms)
    scale = scale[free]
    lo = np.array([1e-6 * abs(theta_ref[0]), 0.0, -np.inf, -np.inf, -np.inf, -np.inf, 0.5])[free] / scale
    hi = np.array([np.inf] * 6 + [4.0])[free] / scale
    costs: list[float] = []
    best: Optional[LMResult] = None
    with ThreadPoolExecutor(max(1, threads)) as pool:
        fun = _residuals(exps, theta_ref, free, scale, backend, pool, max_step)
        for cand in random_starts(theta_ref, y_rms, starts, seed):
            try:
                res = levenberg_marquardt(
                    fun, cand[free] / scale, lo, hi, max_iter=15 if starts > 1 else max_iter
                )
            except NonFiniteError:
                costs.append(math.nan)
                continue
            costs.append(res.cost)
            if best is None or res.cost < best.cost:
                best = res
        if best is None:
            raise NonFiniteError("no start could be simulated; give theta0 near the system's parameters")
        if starts > 1:
            best = levenberg_marquardt(fun, best.p, lo, hi, max_iter=max_iter, sigma2=noise_variance)
    fit = _result(best, exps, theta_ref, free, scale, beta, costs, time.perf_counter() - t_start)
    bounds = np.cumsum([0] + [yb.size for _, _, yb in exps])
    segments = [best.residuals[a:b] for a, b in zip(bounds[:-1], bounds[1:])]
    return replace(fit, adequacy=sine_adequacy(segments, len(free), noise_pairs, noise_variance))


def _result(
    lm: LMResult,
    exps: list[tuple[float, float, FloatArray]],
    theta_ref: FloatArray,
    free: list[int],
    scale: FloatArray,
    beta: float,
    costs: list[float],
    elapsed: float,
) -> FeedbackFit:
    theta = theta_ref.copy()
    theta[free] = lm.p * scale
    cov = lm.covariance * np.outer(scale, scale)
    se = np.sqrt(np.abs(np.diag(cov)))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    jn = lm.jacobian / np.maximum(np.linalg.norm(lm.jacobian, axis=0), 1e-300)
    sv = np.linalg.svd(jn, compute_uv=False)
    bounds = np.cumsum([0] + [yb.size for _, _, yb in exps])
    rmse = [float(np.sqrt(np.mean(lm.residuals[a:b] ** 2))) for a, b in zip(bounds[:-1], bounds[1:])]
    return FeedbackFit(
        model=FeedbackModel.from_theta(theta, beta),
        names=tuple(FEEDBACK_PARAMETERS[i] for i in free),
        estimates=theta[free],
        standard_errors=se,
        correlation=corr,
        x0=[],
        rmse=np.array(rmse),
        sigma2=float(lm.sigma2),
        condition=float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf,
        reason=lm.reason,
        iterations=lm.iterations,
        starts=len(costs),
        elapsed=elapsed,
        start_costs=np.array(costs, dtype=np.float64),
        identifiability=(
            f"beta is fixed at {beta:g}: it only multiplies gamma and delta, so (beta, gamma, delta) and "
            "(s beta, gamma/s, delta/s) give the same output; the identifiable set is "
            "[m, c, k, alpha, beta*gamma, beta*delta, nu]"
        ),
    )
