"""Identification of a Wiener-Bouc-Wen system from sine experiments (the paper's method, Section 3).

:func:`identify` reads as its steps: check the arguments, prepare each experiment (:mod:`.prepare`), scale
to units of order one, run the estimator (:mod:`.estimators`), map the estimates back with their
covariance, build one :class:`~bouc_wen_id.result.ExperimentEstimate` per experiment, note what the data do
not support, and return an :class:`~bouc_wen_id.result.IdentificationResult` (:mod:`.result`).

Each experiment is reduced to one averaged period (:mod:`bouc_wen_id.prepare`): a
:class:`~bouc_wen_id.model.Recording` by the paper's periodic average (4a-b), a
:class:`~bouc_wen_id.measurement.Measurement` by the synchronous average of each of its steady segments
(:func:`bouc_wen_id.signal.average_segments`; one experiment per segment), an
:class:`~bouc_wen_id.signal.AveragedPeriod` as it is.  The data are scaled to units of order one, the
estimator runs (:mod:`bouc_wen_id.estimators`), and the estimates are mapped back with their covariance.

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
    weighted by N/sigma^2 with the noise variance from the period-to-period spread.  When the profile
    start runs mu to 1, or the fit ends on the constraint beta = |gamma| or costs more than a linear
    spring + dashpot, generic starts spread over the loop shapes are screened and the best is
    finished.  Gives standard errors, confidence intervals, an adequacy test and whether the LM
    converged (``result.converged``).  Needs at least 2 averaged periods.

References
----------
*Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose equation
numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2): F. Ikhouane and
J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control using the Bouc-Wen Model*,
Wiley, 2007.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal, Optional

import numpy as np
from numpy.typing import NDArray

from . import budget
from ._backend import Backend, selected
from .errors import ConvergenceWarning, IdentifiabilityWarning, InsufficientDataError, InvalidParameterError
from .estimators import Fit, adequacy, boundary_note, fit, linear_nrmse, on_constraint, steady_substeps
from .model import Recording
from .prepare import Prepared, Scales, auto_harmonics, noise_variance, prepare, scale
from .result import NOT_CONVERGED, Adequacy, ExperimentEstimate, IdentificationResult, Truth, wrap_phase
from .units import harmonise
from .validation import count, z_value

if TYPE_CHECKING:  # pragma: no cover - typing only
    from typing_extensions import TypeAlias

    from .measurement import Measurement
    from .signal import AveragedPeriod

    #: What identify takes: simulated recordings, raw lab measurements, or averaged periods.
    Experiment: TypeAlias = "Recording | Measurement | AveragedPeriod"

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

#: Identifiability alarm: condition number of the Fisher matrix after scaling to unit diagonal.
FISHER_COND_MAX = 1e10


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
    """Identify beta, gamma, mu and G(j omega_i) from sine experiments (the steps: module docstring).

    Parameters
    ----------
    recordings : Recording, Measurement or AveragedPeriod, or a sequence of them
        The experiments, mixed freely.  A Recording states U and omega and needs a whole number of
        samples per period; a Measurement is raw lab data at any sampling rate (its steady segments
        are found and averaged); an AveragedPeriod is one already averaged.
    method : {"refined", "profile", "paper"}
        The estimator: the seed paper exactly, the separable fit with the phase as a parameter, or
        (default) the joint output-error fit from the profile start (module docstring, "Methods").
    reference : int
        Index of the recording used for the separable fit of (beta, gamma, mu) (omega_1 in the paper).
    settle_periods : int, optional
        Leading periods dropped as transient; default: each recording's own ``settle_periods``
        (Recordings only: a Measurement's steady stretch is detected from the data).
    periods : int, optional
        Periods averaged; default: every whole period after the settling ones (Recordings only).
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
        The Rust core (default) or the NumPy reference, for every step (a Measurement's lab kernels too).

    Returns
    -------
    IdentificationResult

    Raises
    ------
    FrequencyMismatchError, InsufficientDataError, ZeroAmplitudeError, SingularNormalMatrixError,
    SearchAtBoundError, InvalidParameterError, NonFiniteError, NotConvergedError, UnitMismatchError
        And, for Measurements, the errors of :func:`bouc_wen_id.signal.find_steady_segments`
        (TimeAxisError, UndersampledError, NotPeriodicError, ...).

    Warns
    -----
    IdentifiabilityWarning
        When the parameters are poorly determined by the data, the fit ends on the constraint
        beta = |gamma|, the loops explain less than a linear model, or the separable estimates violate
        the Bouc-Wen conditions.
    DistortedInputWarning, UnitWarning
        When a Measurement's input is far from a pure sine; when experiments state other units of one
        quantity than the first's, converted to them (:mod:`bouc_wen_id.units`).
    ConvergenceWarning
        When the Levenberg-Marquardt refinement stops at ``max_iter`` before converging
        (``result.converged`` is False).
    """
    items, (lo, hi), (unit_notes, units) = _check_arguments(recordings, method, confidence, mu_bracket)
    reference, phase_grid, max_iter = _check_counts(reference, phase_grid, max_iter, harmonics)
    with selected(backend) as parts:  # the lab preprocessing of Measurements runs on the same backend
        prepared = prepare(items, parts.paper, settle_periods, periods, harmonics)
    _check_work(prepared, method, phase_grid, max_iter)
    reference = _reference_index(reference, len(prepared))
    scaled, scales = scale(prepared)
    fitted = fit(scaled, parts, method, reference, lo, hi, tol, phase_grid, max_iter)
    est = _unscale(fitted, scales)
    experiments = _experiment_estimates(prepared, fitted, est, scales)
    note = boundary_note(fitted.stop, fitted.active, mu=fitted.mu)  # mu = 1 alone: a valid exponent
    notes = _warn(_notes(method, est, experiments, confidence, note), fitted, unit_notes)
    settings = {
        "settle_periods": settle_periods,
        "periods": periods,
        "harmonics": harmonics,
        "mu_bracket": [lo, hi],
        "tol": tol,
        "phase_grid": phase_grid,
        "max_iter": max_iter,
        "scales": {"y": scales.y, "u": scales.u},
    }
    return _result(
        method, backend, reference, prepared, fitted, est, experiments, settings, notes, confidence, units
    )


def _warn(notes: Sequence[str], fitted: Fit, unit_notes: Sequence[str]) -> list[str]:
    """The notes as IdentifiabilityWarning, a refinement stopped at max_iter as ConvergenceWarning (both
    pointing at identify's caller); the result's notes: the units' (warned already, if at all), then these."""
    for note in notes:
        warnings.warn(note, IdentifiabilityWarning, stacklevel=3)
    if fitted.converged is False:
        warnings.warn(NOT_CONVERGED.format(iterations=fitted.iterations), ConvergenceWarning, stacklevel=3)
    return [*unit_notes, *notes]


def _result(
    method: Method,
    backend: Backend,
    reference: int,
    prepared: Sequence[Prepared],
    fitted: Fit,
    est: _Estimates,
    experiments: Sequence[ExperimentEstimate],
    settings: dict[str, Any],
    notes: Sequence[str],
    confidence: float,
    units: Mapping[str, str],
) -> IdentificationResult:
    """The result object of :func:`identify` from its pieces."""
    return IdentificationResult(
        method=method,
        backend=backend,
        beta=float(est.beta),
        gamma=float(est.gamma),
        mu=float(est.mu),
        cost=float(fitted.cost),
        iterations=int(fitted.iterations),
        reference=reference,
        experiments=tuple(experiments),
        settings=settings,
        truth=_truth(prepared, experiments),
        standard_errors=est.standard_errors,
        covariance=est.cov,
        adequacy=adequacy(prepared, [ex.model for ex in experiments], 3 + 2 * len(prepared)),
        warnings=tuple(notes),
        confidence=confidence,
        converged=fitted.converged,
        units=dict(units),
    )


def _check_arguments(
    recordings: Any, method: str, confidence: float, mu_bracket: tuple[float, float]
) -> tuple[list[Any], tuple[float, float], tuple[tuple[str, ...], dict[str, str]]]:
    """The experiments as a list in one unit per quantity (:mod:`bouc_wen_id.units`: later ones converted
    to the first's, with their notes), and the mu bracket; refuses a bad method, confidence or bracket."""
    if method not in ("paper", "profile", "refined"):
        raise InvalidParameterError(f"method must be 'refined', 'profile' or 'paper', got {method!r}")
    if isinstance(confidence, bool) or not isinstance(confidence, (int, float, np.integer, np.floating)):
        raise InvalidParameterError(f"confidence = {confidence!r} must be a number in (0, 1)")
    if not 0.0 < confidence < 1.0:
        raise InvalidParameterError(f"confidence = {confidence} must be in (0, 1)")
    items: list[Any] = [recordings] if not isinstance(recordings, (list, tuple)) else list(recordings)
    if not items:
        raise InsufficientDataError("no recordings were given")
    try:
        lo, hi = (float(v) for v in mu_bracket)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"mu_bracket = {mu_bracket!r} must be two numbers: {exc}") from None
    if not 1.0 <= lo < hi:
        raise InvalidParameterError(f"mu_bracket = {mu_bracket} must satisfy 1 <= lo < hi (mu > 1)")
    joined = harmonise(items, stacklevel=4)  # warns at identify's caller
    return joined.items, (lo, hi), (joined.notes, joined.units)


def _check_counts(reference: Any, phase_grid: Any, max_iter: Any, harmonics: Any) -> tuple[int, int, int]:
    """Counts must be integers (not 0.5, not True) before anything indexes or loops with them."""
    if isinstance(reference, bool) or not isinstance(reference, (int, np.integer)):
        raise InvalidParameterError(f"reference = {reference!r} must be an integer")
    if isinstance(harmonics, str):
        if harmonics not in ("auto", "all"):
            raise InvalidParameterError(f"harmonics = {harmonics!r} must be 'auto', 'all' or an integer >= 1")
    elif isinstance(harmonics, bool) or not isinstance(harmonics, (int, np.integer)) or harmonics < 1:
        raise InvalidParameterError(f"harmonics = {harmonics!r} must be 'auto', 'all' or an integer >= 1")
    return int(reference), count("phase_grid", phase_grid, 3), count("max_iter", max_iter, 1)


#: Work estimates of the budget checks, as rust/budget.rs (Work): golden reductions of one mu search, shooting
#: passes of one steady loop.
_GOLDEN_ITER_ESTIMATE = 50
_SHOOT_ITER_ESTIMATE = 4


def _check_work(prepared: Sequence[Prepared], method: str, phase_grid: int, max_iter: int) -> None:
    """Refuse, before any fit and for either backend, work beyond the budget (:mod:`bouc_wen_id.budget`)."""
    p_max = max(e.p for e in prepared)
    if method in ("profile", "refined"):
        budget.check_steps(
            "the phase profile (phase_grid x samples per period x mu search)",
            phase_grid * p_max * _GOLDEN_ITER_ESTIMATE,
        )
    if method == "refined":
        substeps = max(steady_substeps(e.p) for e in prepared)
        budget.check_steps(
            "the refinement (max_iter x samples x substeps)",
            max_iter * sum(e.p for e in prepared) * substeps * _SHOOT_ITER_ESTIMATE,
        )


def _reference_index(reference: int, m: int) -> int:
    if not -m <= reference < m:
        raise InvalidParameterError(f"reference = {reference} is not an index of the {m} experiments")
    return reference % m


@dataclass(frozen=True)
class _Estimates:
    """The fit in the data's units: shared parameters, gains, and the covariance of all of them."""

    beta: float
    gamma: float
    mu: float
    gains: FloatArray
    cov: Optional[FloatArray]
    standard_errors: Optional[dict[str, float]]


def _unscale(fitted: Fit, scales: Scales) -> _Estimates:
    """Map the estimates back to the data's units (see :class:`~bouc_wen_id.prepare.Scales`)."""
    s_y, s_u = scales.y, scales.u
    beta, gamma, mu = fitted.beta / s_y**fitted.mu, fitted.gamma / s_y**fitted.mu, fitted.mu
    gains = fitted.gains * (s_y / s_u)
    if fitted.cov is None:
        return _Estimates(beta, gamma, mu, gains, None, None)
    # Delta method through the back-transformation (beta and gamma depend on mu through s_y^mu).
    jac = np.eye(fitted.cov.shape[0])
    jac[0, 0] = jac[1, 1] = s_y**-fitted.mu
    jac[0, 2] = -beta * math.log(s_y)
    jac[1, 2] = -gamma * math.log(s_y)
    jac[3::2, 3::2] *= s_y / s_u
    cov = jac @ fitted.cov @ jac.T
    se_all = np.sqrt(np.abs(np.diag(cov)))
    se = {"beta": float(se_all[0]), "gamma": float(se_all[1]), "mu": float(se_all[2])}
    return _Estimates(beta, gamma, mu, gains, cov, se)


def _experiment_estimates(
    prepared: Sequence[Prepared], fitted: Fit, est: _Estimates, scales: Scales
) -> list[ExperimentEstimate]:
    """One estimate per experiment, on the canonical branch |G| > 0, with its loop and fit quality."""
    cov = est.cov
    experiments = []
    for i, e in enumerate(prepared):
        # (G, phi) and (-G, phi + pi) draw the same x = U G cos(omega t - phi): report |G| > 0.  The
        # phase is that of G itself, whatever the sign of U.
        phase = fitted.phis[i] + e.phase_shift
        if est.gains[i] < 0:
            phase += math.pi
        loop = fitted.loops[i]
        w = None if loop is None else np.asarray(loop * scales.y, dtype=np.float64)
        spread = float(np.linalg.norm(e.ybar - e.ybar.mean()))
        nrmse = float(np.linalg.norm(e.ybar - w)) / spread if w is not None and spread > 0 else math.nan
        experiments.append(
            ExperimentEstimate(
                frequency=e.frequency,
                amplitude=e.amplitude,
                gain=abs(float(est.gains[i])),
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
                linear_nrmse=linear_nrmse(e.ybar),
                model=w,
                source=e.source,
                grid_phase=float(wrap_phase(e.phase_shift)),
                offset=e.offset,
            )
        )
    return experiments


def _notes(
    method: str,
    est: _Estimates,
    experiments: Sequence[ExperimentEstimate],
    confidence: float,
    boundary: Optional[str] = None,
) -> list[str]:
    """Plain-language warnings: poor identifiability, the constraint (``boundary``: the refinement's own
    word on the faces it stopped on, when it did), worse than linear, the conditions."""
    beta, gamma = est.beta, est.gamma
    notes = _identifiability(beta, gamma, est.mu, experiments, est.cov, est.standard_errors, confidence)
    if method == "refined" and boundary is not None:
        notes.append(boundary)
    elif method == "refined" and on_constraint(beta, gamma):
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
    return notes


def _truth(prepared: Sequence[Prepared], experiments: Sequence[ExperimentEstimate]) -> Optional[Truth]:
    """The simulated plant's values, when every recording carries the same plant."""
    plants = [e.plant for e in prepared]
    first = plants[0]
    if first is not None and all(pl is not None and pl.to_dict() == first.to_dict() for pl in plants):
        return Truth.from_plant(first, np.array([e.frequency for e in experiments]))
    return None


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
    z = z_value(confidence)
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
