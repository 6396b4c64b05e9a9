"""Identification of a Wiener-Bouc-Wen system from sine recordings (the paper's method, Section 3)."""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal, Optional

import numpy as np
from numpy.typing import NDArray

from ._backend import Backend, get_backend
from .errors import (
    FrequencyMismatchError,
    InsufficientDataError,
    InvalidParameterError,
)
from .model import Recording, WienerPlant, as_recordings

if TYPE_CHECKING:  # pragma: no cover - typing only
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["identify", "IdentificationResult", "ExperimentEstimate", "Truth", "Method"]

FloatArray = NDArray[np.float64]
Method = Literal["paper"]

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
    periods: int
    harmonics: int
    ybar: FloatArray = field(repr=False)

    @property
    def response(self) -> complex:
        """``G(j omega) = |G| exp(-j phi)`` (alpha-normalised)."""
        return complex(self.gain * np.exp(-1j * self.phase))

    def model_input(self) -> FloatArray:
        """The steady ``x(t) = U |G| cos(omega t - phi)`` on the averaged period's grid."""
        t = np.arange(self.samples_per_period) * (TWO_PI / self.frequency / self.samples_per_period)
        out: FloatArray = self.amplitude * self.gain * np.cos(self.frequency * t - self.phase)
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
        The separable least-squares cost I_N(mu) of (21) on the reference experiment.
    experiments : tuple of ExperimentEstimate
        One frequency-response point per recording, in input order.
    reference : int
        Index of the experiment used for (beta, gamma, mu).
    truth : Truth or None
        The simulated plant's values when every recording carries the same plant.
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
        """A plain-text table of the estimates (and the truth, when known)."""
        tr = self.truth
        lines = [f"Wiener-Bouc-Wen identification (method={self.method}, backend={self.backend})"]
        lines.append(
            f"  reference experiment {self.reference}, {self.iterations} golden-section iterations, "
            f"cost I_N(mu) = {self.cost:.4g}"
        )
        head = f"  {'parameter':<12}{'estimate':>13}"
        if tr is not None:
            head += f"{'truth':>13}{'error':>12}{'rel.err':>10}"
        lines.append(head)
        scal = [("beta", self.beta), ("gamma", self.gamma), ("mu", self.mu)]
        for name, val in scal:
            row = f"  {name:<12}{val:>13.6g}"
            if tr is not None:
                t = float(getattr(tr, name))
                row += f"{t:>13.6g}{val - t:>12.3g}{_rel(val, t):>10}"
            lines.append(row)
        lines.append("")
        head = f"  {'omega':>9}{'U':>8}{'|G| est':>11}{'phi est':>10}"
        if tr is not None:
            head += f"{'|G| true':>11}{'phi true':>10}{'|G| rel.err':>12}{'phi err':>10}"
        head += f"{'P':>6}{'N':>5}"
        lines.append(head)
        for i, e in enumerate(self.experiments):
            row = f"  {e.frequency:>9.4g}{e.amplitude:>8.3g}{e.gain:>11.5g}{e.phase:>10.4f}"
            if tr is not None:
                dphi = float(phase_error(e.phase, tr.phase[i]))
                row += (
                    f"{tr.gain[i]:>11.5g}{tr.phase[i]:>10.4f}{_rel(e.gain, float(tr.gain[i])):>12}"
                    f"{dphi:>10.2e}"
                )
            row += f"{e.samples_per_period:>6}{e.periods:>5}"
            if i == self.reference:
                row += "  (reference)"
            lines.append(row)
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


def _check_input(rec: Recording, start: int, stop: int) -> None:
    """Refuse a recording whose ``u`` is not ``U cos(omega t)`` on its own time axis."""
    t = rec.t[start:stop]
    u = rec.u[start:stop]
    basis = np.column_stack([np.cos(rec.frequency * t), np.sin(rec.frequency * t), np.ones_like(t)])
    coef, *_ = np.linalg.lstsq(basis, u, rcond=None)
    spread = float(np.linalg.norm(u - u.mean()))
    misfit = float(np.linalg.norm(u - basis @ coef)) / spread if spread > 0 else math.inf
    if misfit > INPUT_MISFIT_MAX:
        raise FrequencyMismatchError(
            f"the recorded input is not a sine at omega = {rec.frequency:.6g} rad/s "
            f"(relative misfit {misfit:.2g} > {INPUT_MISFIT_MAX}); check the stated frequency and its units"
        )
    amp = float(math.hypot(coef[0], coef[1]))
    if abs(amp - abs(rec.amplitude)) > INPUT_MISFIT_MAX * abs(rec.amplitude):
        raise InvalidParameterError(
            f"the stated amplitude U = {rec.amplitude:.6g} does not match the recorded input's {amp:.6g}"
        )
    phase = math.atan2(coef[1], coef[0] * np.sign(rec.amplitude))
    if abs(phase) > INPUT_PHASE_MAX:
        raise InvalidParameterError(
            f"the recorded input is U cos(omega t - {phase:.3g}) rather than U cos(omega t) on its time "
            "axis; shift the time column so that the input peaks at t = 0"
        )


def identify(
    recordings: Recording | Sequence[Recording],
    method: Method = "paper",
    *,
    reference: int = 0,
    settle_periods: Optional[int] = None,
    periods: Optional[int] = None,
    harmonics: Optional[int] = None,
    mu_bracket: tuple[float, float] = (1.0, 10.0),
    tol: float = 1e-8,
    backend: Backend = "rust",
) -> IdentificationResult:
    """Identify beta, gamma, mu and G(j omega_i) from sine recordings.

    ``method="paper"`` runs the seed paper's estimators: periodic averaging (4a-b), the phase from the
    time of the averaged output's maximum (9), separable least squares for (mu, |G(j omega_1)|, beta,
    gamma) on the reference experiment (18)-(24), and the gain (27b) at every other frequency.

    Parameters
    ----------
    recordings : Recording or sequence of Recording
        One recording per frequency.  Each needs a whole number of samples per period.
    method : {"paper"}
        The estimator.
    reference : int
        Index of the recording used for the hysteresis parameters (omega_1 in the paper).
    settle_periods : int, optional
        Leading periods dropped as transient; default: each recording's own ``settle_periods``.
    periods : int, optional
        Periods averaged; default: every whole period after the settling ones.
    harmonics : int, optional
        Harmonics K kept in the spectral derivative of the averaged output.  Default: every harmonic
        below Nyquist, ``floor((P - 1) / 2)``, i.e. the exact derivative of the trigonometric interpolant.
        Fewer harmonics smooth noise at the price of a truncation bias.
    mu_bracket : (float, float)
        Search interval for mu; the lower end is excluded (mu > 1).
    tol : float
        Final width of the golden-section bracket on mu.
    backend : {"rust", "numpy"}
        The Rust core (default) or the NumPy reference implementation.

    Returns
    -------
    IdentificationResult

    Raises
    ------
    FrequencyMismatchError, InsufficientDataError, ZeroAmplitudeError, SingularNormalMatrixError,
    SearchAtBoundError, InvalidParameterError, NonFiniteError
    """
    if method != "paper":
        raise InvalidParameterError(f"method must be 'paper', got {method!r}")
    recs = as_recordings(recordings)
    if not -len(recs) <= reference < len(recs):
        raise InvalidParameterError(f"reference = {reference} is not an index of the {len(recs)} recordings")
    reference = reference % len(recs)
    lo, hi = (float(v) for v in mu_bracket)
    if not 1.0 <= lo < hi:
        raise InvalidParameterError(f"mu_bracket = {mu_bracket} must satisfy 1 <= lo < hi (mu > 1)")
    core = get_backend(backend)

    prepared = []
    for i, rec in enumerate(recs):
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
        k = (p - 1) // 2 if harmonics is None else int(harmonics)
        ybar = np.asarray(core.periodic_average(np.ascontiguousarray(rec.y), p, s, n))
        # The averaged window starts at t[0] + s periods; its local phase is shifted by omega t[0].
        phi_local = float(core.phase_from_max(ybar))
        ydot = np.asarray(core.spectral_derivative(ybar, rec.frequency, k))
        prepared.append((rec, p, s, n, k, ybar, ydot, phi_local))

    rec, p, s, n, k, ybar, ydot, phi1 = prepared[reference]
    mu, theta, cost, iterations = core.sls_search(ybar, ydot, rec.amplitude, rec.frequency, phi1, lo, hi, tol)
    theta = np.asarray(theta)
    beta = float(theta[1] / theta[0])
    gamma = float(theta[2] / theta[0])

    experiments = []
    for i, (rec, p, s, n, k, ybar, ydot, phi_local) in enumerate(prepared):
        if i == reference:
            gain = float(theta[0])
        else:
            gain = float(
                core.gain_estimate(ybar, ydot, rec.amplitude, rec.frequency, phi_local, beta, gamma, mu)
            )
        # (G, phi) and (-G, phi + pi) draw the same x: report the one with |G| > 0.  A negative U is
        # folded in the same way, so that the table always reads against u = |U| cos(omega t).
        phase = phi_local + rec.frequency * float(rec.t[0])
        if gain * rec.amplitude < 0:
            phase += math.pi
        experiments.append(
            ExperimentEstimate(
                frequency=rec.frequency,
                amplitude=abs(rec.amplitude),
                gain=abs(gain),
                phase=float(wrap_phase(phase)),
                samples_per_period=p,
                settle_periods=s,
                periods=n,
                harmonics=k,
                ybar=ybar,
            )
        )

    plants = [r.plant for r in recs]
    truth = None
    if plants[0] is not None and all(pl is not None and pl.to_dict() == plants[0].to_dict() for pl in plants):
        truth = Truth.from_plant(plants[0], np.array([e.frequency for e in experiments]))
    settings = {
        "settle_periods": settle_periods,
        "periods": periods,
        "harmonics": harmonics,
        "mu_bracket": [lo, hi],
        "tol": tol,
    }
    return IdentificationResult(
        method=method,
        backend=backend,
        beta=beta,
        gamma=gamma,
        mu=float(mu),
        cost=float(cost),
        iterations=int(iterations),
        reference=reference,
        experiments=tuple(experiments),
        settings=settings,
        truth=truth,
    )
