"""Identification of a Wiener-Bouc-Wen system from sine recordings (the paper's method, Section 3)."""

from __future__ import annotations

import dataclasses
import json
import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Optional

import numpy as np
from numpy.typing import NDArray

from ._backend import Backend, get_backend
from .errors import (
    BoucWenIdError,
    ConvergenceWarning,
    FrequencyMismatchError,
    IdentifiabilityWarning,
    InsufficientDataError,
    InvalidParameterError,
    SearchAtBoundError,
    ZeroAmplitudeError,
)
from .model import Recording, WienerPlant

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .measurement import Measurement
    from .signal import AveragedPeriod

    #: What identify takes: simulated recordings, raw lab measurements, or averaged periods.
    Experiment = Recording | Measurement | AveragedPeriod

__all__ = [
    "identify",
    "IdentificationResult",
    "ExperimentEstimate",
    "Truth",
    "Adequacy",
    "Method",
    "noise_variance",
    "auto_harmonics",
]

FloatArray = NDArray[np.float64]
Method = Literal["paper", "profile", "refined"]

TWO_PI = 2.0 * math.pi
#: Largest relative misfit of ``u`` to ``U cos(omega t)`` before the stated frequency is called wrong.
INPUT_MISFIT_MAX = 0.05
#: Largest phase (rad) of the recorded input relative to ``cos(omega t)`` on the given time axis.
INPUT_PHASE_MAX = 0.02


def wrap_phase(phi: float | FloatArray) -> Any:
    """Map a phase to [0, 2 pi)."""
    return np.mod(phi, TWO_PI)


def phase_error(estimate: float | FloatArray, truth: float | FloatArray) -> Any:
    """Signed phase difference wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - (np.asarray(estimate) - np.asarray(truth)), TWO_PI)


@dataclass(frozen=True, eq=False)
class ExperimentEstimate:
    """What one sine experiment gave: the frequency-response point and the averaged loop.

    ``phase`` follows the paper, ``phi = -angle G(j omega)``, in [0, 2 pi).
    """

    frequency: float
    amplitude: float
    gain: float
    phase: float
    samples_per_period: int
    settle_periods: int
    periods: float
    harmonics: int
    ybar: FloatArray = field(repr=False)
    noise_sd: float = math.nan
    gain_se: Optional[float] = None
    phase_se: Optional[float] = None
    nrmse: float = math.nan
    model: Optional[FloatArray] = field(default=None, repr=False)
    source: str = ""
    #: omega t of the averaged grid's first sample (the grid's phase relative to u = U cos(omega t)).
    grid_phase: float = 0.0
    #: NRMSE of the best linear model (spring + dashpot: ybar's fundamental alone), the baseline a
    #: hysteresis model must beat to explain anything nonlinear.
    linear_nrmse: float = math.nan

    @property
    def response(self) -> complex:
        """``G(j omega) = |G| exp(-j phi)`` (alpha-normalised)."""
        return complex(self.gain * np.exp(-1j * self.phase))

    def model_input(self) -> FloatArray:
        """The steady ``x(t) = U |G| cos(omega t - phi)`` on the averaged period's grid."""
        t = np.arange(self.samples_per_period) * (TWO_PI / self.frequency / self.samples_per_period)
        out: FloatArray = (
            self.amplitude * self.gain * np.cos(self.frequency * t - self.phase + self.grid_phase)
        )
        return out

    def times(self) -> FloatArray:
        """Times (s) of the averaged period's samples, from the grid's first sample."""
        step = TWO_PI / self.frequency / self.samples_per_period
        out: FloatArray = np.arange(self.samples_per_period, dtype=np.float64) * np.float64(step)
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "frequency": self.frequency,
            "amplitude": self.amplitude,
            "gain": self.gain,
            "phase": self.phase,
            "samples_per_period": self.samples_per_period,
            "settle_periods": self.settle_periods,
            "periods": self.periods,
            "harmonics": self.harmonics,
            "noise_sd": _num(self.noise_sd),
            "gain_se": _num(self.gain_se),
            "phase_se": _num(self.phase_se),
            "nrmse": _num(self.nrmse),
            "linear_nrmse": _num(self.linear_nrmse),
            "source": self.source,
        }


@dataclass(frozen=True, eq=False)
class Truth:
    """The true, alpha-normalised parameters of a simulated plant, at the experiment frequencies."""

    plant: WienerPlant
    beta: float
    gamma: float
    mu: float
    gain: FloatArray
    phase: FloatArray

    @classmethod
    def from_plant(cls, plant: WienerPlant, frequencies: FloatArray) -> Truth:
        norm = plant.normalized()
        gain, phase = norm.linear.gain_phase(frequencies)
        h = norm.hysteresis
        return cls(norm, h.beta, h.gamma, h.mu, gain, wrap_phase(phase))

    def to_dict(self) -> dict[str, Any]:
        return {
            "plant": self.plant.to_dict(),
            "beta": self.beta,
            "gamma": self.gamma,
            "mu": self.mu,
            "gain": self.gain.tolist(),
            "phase": self.phase.tolist(),
        }


@dataclass(frozen=True, eq=False)
class IdentificationResult:
    """The identified model: hysteresis parameters and frequency-response points of G.

    The model is alpha-normalised (alpha = 1) and canonical (|G| > 0): of the equivalent models
    ``(G, phi)`` and ``(-G, phi + pi)`` the one with a positive gain is reported.

    Attributes
    ----------
    beta, gamma, mu : float
        Bouc-Wen parameters of (2b).
    cost : float
        ``paper``/``profile``: the separable least-squares cost I_N(mu) of (21) on the reference
        experiment; ``refined``: the weighted output-error cost, a chi-square statistic.
    experiments : tuple of ExperimentEstimate
        One frequency-response point per recording, in input order.
    reference : int
        Index of the experiment used for (beta, gamma, mu).
    truth : Truth or None
        The simulated plant's values when every recording carries the same plant.
    standard_errors : dict or None
        Standard errors of beta, gamma, mu (``refined`` only); per-experiment ones sit on each
        :class:`ExperimentEstimate`.
    covariance : ndarray or None
        Covariance of ``[beta, gamma, mu, |G_0|, phi_0, |G_1|, phi_1, ...]`` (``refined`` only).
    adequacy : Adequacy or None
        Residual power of the fitted loops against the noise floor.
    warnings : tuple of str
        Identifiability warnings (also issued as :class:`IdentifiabilityWarning`).
    converged : bool or None
        Whether the joint fit met its tolerances before ``max_iter`` (``refined``; None for the direct
        estimators).  ``False`` is also issued as a :class:`ConvergenceWarning`.
    """

    method: str
    backend: str
    beta: float
    gamma: float
    mu: float
    cost: float
    iterations: int
    reference: int
    experiments: tuple[ExperimentEstimate, ...]
    settings: dict[str, Any]
    truth: Optional[Truth] = None
    standard_errors: Optional[dict[str, float]] = None
    covariance: Optional[FloatArray] = field(default=None, repr=False)
    adequacy: Optional[Adequacy] = None
    warnings: tuple[str, ...] = ()
    confidence: float = 0.95
    converged: Optional[bool] = None

    def interval(self, name: str) -> tuple[float, float]:
        """Confidence interval (at ``self.confidence``) of ``beta``, ``gamma`` or ``mu``.

        Raises
        ------
        InvalidParameterError
            When the method gives no uncertainty (only ``method="refined"`` does).
        """
        if self.standard_errors is None:
            raise InvalidParameterError(f"method={self.method!r} gives no uncertainty; use method='refined'")
        z = _z(self.confidence)
        v, se = float(getattr(self, name)), self.standard_errors[name]
        return v - z * se, v + z * se

    @property
    def frequencies(self) -> FloatArray:
        return np.array([e.frequency for e in self.experiments])

    @property
    def gains(self) -> FloatArray:
        return np.array([e.gain for e in self.experiments])

    @property
    def phases(self) -> FloatArray:
        return np.array([e.phase for e in self.experiments])

    @property
    def frequency_response(self) -> NDArray[np.complex128]:
        """``G(j omega_i)`` estimates (alpha-normalised)."""
        out: NDArray[np.complex128] = self.gains * np.exp(-1j * self.phases)
        return out

    def errors(self) -> dict[str, Any]:
        """Estimate minus truth for every parameter (phases wrapped to (-pi, pi]).

        Raises
        ------
        InvalidParameterError
            When the truth is unknown (recordings that did not come from :func:`simulate`).
        """
        if self.truth is None:
            raise InvalidParameterError("the truth is unknown: these recordings carry no plant")
        tr = self.truth
        return {
            "beta": self.beta - tr.beta,
            "gamma": self.gamma - tr.gamma,
            "mu": self.mu - tr.mu,
            "gain": self.gains - tr.gain,
            "phase": phase_error(self.phases, tr.phase),
        }

    def summary(self) -> str:
        """A plain-text table of the estimates, their uncertainty, the loop fit and the truth."""
        tr = self.truth
        se = self.standard_errors
        z = _z(self.confidence)
        lines = [f"Wiener-Bouc-Wen identification (method={self.method}, backend={self.backend})"]
        what = "LM iterations" if self.method == "refined" else "golden-section iterations"
        lines.append(
            f"  reference experiment {self.reference}, {self.iterations} {what}, cost = {self.cost:.4g}"
        )
        head = f"  {'parameter':<12}{'estimate':>13}"
        if se is not None:
            head += f"{'std.err':>11}{f'{self.confidence:.0%} interval':>24}"
        if tr is not None:
            head += f"{'truth':>13}{'error':>12}{'rel.err':>10}"
        lines.append(head)
        for name in ("beta", "gamma", "mu"):
            val = float(getattr(self, name))
            row = f"  {name:<12}{val:>13.6g}"
            if se is not None:
                row += f"{se[name]:>11.3g}{f'[{val - z * se[name]:.4g}, {val + z * se[name]:.4g}]':>24}"
            if tr is not None:
                t = float(getattr(tr, name))
                row += f"{t:>13.6g}{val - t:>12.3g}{_rel(val, t):>10}"
            lines.append(row)
        lines.append("")
        head = f"  {'omega':>9}{'U':>8}{'|G| est':>11}{'phi est':>10}"
        if se is not None:
            head += f"{'se|G|':>10}{'se phi':>10}"
        if tr is not None:
            head += f"{'|G| true':>11}{'phi true':>10}{'|G| rel.err':>12}{'phi err':>10}"
        head += f"{'P':>7}{'N':>8}{'noise sd':>10}{'NRMSE':>10}"
        lines.append(head)
        for i, e in enumerate(self.experiments):
            row = f"  {e.frequency:>9.4g}{e.amplitude:>8.3g}{e.gain:>11.5g}{e.phase:>10.4f}"
            if se is not None:
                row += f"{_fmt(e.gain_se):>10}{_fmt(e.phase_se):>10}"
            if tr is not None:
                dphi = float(phase_error(e.phase, tr.phase[i]))
                row += (
                    f"{tr.gain[i]:>11.5g}{tr.phase[i]:>10.4f}{_rel(e.gain, float(tr.gain[i])):>12}"
                    f"{dphi:>10.2e}"
                )
            row += f"{e.samples_per_period:>7}{e.periods:>8.4g}{_fmt(e.noise_sd):>10}{_fmt(e.nrmse):>10}"
            if i == self.reference:
                row += "  (reference)"
            lines.append(row)
        lines.append(
            "  (P: points of the averaged period; N: samples averaged per point "
            "(periods x samples per period / P),"
        )
        lines.append(
            "   so each point's noise sd is noise sd / sqrt(N); NRMSE: |ybar - model| / |ybar - mean|)"
        )
        if self.adequacy is not None:
            a = self.adequacy
            lines.append("")
            lines.append(
                f"  adequacy: chi2 = {a.statistic:.4g} on {a.dof} dof (noise floor from {a.noise_dof} dof), "
                f"p = {a.p_value:.3g}"
                + ("  -> the model does not explain the data" if a.p_value < 0.05 else "")
            )
        for w in self.warnings:
            lines.append(f"  warning: {w}")
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def __repr__(self) -> str:
        return (
            f"IdentificationResult(method={self.method!r}, beta={self.beta:.6g}, gamma={self.gamma:.6g}, "
            f"mu={self.mu:.6g}, experiments={len(self.experiments)}, cost={self.cost:.3g})"
        )

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description (format ``bouc_wen_id.result``, version 1)."""
        out: dict[str, Any] = {
            "format": "bouc_wen_id.result",
            "version": 1,
            "method": self.method,
            "backend": self.backend,
            "normalisation": "alpha = 1 (G -> alpha G, beta -> beta/alpha, gamma -> gamma/alpha)",
            "phase_convention": "phi = -angle G(j omega), radians in [0, 2 pi)",
            "beta": self.beta,
            "gamma": self.gamma,
            "mu": self.mu,
            "cost": self.cost,
            "iterations": self.iterations,
            "reference": self.reference,
            "settings": self.settings,
            "experiments": [e.to_dict() for e in self.experiments],
            "truth": None if self.truth is None else self.truth.to_dict(),
            "confidence": self.confidence,
            "standard_errors": self.standard_errors,
            "covariance": None if self.covariance is None else self.covariance.tolist(),
            "adequacy": None if self.adequacy is None else self.adequacy.to_dict(),
            "warnings": list(self.warnings),
        }
        if self.truth is not None:
            err = self.errors()
            out["errors"] = {
                k: (v.tolist() if isinstance(v, np.ndarray) else float(v)) for k, v in err.items()
            }
        return out

    def to_json(self, indent: int = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def plot_loop(self, experiment: Optional[int] = None, ax: Optional[Axes] = None) -> Figure:
        """Plot the averaged loop ybar against the identified x (all experiments, or one)."""
        from .plotting import plot_loop

        return plot_loop(self, experiment=experiment, ax=ax)

    def plot_bode(self, axes: Optional[Sequence[Axes]] = None) -> Figure:
        """Plot the identified |G(j omega_i)| and phi(omega_i) points, against the truth when known."""
        from .plotting import plot_bode

        return plot_bode(self, axes=axes)


def _rel(est: float, true: float) -> str:
    return f"{(est - true) / abs(true):.2e}" if true != 0 else "-"


def _fmt(v: Optional[float]) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.3g}"


def _num(v: Optional[float]) -> Optional[float]:
    """JSON has no NaN: unknown values are written as null."""
    return None if v is None or not math.isfinite(v) else float(v)


def _z(confidence: float) -> float:
    """Two-sided normal quantile for a confidence level."""
    from statistics import NormalDist

    return NormalDist().inv_cdf(0.5 + confidence / 2.0)


@dataclass(frozen=True)
class Adequacy:
    """Residual power of the fitted loops against the noise floor (an F-test).

    ``statistic = sum_i (N_i / sigma_i^2) ||ybar_i - w_i||^2`` is chi-square with ``dof`` degrees of
    freedom when the model is right and the noise white; the noise variances come from the
    period-to-period spread with ``noise_dof`` degrees of freedom, so ``(statistic / dof)`` is compared
    with an F(dof, noise_dof) distribution.
    """

    statistic: float
    dof: int
    noise_dof: int
    p_value: float

    def rejects(self, level: float = 0.05) -> bool:
        """True when the model is rejected at ``level``."""
        return self.p_value < level

    def to_dict(self) -> dict[str, Any]:
        return {
            "statistic": self.statistic,
            "dof": self.dof,
            "noise_dof": self.noise_dof,
            "p_value": self.p_value,
        }


def _check_input(rec: Recording, start: int, stop: int) -> None:
    """Refuse a recording whose ``u`` is not ``U cos(omega t)`` on its own time axis.

    Over whole periods, cos, sin and the constant are orthogonal on the sample grid, so their
    least-squares coefficients are plain projections (no linear solve needed).
    """
    t = rec.t[start:stop]
    u = rec.u[start:stop]
    c, s = np.cos(rec.frequency * t), np.sin(rec.frequency * t)
    a_cos = 2.0 * float(np.dot(u, c)) / u.size
    a_sin = 2.0 * float(np.dot(u, s)) / u.size
    centred = u - u.mean()
    spread = float(np.dot(centred, centred))
    fitted = 0.5 * u.size * (a_cos**2 + a_sin**2)
    misfit = math.sqrt(max(spread - fitted, 0.0) / spread) if spread > 0 else math.inf
    if misfit > INPUT_MISFIT_MAX:
        raise FrequencyMismatchError(
            f"the recorded input is not a sine at omega = {rec.frequency:.6g} rad/s "
            f"(relative misfit {misfit:.2g} > {INPUT_MISFIT_MAX}); check the stated frequency and its units"
        )
    amp = math.hypot(a_cos, a_sin)
    if abs(amp - abs(rec.amplitude)) > INPUT_MISFIT_MAX * abs(rec.amplitude):
        raise InvalidParameterError(
            f"the stated amplitude U = {rec.amplitude:.6g} does not match the recorded input's {amp:.6g}"
        )
    phase = math.atan2(a_sin, a_cos * np.sign(rec.amplitude))
    if abs(phase) > INPUT_PHASE_MAX:
        raise InvalidParameterError(
            f"the recorded input is U cos(omega t - {phase:.3g}) rather than U cos(omega t) on its time "
            "axis; shift the time column so that the input peaks at t = 0"
        )


def noise_variance(y: FloatArray, samples_per_period: int, settle_periods: int, periods: int) -> float:
    """Noise variance from the period-to-period spread of the raw samples (needs >= 2 periods).

    ``sum_j sum_k (y_kj - ybar_j)^2 / (P (N - 1))``: unbiased for white noise, free of the signal.
    """
    if periods < 2:
        return math.nan
    p = samples_per_period
    seg = np.asarray(y[settle_periods * p : (settle_periods + periods) * p]).reshape(periods, p)
    return float(np.mean(np.var(seg, axis=0, ddof=1)))


#: A harmonic is signal when its power exceeds this multiple of the noise floor sigma^2/(N P): the
#: noise power of one bin is exponential, so a false alarm has probability e^-16 ~ 1e-7 per bin.
HARMONIC_SNR = 16.0


def auto_harmonics(ybar: FloatArray, noise_var: float, periods: float) -> int:
    """Highest harmonic of ``ybar`` standing above the noise floor (all of them when noise-free)."""
    p = ybar.size
    k_max = (p - 1) // 2
    if not math.isfinite(noise_var) or noise_var <= 0.0:
        return k_max
    power = np.abs(np.fft.rfft(ybar)[1 : k_max + 1] / p) ** 2
    above = np.flatnonzero(power > HARMONIC_SNR * noise_var / (periods * p))
    return int(above[-1]) + 1 if above.size else 1


@dataclass
class _Prepared:
    """One experiment reduced to its averaged period and what the estimators need of it."""

    amplitude: float
    frequency: float
    #: Added to the local phase (that of the averaged window's first sample) to give the phase of G.
    phase_shift: float
    p: int
    s: int
    n: float
    k: int
    ybar: FloatArray
    ydot: FloatArray
    noise_var: float
    noise_dof: int
    plant: Optional[WienerPlant]
    source: str


def _steady_substeps(p: int) -> int:
    """RK4 steps per sample of the steady-loop solver: a step of at most 2 pi/2048 rad."""
    return max(2, math.ceil(2048 / p))


def _harmonics(harmonics: int | str, ybar: FloatArray, noise_var: float, n: float) -> int:
    p = ybar.size
    if harmonics == "auto":
        return auto_harmonics(ybar, noise_var, n)
    if harmonics == "all":
        return (p - 1) // 2
    if isinstance(harmonics, (int, np.integer)) and not isinstance(harmonics, bool):
        return int(harmonics)
    raise InvalidParameterError(f"harmonics must be 'auto', 'all' or an int, got {harmonics!r}")


def _prepare_recording(
    i: int,
    rec: Recording,
    core: Any,
    settle_periods: Optional[int],
    periods: Optional[int],
    harmonics: int | str,
) -> _Prepared:
    """The paper's path: a whole number of samples per period and the periodic average (4a-b)."""
    p = rec.samples_per_period
    s = rec.settle_periods if settle_periods is None else int(settle_periods)
    if s < 0:
        raise InvalidParameterError(f"settle_periods = {s} must be >= 0")
    n = rec.whole_periods - s if periods is None else int(periods)
    if n < 1 or s + n > rec.whole_periods:
        raise InsufficientDataError(
            f"recording {i} holds {rec.whole_periods} whole periods; {s} settling + {max(n, 1)} averaged "
            "periods do not fit. Record longer or lower settle_periods/periods"
        )
    _check_input(rec, s * p, (s + n) * p)
    ybar = np.asarray(core.periodic_average(np.ascontiguousarray(rec.y), p, s, n))
    noise_var = noise_variance(rec.y, p, s, n)
    k = _harmonics(harmonics, ybar, noise_var, n)
    ydot = np.asarray(core.spectral_derivative(ybar, rec.frequency, k))
    # The averaged window starts at t[0] + s whole periods: the local phase is shifted by omega t[0].
    return _Prepared(
        rec.amplitude,
        rec.frequency,
        rec.frequency * float(rec.t[0]),
        p,
        s,
        n,
        k,
        ybar,
        ydot,
        noise_var,
        p * (n - 1),
        rec.plant,
        rec.metadata.get("name", f"recording {i}"),
    )


def _prepare_averaged(ap: Any, core: Any, harmonics: int | str) -> _Prepared:
    """A period averaged from lab data (any sampling rate): its grid starts at the input's phase zero."""
    ybar = np.ascontiguousarray(ap.ybar, dtype=np.float64)
    k = _harmonics(harmonics, ybar, ap.noise_var, ap.periods)
    ydot = np.asarray(core.spectral_derivative(ybar, ap.frequency, k))
    return _Prepared(
        ap.amplitude,
        ap.frequency,
        0.0,
        ybar.size,
        0,
        float(ap.periods),
        k,
        ybar,
        ydot,
        float(ap.noise_var),
        int(ap.noise_dof),
        None,
        str(ap.source),
    )


def _prepare(
    items: Sequence[Any],
    core: Any,
    settle_periods: Optional[int],
    periods: Optional[int],
    harmonics: int | str,
) -> list[_Prepared]:
    out = []
    for i, item in enumerate(items):
        if isinstance(item, Recording):
            out.append(_prepare_recording(i, item, core, settle_periods, periods, harmonics))
            continue
        # Lab data: imported here so that the paper's path does not pay for the preprocessing modules.
        from .measurement import Measurement
        from .signal import AveragedPeriod, average_measurement

        if isinstance(item, (Measurement, AveragedPeriod)) and (settle_periods, periods) != (None, None):
            raise InvalidParameterError(
                f"item {i}: settle_periods and periods apply to Recordings only; the steady stretch of a "
                "Measurement is detected from the data. To average a chosen stretch, call "
                "signal.find_steady_segments and signal.synchronous_average(..., start=, stop=)"
            )

        if isinstance(item, AveragedPeriod):
            out.append(_prepare_averaged(item, core, harmonics))
        elif isinstance(item, Measurement):
            out.extend(_prepare_averaged(ap, core, harmonics) for ap in average_measurement(item))
        else:
            raise InvalidParameterError(
                f"item {i} is a {type(item).__name__}; identify takes Recording, Measurement or "
                "AveragedPeriod objects"
            )
    if not out:
        raise InsufficientDataError("nothing to identify: no recording gave an averaged period")
    return out


def _loop_fit(
    core: Any, e: _Prepared, gain: float, phi_local: float, beta: float, gamma: float, mu: float
) -> tuple[Optional[FloatArray], float]:
    """The identified model's steady loop on the data grid and its NRMSE against ybar."""
    try:
        w = np.asarray(
            core.steady_loop(e.amplitude * gain, beta, gamma, mu, phi_local, e.p, _steady_substeps(e.p))[0]
        )
    except BoucWenIdError:
        return None, math.nan
    spread = float(np.linalg.norm(e.ybar - e.ybar.mean()))
    return w, float(np.linalg.norm(e.ybar - w)) / spread if spread > 0 else math.nan


def _weights(prepared: Sequence[_Prepared]) -> FloatArray:
    """N / sigma^2 per experiment; the variance is floored at rounding level for noise-free data."""
    out = []
    for e in prepared:
        floor = (1e-13 * float(np.max(np.abs(e.ybar)))) ** 2 + np.finfo(float).tiny
        out.append(e.n / max(e.noise_var, floor))
    return np.array(out)


def _adequacy(
    prepared: Sequence[_Prepared], loops: Sequence[Optional[FloatArray]], n_params: int
) -> Optional[Adequacy]:
    fitted = [w for w in loops if w is not None]
    if len(fitted) != len(loops) or any(not math.isfinite(e.noise_var) for e in prepared):
        return None
    if any(e.noise_var <= (NOISE_FREE_RTOL * float(np.max(np.abs(e.ybar)))) ** 2 for e in prepared):
        # Noise-free (simulated) data: the floor is rounding, and any discretisation error "rejects".
        return None
    # scipy.special, not scipy.stats: the latter takes over a second to import.
    from scipy.special import fdtrc  # type: ignore[import-untyped]

    wts = _weights(prepared)
    statistic = float(sum(wt * np.sum((e.ybar - w) ** 2) for wt, e, w in zip(wts, prepared, fitted)))
    dof = sum(e.p for e in prepared) - n_params
    noise_dof = sum(e.noise_dof for e in prepared)
    if dof < 1:
        return None
    p_value = float(fdtrc(dof, noise_dof, statistic / dof))
    return Adequacy(statistic, dof, noise_dof, p_value)


#: Smallest margin of beta over |gamma| the refinement starts from (no steady loop below 0).
MIN_BETA_PLUS_GAMMA = 1e-3
#: The refinement starts at least this fraction of the mu bracket away from its ends.
START_MU_MARGIN = 1e-2
#: A refined mu closer than this fraction of the bracket to one of its ends is "at the bound".
AT_BOUND_FRACTION = 1e-4
#: Below this noise sd relative to the loop's peak, data count as noise-free (no adequacy test).
NOISE_FREE_RTOL = 1e-9
#: Identifiability alarm: condition number of the Fisher matrix after scaling to unit diagonal.
FISHER_COND_MAX = 1e10
#: Range of output and input scales identify accepts: beyond it, squares of the data leave the
#: floating-point range (s^2 underflows below 1e-154) and s^mu with mu up to 10 overflows past 1e30.
_SCALE_MIN, _SCALE_MAX = 1e-30, 1e30


def identify(
    recordings: Experiment | Sequence[Experiment],
    method: Method = "refined",
    *,
    reference: int = 0,
    settle_periods: Optional[int] = None,
    periods: Optional[int] = None,
    harmonics: int | str = "auto",
    mu_bracket: tuple[float, float] = (1.0, 10.0),
    tol: float = 1e-8,
    phase_grid: int = 48,
    max_iter: int = 200,
    confidence: float = 0.95,
    backend: Backend = "rust",
) -> IdentificationResult:
    """Identify beta, gamma, mu and G(j omega_i) from sine recordings.

    Methods
    -------
    ``"paper"``
        The seed paper exactly: periodic averaging (4a-b), the phase from the time of the averaged
        output's maximum (9), separable least squares for (mu, |G(j omega_1)|, beta, gamma) with
        ``sgn(d ybar/dt)`` in the regressor (18)-(24) on the reference experiment, and the gain (27b)
        at every other frequency.
    ``"profile"``
        The separable fit with the phase as a parameter: the cost (21) is profiled over phi (coarse
        grid, golden refinement), ``sgn(xdot)`` comes from the candidate phase (Proposition 2), and the
        other frequencies get gain and phase by the same profiling of (27b).
    ``"refined"`` (default)
        ``"profile"`` as a start, then a joint output-error fit of every averaged period by
        Levenberg-Marquardt on the steady-state loop (shared beta, gamma, mu; per experiment |G|, phi),
        weighted by N/sigma^2 with the noise variance from the period-to-period spread.  Gives standard
        errors, confidence intervals and an adequacy test.  Needs at least 2 averaged periods.

    Parameters
    ----------
    recordings : Recording or sequence of Recording
        One recording per frequency.  Each needs a whole number of samples per period.
    method : {"refined", "profile", "paper"}
        The estimator (see above).
    reference : int
        Index of the recording used for the separable fit of (beta, gamma, mu) (omega_1 in the paper).
    settle_periods : int, optional
        Leading periods dropped as transient; default: each recording's own ``settle_periods``.
    periods : int, optional
        Periods averaged; default: every whole period after the settling ones.
    harmonics : "auto", "all" or int
        Harmonics K kept in the spectral derivative of the averaged output (used by the separable
        fits).  ``"auto"`` (default) keeps harmonics up to the last one whose power stands 16x above the
        noise floor sigma^2/(N P), all of them when the data are noise-free; ``"all"`` keeps every
        harmonic below Nyquist (the exact derivative of the trigonometric interpolant).
    mu_bracket : (float, float)
        Search interval for mu; the lower end is excluded (mu > 1).
    tol : float
        Final width of the golden-section bracket on mu.
    phase_grid : int
        Coarse phase candidates of the profiled fits.
    max_iter : int
        Levenberg-Marquardt iteration cap (``refined``).
    confidence : float
        Level of the reported confidence intervals.
    backend : {"rust", "numpy"}
        The Rust core (default) or the NumPy reference implementation.

    Returns
    -------
    IdentificationResult

    Raises
    ------
    FrequencyMismatchError, InsufficientDataError, ZeroAmplitudeError, SingularNormalMatrixError,
    SearchAtBoundError, InvalidParameterError, NonFiniteError

    Warns
    -----
    IdentifiabilityWarning
        When the parameters are poorly determined by the data (``refined``).
    """
    if method not in ("paper", "profile", "refined"):
        raise InvalidParameterError(f"method must be 'refined', 'profile' or 'paper', got {method!r}")
    # Counts must be integers (not 0.5, not True) before anything indexes or loops with them.
    counts = (("reference", reference, None), ("phase_grid", phase_grid, 3), ("max_iter", max_iter, 1))
    for name, value, low in counts:
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
            raise InvalidParameterError(f"{name} = {value!r} must be an integer")
        if low is not None and value < low:
            raise InvalidParameterError(f"{name} = {value} must be >= {low}")
    reference, phase_grid, max_iter = int(reference), int(phase_grid), int(max_iter)
    if isinstance(harmonics, str):
        if harmonics not in ("auto", "all"):
            raise InvalidParameterError(f"harmonics = {harmonics!r} must be 'auto', 'all' or an integer >= 1")
    elif isinstance(harmonics, bool) or not isinstance(harmonics, (int, np.integer)) or harmonics < 1:
        raise InvalidParameterError(f"harmonics = {harmonics!r} must be 'auto', 'all' or an integer >= 1")
    if not isinstance(confidence, (int, float, np.floating)) or isinstance(confidence, bool):
        raise InvalidParameterError(f"confidence = {confidence!r} must be a number in (0, 1)")
    if not 0.0 < confidence < 1.0:
        raise InvalidParameterError(f"confidence = {confidence} must be in (0, 1)")
    items: list[Any] = [recordings] if not isinstance(recordings, (list, tuple)) else list(recordings)
    if not items:
        raise InsufficientDataError("no recordings were given")
    lo, hi = (float(v) for v in mu_bracket)
    if not 1.0 <= lo < hi:
        raise InvalidParameterError(f"mu_bracket = {mu_bracket} must satisfy 1 <= lo < hi (mu > 1)")
    core = get_backend(backend)
    prepared = _prepare(items, core, settle_periods, periods, harmonics)
    m = len(prepared)
    if not -m <= reference < m:
        raise InvalidParameterError(f"reference = {reference} is not an index of the {m} experiments")
    reference = reference % m
    # Work in units where the output and the input are of order one (forces of 1500 N and strokes of
    # 5 mm fit as well as unit-scale data), then map back: with y = s_y y', u = s_u u',
    # |G| = |G'| s_y / s_u, beta = beta' / s_y^mu, gamma = gamma' / s_y^mu.
    s_y = max(float(np.max(np.abs(e.ybar))) for e in prepared) or 1.0
    s_u = max(abs(e.amplitude) for e in prepared)
    for what, scale in (("output", s_y), ("input amplitude", s_u)):
        # Squares and powers of the scales must stay inside the floating-point range.
        if not _SCALE_MIN <= scale <= _SCALE_MAX:
            raise ZeroAmplitudeError(
                f"the {what} is of size {scale:.3e}, outside [{_SCALE_MIN:g}, {_SCALE_MAX:g}]: "
                "express the data in units that keep it there (e.g. mm instead of km)"
            )
    scaled = [
        dataclasses.replace(
            e,
            amplitude=e.amplitude / s_u,
            ybar=e.ybar / s_y,
            ydot=e.ydot / s_y,
            noise_var=e.noise_var / s_y**2,
        )
        for e in prepared
    ]
    try:
        fit = _fit(scaled, core, method, reference, lo, hi, tol, phase_grid, max_iter)
    except SearchAtBoundError as exc:
        if not (exc.lower and exc.bound is not None and exc.bound <= 1.0):
            raise
        # mu = 1 is the model's own limit, so "widen the bracket" is no advice here: say what it means.
        err = SearchAtBoundError(
            "the fit drove mu to 1, the lower end of the model's range (mu > 1): the data turn at each "
            "reversal in a way no Bouc-Wen loop with mu > 1 draws (typically a force that jumps at the "
            "reversal, as Coulomb friction, or keeps growing with velocity, as viscous damping beside "
            "friction in MR dampers). The plain Wiener-Bouc-Wen model does not describe these data; the "
            "physics it leaves out must be modelled"
        )
        err.lower, err.bound = exc.lower, exc.bound
        raise err from exc
    beta, gamma, mu = fit.beta / s_y**fit.mu, fit.gamma / s_y**fit.mu, fit.mu
    gains = fit.gains * (s_y / s_u)
    cov = None
    se_shared = None
    if fit.cov is not None:
        # Delta method through the back-transformation (beta and gamma depend on mu through s_y^mu).
        jac = np.eye(3 + 2 * m)
        jac[0, 0] = jac[1, 1] = s_y**-fit.mu
        jac[0, 2] = -beta * math.log(s_y)
        jac[1, 2] = -gamma * math.log(s_y)
        jac[3::2, 3::2] *= s_y / s_u
        cov = jac @ fit.cov @ jac.T
        se_all = np.sqrt(np.abs(np.diag(cov)))
        se_shared = {"beta": float(se_all[0]), "gamma": float(se_all[1]), "mu": float(se_all[2])}

    experiments = []
    for i, e in enumerate(prepared):
        # (G, phi) and (-G, phi + pi) draw the same x = U G cos(omega t - phi): report |G| > 0.  The
        # phase is that of G itself, whatever the sign of U.
        phase = fit.phis[i] + e.phase_shift
        if gains[i] < 0:
            phase += math.pi
        loop = fit.loops[i]
        w = None if loop is None else np.asarray(loop * s_y, dtype=np.float64)
        spread = float(np.linalg.norm(e.ybar - e.ybar.mean()))
        nrmse = float(np.linalg.norm(e.ybar - w)) / spread if w is not None and spread > 0 else math.nan
        experiments.append(
            ExperimentEstimate(
                frequency=e.frequency,
                amplitude=e.amplitude,
                gain=abs(float(gains[i])),
                phase=float(wrap_phase(phase)),
                samples_per_period=e.p,
                settle_periods=e.s,
                periods=e.n,
                harmonics=e.k,
                ybar=e.ybar,
                noise_sd=math.sqrt(e.noise_var) if math.isfinite(e.noise_var) else math.nan,
                gain_se=None if cov is None else float(math.sqrt(abs(cov[3 + 2 * i, 3 + 2 * i]))),
                phase_se=None if cov is None else float(math.sqrt(abs(cov[4 + 2 * i, 4 + 2 * i]))),
                nrmse=nrmse,
                linear_nrmse=_linear_nrmse(e.ybar),
                model=w,
                source=e.source,
                grid_phase=float(wrap_phase(e.phase_shift)),
            )
        )

    notes = _identifiability(beta, gamma, mu, experiments, cov, se_shared, confidence)
    if method == "refined" and beta - abs(gamma) <= _ON_CONSTRAINT_RTOL * max(abs(beta), abs(gamma), 1e-300):
        face = "beta = gamma" if gamma > 0 else "beta = -gamma"
        notes.append(
            f"the fit ends on the Bouc-Wen constraint {face} (beta = {beta:.4g}, gamma = {gamma:.4g}): the "
            "data pull beyond the loops the model can draw, so the intervals of beta and gamma do not hold "
            "there; judge the model by the NRMSE and the adequacy test, not by these parameters"
        )
    worse = [e.source or f"experiment {i}" for i, e in enumerate(experiments) if e.nrmse > e.linear_nrmse]
    if worse:
        notes.append(
            f"the fitted loops explain {', '.join(worse)} less well than a linear spring + dashpot (NRMSE "
            "above linear_nrmse): the hysteresis model adds nothing there"
        )
    if not (beta >= abs(gamma) and beta + gamma > 0):
        notes.append(
            f"the estimates violate the Bouc-Wen conditions beta >= |gamma|, beta + gamma > 0 (beta = "
            f"{beta:.4g}, gamma = {gamma:.4g}): the data do not support this model, or the mu bracket "
            "excludes the truth; method='refined' keeps the fit inside the conditions"
        )
    for note in notes:
        warnings.warn(note, IdentifiabilityWarning, stacklevel=2)
    if fit.converged is False:
        warnings.warn(
            f"the joint fit stopped at max_iter = {max_iter} iterations before meeting its tolerances: the "
            "estimates and their intervals are those of an unfinished fit; raise max_iter",
            ConvergenceWarning,
            stacklevel=2,
        )
    plants = [e.plant for e in prepared]
    truth = None
    first = plants[0]
    if first is not None and all(pl is not None and pl.to_dict() == first.to_dict() for pl in plants):
        truth = Truth.from_plant(first, np.array([e.frequency for e in experiments]))
    settings = {
        "settle_periods": settle_periods,
        "periods": periods,
        "harmonics": harmonics,
        "mu_bracket": [lo, hi],
        "tol": tol,
        "phase_grid": phase_grid,
        "max_iter": max_iter,
        "scales": {"y": s_y, "u": s_u},
    }
    return IdentificationResult(
        method=method,
        backend=backend,
        beta=float(beta),
        gamma=float(gamma),
        mu=float(mu),
        cost=float(fit.cost),
        iterations=int(fit.iterations),
        reference=reference,
        experiments=tuple(experiments),
        settings=settings,
        truth=truth,
        standard_errors=se_shared,
        covariance=cov,
        adequacy=_adequacy(
            prepared, [None if w is None else w for w in (ex.model for ex in experiments)], 3 + 2 * m
        ),
        warnings=tuple(notes),
        confidence=confidence,
        converged=fit.converged,
    )


@dataclass
class _Fit:
    """Estimates in the scaled units the estimators worked in."""

    beta: float
    gamma: float
    mu: float
    gains: FloatArray
    phis: FloatArray
    cost: float
    iterations: int
    cov: Optional[FloatArray]
    loops: list[Optional[FloatArray]]
    #: Whether the iterative fit met its tolerances (None for the direct estimators).
    converged: Optional[bool] = None


def _fit(
    prepared: Sequence[_Prepared],
    core: Any,
    method: str,
    reference: int,
    lo: float,
    hi: float,
    tol: float,
    phase_grid: int,
    max_iter: int,
) -> _Fit:
    """Run the chosen estimator; phases are local (relative to each averaged window's first sample)."""
    m = len(prepared)
    phis = np.zeros(m)
    gains = np.zeros(m)
    ref = prepared[reference]
    if method == "paper":
        phis = np.array([float(core.phase_from_max(e.ybar)) for e in prepared])
        mu, theta, cost, iterations = core.sls_search(
            ref.ybar, ref.ydot, ref.amplitude, ref.frequency, phis[reference], lo, hi, tol
        )
        theta = np.asarray(theta)
        beta, gamma = float(theta[1] / theta[0]), float(theta[2] / theta[0])
        for i, e in enumerate(prepared):
            gains[i] = (
                float(theta[0])
                if i == reference
                else float(
                    core.gain_estimate(e.ybar, e.ydot, e.amplitude, e.frequency, phis[i], beta, gamma, mu)
                )
            )
    else:
        try:
            phi_r, mu, g_r, beta, gamma, cost, _ = core.profile_phase_sls(
                ref.ybar, ref.ydot, ref.amplitude, ref.frequency, lo, hi, tol, phase_grid
            )
        except SearchAtBoundError as exc:
            # The separable fit is only the refinement's start: when it runs to mu's lower end, the
            # output-error fit still gets its chance from generic starts (and is refused only if it
            # ends there too).
            if method != "refined" or not exc.lower:
                raise
            return _refine(prepared, core, None, lo, hi, max_iter, profile_error=exc)
        iterations = 0
        for i, e in enumerate(prepared):
            if i == reference:
                gains[i], phis[i] = g_r, phi_r
            else:
                gains[i], phis[i], _ = core.profile_phase_gain(
                    e.ybar, e.ydot, e.amplitude, e.frequency, beta, gamma, mu, phase_grid
                )
    mu = float(mu)
    if method != "refined":
        loops = [_loop_fit(core, e, gains[i], phis[i], beta, gamma, mu)[0] for i, e in enumerate(prepared)]
        return _Fit(beta, gamma, mu, gains, phis, float(cost), int(iterations), None, loops)

    return _refine(prepared, core, (float(beta), float(gamma), mu, gains, phis), lo, hi, max_iter)


#: Generic starts of the joint fit (see :func:`_generic_starts`): mu values, gamma/beta ratios, and the
#: depth of saturation A / w_sat.
_START_MUS = (1.15, 1.6, 2.5, 5.0)
_START_RATIOS = (0.5, -0.5)
_START_DEPTHS = (1.5, 4.0)
#: LM iterations of each generic start's screening fit (the best one is then run to convergence).
_SCREEN_ITER = 25
#: Assumed lag (rad) of the loop's fundamental behind x for the generic starts.
_START_LAG = 0.3
#: A fit is checked from the generic starts when it ends this close (relative) to beta = |gamma|.
_ON_CONSTRAINT_RTOL = 1e-6


def _fundamental(ybar: FloatArray) -> complex:
    """``c`` with ``ybar`` ~ Re(c exp(i 2 pi j / P)): the averaged output's first harmonic."""
    return complex(2.0 * np.fft.rfft(ybar)[1] / ybar.size)


def _linear_residual(ybar: FloatArray) -> FloatArray:
    """``ybar`` minus its fundamental: the residual of the best linear (spring + dashpot) model."""
    theta = TWO_PI * np.arange(ybar.size) / ybar.size
    out: FloatArray = ybar - np.real(_fundamental(ybar) * np.exp(1j * theta))
    return out


def _linear_nrmse(ybar: FloatArray) -> float:
    """NRMSE of ybar's fundamental alone (the best linear model) against ybar, as ``nrmse``."""
    spread = float(np.linalg.norm(ybar - ybar.mean()))
    if spread == 0.0:
        return math.nan
    return float(np.linalg.norm(_linear_residual(ybar))) / spread


def _linear_cost(prepared: Sequence[_Prepared], weights: FloatArray) -> float:
    """The weighted cost of the best linear (spring + dashpot) model: each ybar's fundamental alone.

    A Bouc-Wen loop driven far below saturation is x itself, of any amplitude and phase, so the joint
    fit can always reach this cost; a fit above it sits in a wrong basin.
    """
    return sum(float(wt) * float(np.sum(_linear_residual(e.ybar) ** 2)) for e, wt in zip(prepared, weights))


def _generic_starts(
    prepared: Sequence[_Prepared], lo: float, hi: float
) -> list[tuple[float, float, float, FloatArray, FloatArray]]:
    """Starting points spread over the shapes a Bouc-Wen loop can take, scaled to the data.

    The saturation level ``w_sat = (beta + gamma)^(-1/mu)`` is set a little above the largest averaged
    output; each experiment's x reaches ``depth`` times its loop's amplitude, with the phase of its
    fundamental less a typical hysteretic lag.
    """
    fund = [_fundamental(e.ybar) for e in prepared]
    peak = max(max(float(np.max(np.abs(e.ybar))) for e in prepared), 1e-300)
    margin = START_MU_MARGIN * (hi - lo)
    starts = []
    for mu in _START_MUS:
        mu = min(max(mu, lo + margin), hi - margin)
        total = (1.1 * peak) ** (-mu)
        for ratio in _START_RATIOS:
            beta = total / (1.0 + ratio)
            gamma = ratio * beta
            for depth in _START_DEPTHS:
                gains = np.array([depth * 1.1 * abs(c) / e.amplitude for c, e in zip(fund, prepared)])
                phis = np.array([-math.atan2(c.imag, c.real) - _START_LAG for c in fund])
                starts.append((beta, gamma, mu, gains, phis))
    return starts


def _refine(
    prepared: Sequence[_Prepared],
    core: Any,
    start: Optional[tuple[float, float, float, FloatArray, FloatArray]],
    lo: float,
    hi: float,
    max_iter: int,
    profile_error: Optional[SearchAtBoundError] = None,
) -> _Fit:
    """The joint output-error fit from ``start`` (the profile estimates), safeguarded by generic starts.

    The generic starts run when there is no profile start (its mu ran to the lower bound), or when the
    fit from it ends on the Bouc-Wen constraint beta = |gamma| or costs more than the best linear model
    (both signs of a wrong basin); the lowest cost wins.
    """
    m = len(prepared)
    short = [e.source for e in prepared if e.n < 2]
    if short:
        raise InsufficientDataError(
            f"method='refined' estimates the noise floor from the period-to-period spread and needs at "
            f"least 2 averaged periods; {', '.join(short)} have fewer. Use method='paper' or record longer"
        )
    weights = _weights(prepared)
    substeps = max(_steady_substeps(e.p) for e in prepared)
    margin = START_MU_MARGIN * (hi - lo)

    def run(
        beta: float, gamma: float, mu: float, gains: FloatArray, phis: FloatArray, iters: int = max_iter
    ) -> Optional[Any]:
        # The separable fit knows nothing of the Bouc-Wen conditions (beta >= |gamma|) and a loop too
        # linear to fix beta + gamma can put it outside them, where no steady loop exists: start the
        # joint fit just inside, and within the mu bracket, and let the data speak.
        beta = max(beta, abs(gamma) + MIN_BETA_PLUS_GAMMA)
        mu = min(max(mu, lo + margin), hi - margin)
        try:
            return core.refine(
                [e.ybar for e in prepared],
                [e.amplitude for e in prepared],
                weights,
                beta,
                gamma,
                mu,
                gains,
                phis,
                max_iter=iters,
                substeps=substeps,
                mu_lo=lo,
                mu_hi=hi,
            )
        except BoucWenIdError:
            if start is None:
                return None  # a generic start that is no valid loop: the others decide
            raise

    best = None if start is None else run(*start)
    linear = _linear_cost(prepared, weights)

    def suspicious(out: Any) -> bool:
        b, g = (float(v) for v in np.asarray(out[0])[:2])
        on_constraint = b - abs(g) <= _ON_CONSTRAINT_RTOL * max(abs(b), abs(g), 1e-300)
        return on_constraint or float(out[1]) > linear

    if best is None or suspicious(best):
        # Screen every generic start with a short fit, then finish the most promising one.
        screened = None
        for candidate in _generic_starts(prepared, lo, hi):
            out = run(*candidate, iters=min(_SCREEN_ITER, max_iter))
            if out is not None and (screened is None or float(out[1]) < float(screened[1])):
                screened = out
        if screened is not None and (best is None or float(screened[1]) < float(best[1])):
            par = np.asarray(screened[0])
            final = run(float(par[0]), float(par[1]), float(par[2]), par[3::2].copy(), par[4::2].copy())
            best = final if final is not None and float(final[1]) <= float(screened[1]) else screened
    if best is None:
        if profile_error is not None:
            raise profile_error
        raise SearchAtBoundError("no start of the joint fit gave a valid steady loop")
    params, cost, iterations, converged, fisher, loops = best
    params = np.asarray(params)
    beta, gamma, mu = (float(v) for v in params[:3])
    if min(mu - lo, hi - mu) <= AT_BOUND_FRACTION * (hi - lo):
        lower = mu - lo <= hi - mu
        err = SearchAtBoundError(
            f"the joint fit ended on the {'lower' if lower else 'upper'} end of the mu bracket "
            f"[{lo}, {hi}] (mu = {mu:.6g}); widen the bracket, or check that the data excite the "
            "hysteresis"
        )
        err.lower, err.bound = lower, lo if lower else hi
        raise err
    gains = params[3::2].copy()
    phis = params[4::2].copy()
    fisher = np.asarray(fisher)
    # Flip the sign of g_i rows/columns where the canonical branch (|G| > 0) is reported.
    flip = np.ones(3 + 2 * m)
    flip[3::2] = np.where(gains < 0, -1.0, 1.0)
    fisher = fisher * np.outer(flip, flip)
    try:
        cov = np.linalg.inv(fisher)
    except np.linalg.LinAlgError:
        cov = np.full_like(fisher, np.nan)
    return _Fit(
        beta,
        gamma,
        mu,
        gains,
        phis,
        float(cost),
        int(iterations),
        cov,
        [np.asarray(w) for w in loops],
        bool(converged),
    )


def _identifiability(
    beta: float,
    gamma: float,
    mu: float,
    experiments: Sequence[ExperimentEstimate],
    cov: Optional[FloatArray],
    se: Optional[dict[str, float]],
    confidence: float,
) -> list[str]:
    """Plain-language warnings when the data do not pin the parameters down."""
    if cov is None or se is None:
        return []
    notes = []
    if not np.all(np.isfinite(cov)):
        return ["the Fisher information is singular: some parameters are not identifiable from these data"]
    d = np.sqrt(np.abs(np.diag(cov)))
    corr = cov / np.outer(d, d)
    cond = float(np.linalg.cond(corr))
    if cond > FISHER_COND_MAX:
        notes.append(
            f"the Fisher information is ill-conditioned (condition number {cond:.2g} after scaling): "
            "very different parameter sets draw nearly the same loops; check the loop-fit NRMSE rather "
            "than the individual parameters"
        )
    z = _z(confidence)
    wide = [name for name, v in (("beta", beta), ("gamma", gamma), ("mu", mu)) if z * se[name] > abs(v)]
    wide += [
        f"|G(j{e.frequency:g})|" for e in experiments if e.gain_se is not None and z * e.gain_se > e.gain
    ]
    if wide:
        notes.append(
            f"the {confidence:.0%} intervals of {', '.join(wide)} are wider than the values themselves: "
            "these parameters are poorly identifiable from these data (more periods, amplitudes that "
            "reach saturation, or less noise would help)"
        )
    return notes
