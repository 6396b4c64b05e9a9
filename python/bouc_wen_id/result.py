"""What an identification returns: the result, one estimate per experiment, the truth, the adequacy test.

Frozen records with a readable ``repr``, a ``summary()`` table, ``to_dict``/``to_json`` (format
``bouc_wen_id.result``, version 1) and plots (:mod:`~bouc_wen_id.plotting`, imported when called).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import NDArray

from ._text import Summarised, with_warnings
from .errors import InvalidParameterError
from .model import WienerPlant
from .validation import z_value

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

    from .tfit import TransferFunctionFit

__all__ = [
    "IdentificationResult",
    "ExperimentEstimate",
    "Truth",
    "Adequacy",
    "wrap_phase",
    "phase_error",
]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: What a refinement that hit its iteration cap means, for the summary and the warning.
NOT_CONVERGED = (
    "the Levenberg-Marquardt refinement stopped at its cap of {iterations} iterations before converging: "
    "the estimates and their intervals are those of an unfinished fit; raise max_iter"
)


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
    #: The output's offset (its mean over the averaged window), removed before the fit: the model's loop
    #: has none.
    offset: float = 0.0

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
            "offset": _num(self.offset),
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
class IdentificationResult(Summarised):
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
        ``refined``: whether the Levenberg-Marquardt run the estimates come from converged before
        ``max_iter`` (``False`` is also issued as :class:`ConvergenceWarning`); None for the other methods.
    units : dict
        The units of ``u`` and ``y`` the recordings stated (``{"u": "mm", "y": "N"}``; empty: none): the
        model holds in them (``validate`` converts or refuses records in others).
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
    units: dict[str, str] = field(default_factory=dict)

    def interval(self, name: str) -> tuple[float, float]:
        """Confidence interval (at ``self.confidence``) of ``beta``, ``gamma`` or ``mu``.

        Raises
        ------
        InvalidParameterError
            When the method gives no uncertainty (only ``method="refined"`` does).
        """
        if self.standard_errors is None:
            raise InvalidParameterError(f"method={self.method!r} gives no uncertainty; use method='refined'")
        z = z_value(self.confidence)
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
        z = z_value(self.confidence)
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
        if self.converged is False:
            lines.append(f"  warning: {NOT_CONVERGED.format(iterations=self.iterations)}")
        return with_warnings(lines, self.warnings)

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
            "converged": self.converged,
            "units": dict(self.units),
        }
        if self.truth is not None:
            err = self.errors()
            out["errors"] = {
                k: (v.tolist() if isinstance(v, np.ndarray) else float(v)) for k, v in err.items()
            }
        return out

    def to_json(self, indent: int = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    def to_dataframe(self) -> Any:
        """The frequency-response points as a :class:`pandas.DataFrame` (needs the ``pandas`` extra).

        One row per experiment (index ``experiment``, in input order): ``frequency`` (rad/s),
        ``frequency_hz``, ``amplitude``, ``gain`` (alpha-normalised ``|G|``), ``gain_se``, ``gain_low``,
        ``gain_high``, ``phase`` (rad, ``phi = -angle G``), ``phase_se``, ``phase_low``, ``phase_high``
        (the bounds at ``confidence``; NaN, like the SEs, for methods without uncertainty), ``offset``,
        ``noise_sd``, ``nrmse``, ``linear_nrmse``, ``periods``, ``samples_per_period``,
        ``settle_periods``, ``harmonics``, ``source``; with a known truth also ``gain_true`` and
        ``phase_true``.

        What the experiments share sits in ``df.attrs`` (a flat dict, kept by copies of the frame but not
        by every pandas operation): ``beta``, ``gamma``, ``mu``, their ``*_se``, ``*_low``, ``*_high``
        (NaN without uncertainty), ``confidence``, ``method``, ``backend``, ``reference``, ``cost``,
        ``converged`` and ``warnings``.  :meth:`to_dict` holds all of it too, with the covariance.
        """
        from . import _optional

        pd = _optional.require("pandas", "IdentificationResult.to_dataframe")
        z = z_value(self.confidence)
        rows = []
        for e in self.experiments:
            g_se, p_se = _nan(e.gain_se), _nan(e.phase_se)
            rows.append(
                {
                    "frequency": e.frequency,
                    "frequency_hz": e.frequency / TWO_PI,
                    "amplitude": e.amplitude,
                    "gain": e.gain,
                    "gain_se": g_se,
                    "gain_low": e.gain - z * g_se,
                    "gain_high": e.gain + z * g_se,
                    "phase": e.phase,
                    "phase_se": p_se,
                    "phase_low": e.phase - z * p_se,
                    "phase_high": e.phase + z * p_se,
                    "offset": e.offset,
                    "noise_sd": e.noise_sd,
                    "nrmse": e.nrmse,
                    "linear_nrmse": e.linear_nrmse,
                    "periods": e.periods,
                    "samples_per_period": e.samples_per_period,
                    "settle_periods": e.settle_periods,
                    "harmonics": e.harmonics,
                    "source": e.source,
                }
            )
        df = pd.DataFrame(rows, index=pd.RangeIndex(len(rows), name="experiment"))
        if self.truth is not None:
            df["gain_true"] = np.asarray(self.truth.gain, dtype=np.float64)
            df["phase_true"] = np.asarray(self.truth.phase, dtype=np.float64)
        shared: dict[str, Any] = {}
        for name in ("beta", "gamma", "mu"):
            v = float(getattr(self, name))
            se = _nan(None if self.standard_errors is None else self.standard_errors.get(name))
            shared.update({name: v, f"{name}_se": se, f"{name}_low": v - z * se, f"{name}_high": v + z * se})
        shared.update(
            {
                "confidence": self.confidence,
                "method": self.method,
                "backend": self.backend,
                "reference": self.reference,
                "cost": self.cost,
                "converged": self.converged,
                "warnings": list(self.warnings),
            }
        )
        df.attrs.update(shared)
        return df

    def plot_loop(self, experiment: Optional[int] = None, ax: Optional[Axes] = None) -> Figure:
        """Plot the averaged loop ybar against the identified x (all experiments, or one)."""
        from .plotting import plot_loop

        return plot_loop(self, experiment=experiment, ax=ax)

    def plot_bode(self, axes: Optional[Sequence[Axes]] = None) -> Figure:
        """Plot the identified |G(j omega_i)| and phi(omega_i) points, against the truth when known."""
        from .plotting import plot_bode

        return plot_bode(self, axes=axes)

    # Issue #11 parts 1-2: a parametric G(s) from the points, and the points for python-control.
    def fit_transfer_function(self, **options: Any) -> TransferFunctionFit:
        """A stable, proper G(s) fitted to these points (:func:`bouc_wen_id.tfit.fit_transfer_function`)."""
        from .tfit import fit_transfer_function

        return fit_transfer_function(self, **options)

    def to_frd(self) -> Any:
        """The points as a ``control.FRD`` (:func:`bouc_wen_id.interop.to_frd`; needs the control extra)."""
        from .interop import to_frd

        return to_frd(self)


def _rel(est: float, true: float) -> str:
    return f"{(est - true) / abs(true):.2e}" if true != 0 else "-"


def _fmt(v: Optional[float]) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.3g}"


def _nan(v: Optional[float]) -> float:
    """None (no uncertainty) as NaN, for numeric table columns."""
    return math.nan if v is None else float(v)


def _num(v: Optional[float]) -> Optional[float]:
    """JSON has no NaN: unknown values are written as null."""
    return None if v is None or not math.isfinite(v) else float(v)


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
