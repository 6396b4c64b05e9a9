"""Bouc-Wen in feedback (issue #20): the model class of the Noel-Schoukens benchmark and its output-error fit.

The system is ``m ydd + c yd + k y + z = u`` with the hysteretic force

    ``zdot = alpha yd - beta (gamma |yd| |z|^(nu-1) z + delta yd |z|^nu)``,

input ``u`` (force), output ``y`` (displacement), ``z`` unmeasured.

**Identifiable parameters.**  ``beta`` only ever multiplies ``gamma`` and ``delta``: ``(beta, gamma, delta)``
and ``(s beta, gamma / s, delta / s)`` give the same output for every ``s > 0``, so the three cannot be
identified together (Brunot et al., IFAC-PapersOnLine 50(1) 2017, found correlations of 0.998-1.00 and a
Jacobian condition number of 1.6e6 when fitting all three).  The fit therefore estimates the identifiable
set ``[m, c, k, alpha, beta*gamma, beta*delta, nu]`` (seven physical parameters) and reports ``gamma`` and
``delta`` at a **fixed** ``beta`` (the normalisation, given by the user; 1 by default).  ``z`` has no free
scale: it enters the force balance with the coefficient 1, which fixes its unit (N) and so ``alpha``.

The simulation with forward sensitivities (exact Jacobian of the discrete RK4 map) is ``rust/feedback.rs``,
reached through :func:`bouc_wen_id._backend.feedback_part`; the search is the bounded
:func:`~bouc_wen_id.timedomain.levenberg_marquardt` of this package.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace
from typing import Literal, Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._backend import feedback_part
from .._text import Summarised
from ..errors import InsufficientDataError, InvalidParameterError, NonFiniteError
from ..validation import count, finite_array, positive_number, z_value
from ._feedback_adequacy import FeedbackAdequacy, record_adequacy
from ._feedback_start import linear_start, random_starts
from ._lm import LMResult, levenberg_marquardt
from ._records import RecordLike, TimeRecord, as_time_records, lead_in_samples

__all__ = ["FEEDBACK_PARAMETERS", "FeedbackFit", "FeedbackModel", "fit_feedback", "upsample_input"]

FloatArray = NDArray[np.float64]

#: The identifiable physical parameters, in the order of the simulator's Jacobian columns.
FEEDBACK_PARAMETERS = ("m", "c", "k", "alpha", "beta_gamma", "beta_delta", "nu")
_N = len(FEEDBACK_PARAMETERS)

#: Samples reflected at each end of a non-periodic input before its polyphase reconstruction.
_EDGE_PAD = 64

#: RK4 steps per output sample by default (at 750 Hz: 15 kHz, the benchmark's integration rate).
DEFAULT_SUBSTEPS = 20


@dataclass(frozen=True)
class FeedbackModel:
    """``m ydd + c yd + k y + z = u``,
    ``zdot = alpha yd - beta_gamma |yd||z|^(nu-1) z - beta_delta yd |z|^nu``.

    ``beta`` is the fixed normalisation under which :attr:`gamma` and :attr:`delta` are reported (module
    docstring); it does not enter the dynamics except through the products.
    """

    m: float
    c: float
    k: float
    alpha: float
    beta_gamma: float
    beta_delta: float
    nu: float = 1.0
    beta: float = 1.0

    @classmethod
    def from_benchmark(
        cls, m: float, c: float, k: float, alpha: float, beta: float, gamma: float, delta: float, nu: float
    ) -> FeedbackModel:
        """The model from the benchmark's over-parameterised form (``beta`` becomes the normalisation)."""
        beta = positive_number("beta", beta)
        return cls(m, c, k, alpha, beta * gamma, beta * delta, nu, beta)

    @classmethod
    def from_theta(cls, theta: ArrayLike, beta: float = 1.0) -> FeedbackModel:
        th = finite_array("theta", theta)
        if th.size != _N:
            raise InvalidParameterError(f"theta must hold {_N} values {FEEDBACK_PARAMETERS}, got {th.size}")
        m, c, k, alpha, bg, bd, nu = (float(v) for v in th)
        return cls(m, c, k, alpha, bg, bd, nu, float(beta))

    @property
    def gamma(self) -> float:
        """``gamma = beta_gamma / beta`` at the fixed ``beta``."""
        return self.beta_gamma / self.beta

    @property
    def delta(self) -> float:
        """``delta = beta_delta / beta`` at the fixed ``beta``."""
        return self.beta_delta / self.beta

    @property
    def theta(self) -> FloatArray:
        """``[m, c, k, alpha, beta_gamma, beta_delta, nu]``."""
        return np.array([self.m, self.c, self.k, self.alpha, self.beta_gamma, self.beta_delta, self.nu])

    def simulate(
        self,
        u: ArrayLike,
        dt: float,
        *,
        x0: Sequence[float] = (0.0, 0.0, 0.0),
        upsample: int = 1,
        periodic: bool = False,
        substeps: int = DEFAULT_SUBSTEPS,
        backend: str = "rust",
    ) -> FloatArray:
        """The displacement ``y`` on the grid ``k dt`` driven by the samples ``u`` (same grid), from the state
        ``x0 = [y0, yd0, z0]``.  ``upsample > 1`` reconstructs the input between samples band-limitedly
        (:func:`upsample_input`) before the RK4's cubic interpolation."""
        uu = finite_array("u", u)
        fine = upsample_input(uu, upsample, periodic=periodic)
        y, _, _ = feedback_part(backend).feedback_simulate(
            self.theta, np.asarray(x0, dtype=np.float64), fine, float(dt), upsample, substeps, False
        )
        return y

    def simulate_record(self, t: ArrayLike, u: ArrayLike) -> FloatArray:
        """``y`` on a uniformly sampled record from rest: the hook :func:`~bouc_wen_id.validate` calls."""
        tt = finite_array("t", t)
        if tt.ndim != 1 or tt.size < 2:
            raise InvalidParameterError(f"t must be 1-D with at least 2 samples, got shape {tt.shape}")
        return self.simulate(u, float(np.mean(np.diff(tt))))


def upsample_input(u: ArrayLike, factor: int, *, periodic: bool = False) -> FloatArray:
    """``u`` on the grid ``dt / factor`` (``(n - 1) factor + 1`` samples), reconstructed band-limitedly.

    A periodic record (an integer number of periods of a multisine) is interpolated exactly by zero-padding
    its DFT; any other by a polyphase Kaiser-windowed sinc (``scipy.signal.resample_poly``), exact for content
    well below Nyquist (the ends are extended by odd reflection).  ``factor = 1`` returns ``u``.
    """
    uu = finite_array("u", u)
    factor = count("upsample", factor, 1)
    if factor == 1:
        return uu
    n = uu.size
    if n < 2:
        raise InsufficientDataError(f"an input needs at least 2 samples, got {n}")
    if periodic:
        spec = np.fft.rfft(uu)
        if n % 2 == 0:
            spec[-1] *= 0.5  # the Nyquist bin is shared by +-fs/2 once zero-padded
        fine = np.fft.irfft(spec, n * factor) * factor
    else:
        from scipy.signal import resample_poly  # type: ignore[import-untyped]

        # Odd reflection about the end values keeps the value and slope continuous at both ends, so the
        # filter's zero padding does not ring into the record.
        pad = min(_EDGE_PAD, n - 1)
        padded = np.pad(uu, pad, mode="reflect", reflect_type="odd")
        fine = resample_poly(padded, factor, 1, window=("kaiser", 10.0))[pad * factor :]
    return np.ascontiguousarray(fine[: (n - 1) * factor + 1], dtype=np.float64)


@dataclass(frozen=True, eq=False)
class FeedbackFit(Summarised):
    """What :func:`fit_feedback` returns.

    Attributes
    ----------
    model : FeedbackModel
        The estimate (``beta`` the fixed normalisation).
    names : tuple of str
        The estimated parameters (the identifiable set less ``fixed``), then ``x0`` entries when estimated.
    estimates, standard_errors : ndarray
        In ``names`` order, physical units; standard errors from ``sigma2 (J^T J)^-1``.
    correlation : ndarray
        Correlation matrix of the estimates.
    x0 : list of ndarray
        The initial state ``[y0, yd0, z0]`` of each record (zeros for ``initial_state="rest"``).
    rmse : ndarray
        Simulation RMSE of each record over its fitted samples (units of ``y``).
    sigma2 : float
        The residual variance the standard errors use.
    condition : float
        Condition number of the column-normalised Jacobian at the estimate.
    reason : str
        Why the final search stopped (:data:`~bouc_wen_id.timedomain.StopReason`).
    starts, elapsed : int, float
        Starts screened; wall time (s).
    start_costs : ndarray
        The screening cost of every start (NaN where the start could not be simulated).
    identifiability : str
        Which combination is fixed and why.
    adequacy : FeedbackAdequacy or None
        The adequacy test (:mod:`._feedback_adequacy`): residual whiteness for records, residual power
        against the averaged noise for sine periods (None when no noise level was given for those).
    """

    model: FeedbackModel
    names: tuple[str, ...]
    estimates: FloatArray = field(repr=False)
    standard_errors: FloatArray = field(repr=False)
    correlation: FloatArray = field(repr=False)
    x0: list[FloatArray] = field(repr=False)
    rmse: FloatArray
    sigma2: float
    condition: float
    reason: str
    iterations: int
    starts: int
    elapsed: float
    start_costs: FloatArray = field(repr=False)
    identifiability: str = field(repr=False)
    adequacy: Optional[FeedbackAdequacy] = None

    def summary(self) -> str:
        lines = [
            f"FeedbackFit: Bouc-Wen in feedback, {self.reason} after {self.iterations} iterations "
            f"({self.starts} start(s), {self.elapsed:.1f} s); "
            f"RMSE {', '.join(f'{v:.4g}' for v in self.rmse)}",
        ]
        for name, est, se in zip(self.names, self.estimates, self.standard_errors):
            lines.append(f"  {name:>10} = {float(est): .6g} +- {float(se):.3g}")
        if self.adequacy is None:
            lines.append("  adequacy: not run (give the averaged periods' noise: noise= or noise_variance=)")
        else:
            lines.append(f"  {self.adequacy.describe()}")
        lines.append(f"  {self.identifiability}")
        return "\n".join(lines)

    def simulate_record(self, t: ArrayLike, u: ArrayLike) -> FloatArray:
        """The fitted model on a fresh record from rest (what :func:`~bouc_wen_id.validate` calls)."""
        return self.model.simulate_record(t, u)

    def interval(self, name: str, level: float = 0.95) -> tuple[float, float]:
        """The symmetric normal-approximation interval of parameter ``name`` at ``level``."""
        if name not in self.names:
            raise InvalidParameterError(f"{name!r} is not an estimated parameter; estimated: {self.names}")
        if not 0.0 < level < 1.0:
            raise InvalidParameterError(f"level = {level} must lie in (0, 1)")
        i = self.names.index(name)
        half = z_value(level) * float(self.standard_errors[i])
        return float(self.estimates[i]) - half, float(self.estimates[i]) + half

    def benchmark_form(self) -> dict[str, tuple[float, float]]:
        """``{name: (estimate, standard error)}`` in the benchmark's form, ``gamma``, ``delta`` at the fixed
        ``beta`` (their errors are those of the products divided by ``beta``)."""
        out: dict[str, tuple[float, float]] = {}
        beta = self.model.beta
        for name, est, se in zip(self.names, self.estimates, self.standard_errors):
            if name == "beta_gamma":
                out["gamma"] = (float(est) / beta, float(se) / beta)
            elif name == "beta_delta":
                out["delta"] = (float(est) / beta, float(se) / beta)
            elif name in FEEDBACK_PARAMETERS:
                out[name] = (float(est), float(se))
        return out


@dataclass
class _Problem:
    """The records prepared for the simulator, and which columns the search moves."""

    inputs: list[FloatArray]
    outputs: list[FloatArray]
    skips: list[int]
    dts: list[float]
    upsample: int
    substeps: int
    free: list[int]
    theta_fixed: FloatArray
    estimate_x0: bool
    scale: FloatArray
    backend: str

    @property
    def n_free(self) -> int:
        return len(self.free)

    def unpack(self, p: FloatArray) -> tuple[FloatArray, list[FloatArray]]:
        phys = p * self.scale
        theta = self.theta_fixed.copy()
        theta[self.free] = phys[: self.n_free]
        x0s = [
            phys[self.n_free + 3 * i : self.n_free + 3 * i + 3] if self.estimate_x0 else np.zeros(3)
            for i in range(len(self.inputs))
        ]
        return theta, x0s

    def residuals(self, p: FloatArray, pool: Optional[ThreadPoolExecutor]) -> tuple[FloatArray, FloatArray]:
        theta, x0s = self.unpack(p)
        part = feedback_part(self.backend)

        def one(i: int) -> tuple[FloatArray, FloatArray]:
            y, jac, _ = part.feedback_simulate(
                theta, x0s[i], self.inputs[i], self.dts[i], self.upsample, self.substeps, True
            )
            return (y - self.outputs[i])[self.skips[i] :], jac[self.skips[i] :]

        try:
            parts = (
                list(pool.map(one, range(len(self.inputs))))
                if pool
                else [one(i) for i in range(len(self.inputs))]
            )
        except NonFiniteError:
            m = sum(o.size - s for o, s in zip(self.outputs, self.skips))
            return np.full(m, np.nan), np.full((m, p.size), np.nan)
        blocks = []
        for i, (_, jac) in enumerate(parts):
            block = np.zeros((jac.shape[0], p.size))
            block[:, : self.n_free] = jac[:, self.free]
            if self.estimate_x0:
                block[:, self.n_free + 3 * i : self.n_free + 3 * i + 3] = jac[:, _N:]
            blocks.append(block)
        r = np.concatenate([res for res, _ in parts])
        return r, np.vstack(blocks) * self.scale


def _bounds(problem: _Problem) -> tuple[FloatArray, FloatArray]:
    """Box of the search (scaled): ``m > 0``, ``c >= 0``, ``0.5 <= nu <= 4``; the rest free."""
    lo_phys = np.array([0.0, 0.0, -np.inf, -np.inf, -np.inf, -np.inf, 0.5])
    hi_phys = np.array([np.inf, np.inf, np.inf, np.inf, np.inf, np.inf, 4.0])
    lo_phys[0] = 1e-6 * abs(problem.theta_fixed[0])
    n_x0 = 3 * len(problem.inputs) if problem.estimate_x0 else 0
    lo = np.concatenate([lo_phys[problem.free], np.full(n_x0, -np.inf)]) / problem.scale
    hi = np.concatenate([hi_phys[problem.free], np.full(n_x0, np.inf)]) / problem.scale
    return lo, hi


def _prepare(
    recs: list[TimeRecord],
    theta_ref: FloatArray,
    fixed: Sequence[str],
    estimate_x0: bool,
    lead_in: Optional[float],
    upsample: int,
    periodic: bool,
    substeps: int,
    backend: str,
) -> _Problem:
    unknown = [f for f in fixed if f not in FEEDBACK_PARAMETERS]
    if unknown:
        raise InvalidParameterError(
            f"fixed names {unknown} are not parameters; choose among {FEEDBACK_PARAMETERS}"
        )
    free = [i for i, name in enumerate(FEEDBACK_PARAMETERS) if name not in fixed]
    skips = [lead_in_samples(r, lead_in) for r in recs]
    for r, s in zip(recs, skips):
        if len(r) - s < 2 * (len(free) + (3 if estimate_x0 else 0)):
            raise InsufficientDataError(
                f"record {r.name!r} keeps {len(r) - s} samples after the lead-in: too few to fit the model"
            )
    y_rms = max(float(np.sqrt(np.mean(np.concatenate([r.y for r in recs]) ** 2))), 1e-300)
    stiff = abs(theta_ref[2]) + abs(theta_ref[3])
    wn = math.sqrt(max(stiff, 1e-300) / theta_ref[0])
    scale_theta = np.where(np.abs(theta_ref) > 0, np.abs(theta_ref), 1.0)
    scale_theta[4:6] = np.maximum(np.abs(theta_ref[4:6]), 1.0 / y_rms)
    scale_x0 = np.tile([y_rms, y_rms * wn, stiff * y_rms], len(recs)) if estimate_x0 else np.zeros(0)
    return _Problem(
        inputs=[upsample_input(r.u, upsample, periodic=periodic) for r in recs],
        outputs=[r.y for r in recs],
        skips=skips,
        dts=[r.dt for r in recs],
        upsample=upsample,
        substeps=substeps,
        free=free,
        theta_fixed=theta_ref.copy(),
        estimate_x0=estimate_x0,
        scale=np.concatenate([scale_theta[free], scale_x0]),
        backend=backend,
    )


def _truncated(problem: _Problem, samples: int, substeps: int) -> _Problem:
    """The first record's first ``samples`` samples after its lead-in, at ``substeps``: the screening
    problem of the multi-start."""
    up = problem.upsample
    stop = problem.skips[0] + samples
    return _Problem(
        inputs=[problem.inputs[0][: (stop - 1) * up + 1]],
        outputs=[problem.outputs[0][:stop]],
        skips=[problem.skips[0]],
        dts=[problem.dts[0]],
        upsample=up,
        substeps=substeps,
        free=problem.free,
        theta_fixed=problem.theta_fixed,
        estimate_x0=problem.estimate_x0,
        scale=problem.scale[: problem.n_free + (3 if problem.estimate_x0 else 0)],
        backend=problem.backend,
    )


def _search(
    problem: _Problem,
    p0: FloatArray,
    max_iter: int,
    pool: Optional[ThreadPoolExecutor],
    sigma2: Optional[float],
) -> Optional[LMResult]:
    lo, hi = _bounds(problem)
    try:
        return levenberg_marquardt(
            lambda p: problem.residuals(p, pool), p0, lo, hi, max_iter=max_iter, sigma2=sigma2
        )
    except NonFiniteError:
        return None  # this start cannot be simulated (a blow-up at the start itself)


def _initial_states(problem: _Problem, theta: FloatArray, pool: Optional[ThreadPoolExecutor]) -> FloatArray:
    """The initial states of every record at the parameters ``theta`` (the states alone searched from
    rest), so that a record cut mid-motion does not drag the parameters of a start; empty when they are not
    estimated."""
    if not problem.estimate_x0:
        return np.zeros(0)
    n_free = problem.n_free
    states = replace(
        problem, free=[], theta_fixed=np.array(theta, dtype=np.float64), scale=problem.scale[n_free:]
    )
    res = _search(states, np.zeros(states.scale.size), 30, pool, None)
    return np.zeros(states.scale.size) if res is None else res.p * states.scale


def fit_feedback(
    records: Union[RecordLike, Sequence[RecordLike]],
    *,
    theta0: Optional[ArrayLike] = None,
    beta: float = 1.0,
    fixed: Sequence[str] = (),
    initial_state: Literal["rest", "estimate"] = "rest",
    lead_in: Optional[float] = None,
    starts: int = 8,
    seed: int = 0,
    screen_samples: int = 3000,
    max_iter: int = 60,
    substeps: int = DEFAULT_SUBSTEPS,
    upsample: int = 1,
    periodic: bool = False,
    noise_variance: Optional[float] = None,
    threads: int = 2,
    backend: str = "rust",
) -> FeedbackFit:
    """Output-error fit of Bouc-Wen in feedback to records ``(t, u, y)`` of any waveform (module docstring).

    Parameters
    ----------
    records : TimeRecord, (t, u, y) tuple, Recording, or a sequence of them
        Force ``u`` and displacement ``y`` on uniform time grids.
    theta0 : array_like, optional
        A start ``[m, c, k, alpha, beta*gamma, beta*delta, nu]``; without it the start comes from a linear
        (ARX) fit of the records (:func:`~._feedback_start.linear_start`).  Fixed parameters keep its value.
    beta : float
        The normalisation of ``(beta, gamma, delta)`` (only the products are identifiable).
    fixed : sequence of str
        Parameters held at their ``theta0`` value (e.g. ``("nu",)``).
    initial_state : "rest" or "estimate"
        Start every record at rest, or estimate ``[y0, yd0, z0]`` per record.
    lead_in : float, optional
        Seconds at the start of every record simulated but left out of the cost (a transient).
    starts, seed : int
        Multi-start: ``starts`` starting points (the first is ``theta0`` or the linear start, the rest drawn
        from the seeded generator around it), each screened by a short search on the first
        ``screen_samples`` samples of the first record; the best is polished on all data.
    max_iter, substeps : int
        Cap of the final search; RK4 steps per sample.
    upsample, periodic : int, bool
        Band-limited input reconstruction between samples (:func:`upsample_input`); ``periodic`` when every
        record holds an integer number of periods.
    noise_variance : float, optional
        The known output-noise variance for the standard errors (else the residual variance).
    threads : int
        Records simulated at once (the Rust simulator releases the interpreter).
    backend : "rust" or "numpy"
        The simulator (the NumPy oracle is slow: for tests).

    Raises
    ------
    InvalidParameterError, InsufficientDataError, NonFiniteError
        Bad arguments or records; no start could be simulated.
    """
    t_start = time.perf_counter()
    recs = as_time_records(records)
    beta = positive_number("beta", beta)
    starts = count("starts", starts, 1)
    if initial_state not in ("rest", "estimate"):
        raise InvalidParameterError(f"initial_state must be 'rest' or 'estimate', got {initial_state!r}")
    theta_ref = linear_start(recs) if theta0 is None else finite_array("theta0", theta0)
    if theta_ref.size != _N:
        raise InvalidParameterError(
            f"theta0 must hold {_N} values {FEEDBACK_PARAMETERS}, got {theta_ref.size}"
        )
    problem = _prepare(
        recs, theta_ref, fixed, initial_state == "estimate", lead_in, upsample, periodic, substeps, backend
    )
    y_rms = float(np.sqrt(np.mean(np.concatenate([r.y for r in recs]) ** 2)))
    candidates = random_starts(theta_ref, y_rms, starts, seed)
    screen = _truncated(problem, min(screen_samples, len(recs[0]) - problem.skips[0]), max(4, substeps // 2))
    with ThreadPoolExecutor(max(1, threads)) as pool:
        costs, best = [], None
        for cand in candidates:
            p0 = np.concatenate([cand[problem.free], _initial_states(problem, cand, pool)]) / problem.scale
            res = _search(screen, p0[: screen.scale.size], 25, None, None) if starts > 1 else None
            cost = res.cost if res is not None else (math.nan if starts > 1 else 0.0)
            costs.append(cost)
            if starts == 1 or (res is not None and (best is None or cost < best[0])):
                p_best = p0 if res is None else np.concatenate([res.p, p0[res.p.size :]])
                best = (cost, p_best)
        if best is None:
            raise NonFiniteError("no start could be simulated; give theta0 near the system's parameters")
        final = _search(problem, best[1], max_iter, pool, noise_variance)
    if final is None:
        raise NonFiniteError("the best start blew up on the full records; give theta0 or more substeps")
    return _result(problem, final, recs, beta, costs, time.perf_counter() - t_start)


def _result(
    problem: _Problem, lm: LMResult, recs: list[TimeRecord], beta: float, costs: list[float], elapsed: float
) -> FeedbackFit:
    theta, x0s = problem.unpack(lm.p)
    names = tuple(FEEDBACK_PARAMETERS[i] for i in problem.free)
    if problem.estimate_x0:
        names += tuple(f"{s}[{i}]" for i in range(len(recs)) for s in ("y0", "yd0", "z0"))
    cov = lm.covariance * np.outer(problem.scale, problem.scale)
    se = np.sqrt(np.abs(np.diag(cov)))
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(se, se)
    jn = lm.jacobian / np.maximum(np.linalg.norm(lm.jacobian, axis=0), 1e-300)
    sv = np.linalg.svd(jn, compute_uv=False)
    r = lm.residuals
    rmse, at, segments = [], 0, []
    for o, s in zip(problem.outputs, problem.skips):
        seg = r[at : at + o.size - s]
        rmse.append(float(np.sqrt(np.mean(seg**2))))
        segments.append(seg)
        at += o.size - s
    note = (
        f"beta is fixed at {beta:g}: it only multiplies gamma and delta, so (beta, gamma, delta) and "
        "(s beta, gamma/s, delta/s) give the same output; the identifiable set is "
        "[m, c, k, alpha, beta*gamma, beta*delta, nu], gamma and delta are reported at the fixed beta"
    )
    return FeedbackFit(
        model=FeedbackModel.from_theta(theta, beta),
        names=names,
        estimates=np.concatenate([theta[problem.free], np.concatenate(x0s) if problem.estimate_x0 else []]),
        standard_errors=se,
        correlation=corr,
        x0=x0s,
        rmse=np.array(rmse),
        sigma2=float(lm.sigma2),
        condition=float(sv[0] / sv[-1]) if sv[-1] > 0 else math.inf,
        reason=lm.reason,
        iterations=lm.iterations,
        starts=len(costs),
        elapsed=elapsed,
        start_costs=np.array(costs, dtype=np.float64),
        identifiability=note,
        adequacy=record_adequacy(segments),
    )
