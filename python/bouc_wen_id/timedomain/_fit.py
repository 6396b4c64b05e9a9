"""``fit_time_domain``: the Wiener cascade fitted by output error to records of any waveform (issue #20).

Why this name: it says what is fitted to (time-domain records, not sine steady states), beside
:func:`~bouc_wen_id.identify` (the sine path) and :func:`~bouc_wen_id.fit_transfer_function` (G from points).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from typing import Any, Optional, Union

import numpy as np
from numpy.typing import NDArray

from .._backend import Backend, get_backend
from .._text import Summarised, with_warnings
from ..errors import (
    ConvergenceWarning,
    IdentifiabilityWarning,
    InvalidParameterError,
    NotConvergedError,
    PoorFitWarning,
)
from ..model import Recording, WienerPlant
from ..terms import Term
from ..units import harmonise
from ..validation import count, nonnegative_number, positive_number, z_value
from . import _coloured
from ._lm import LMResult, StopReason, free_covariance, levenberg_marquardt
from ._records import RecordLike, TimeRecord, as_time_records, settling_lead_in
from ._starts import rank_starts, sine_starts
from ._terms import term_class
from ._wiener import Problem, Structure, check_records, check_work, lead_ins

FloatArray = NDArray[np.float64]

#: Iterations of each start's screening run; the best start then runs to convergence.
SCREEN_ITER = 8
#: The shapes tried beside the start's own mu (the saturation level (beta + gamma)^(-1/mu) is kept).
ALTERNATIVE_MU = (1.3, 2.0, 3.0)
#: Below this whiteness p-value the standard errors are Newey-West's (:mod:`._coloured`).
COLOURED_LEVEL = 0.05
#: Lags of the residual whiteness test per record (at most a fifth of its samples).
WHITENESS_LAGS = 20


@dataclass(frozen=True)
class Whiteness:
    """The adequacy test of an output-error fit: the Ljung-Box portmanteau statistic of the residuals.

    With the right model and white measurement noise the residuals are white, and
    ``Q = sum_records N (N + 2) sum_k rho_k^2 / (N - k)`` over ``k = 1..L`` is chi-square with ``dof``
    (``L`` per record) degrees of freedom; a small ``p_value`` says the residuals still hold structure the
    model misses (or the noise is coloured).
    """

    statistic: float
    dof: int
    p_value: float

    def rejects(self, level: float = 0.05) -> bool:
        return self.p_value < level

    def to_dict(self) -> dict[str, Any]:
        return {"statistic": self.statistic, "dof": self.dof, "p_value": self.p_value}


@dataclass(frozen=True, eq=False)
class TimeDomainFit(Summarised):
    """The Wiener cascade fitted to time-domain records.

    Attributes
    ----------
    plant : WienerPlant
        The fitted alpha-normalised plant (``x = G u``, Bouc-Wen with alpha = 1, ``y = w``).
    structure : Structure
        Degrees of G and what was fitted (delay, ``w0``).
    parameter_names : tuple of str
        The fitted parameters (``b0..bm``, ``a1..an``, ``delay`` when fitted, ``beta``, ``gamma``, ``mu``,
        ``w0`` when fitted).
    parameters, covariance : ndarray
        Their values and covariance ``sigma^2 (J^T J)^-1`` (``sigma`` the residual RMS, or the known noise).
    rmse : float
        Root mean square residual over every fitted sample (units of y).
    nrmse : tuple of float
        Per record ``||y - y_sim|| / ||y - mean(y)||`` after the lead-in.
    adequacy : Whiteness
        Residual whiteness test.
    reason : str
        Why the search stopped (``converged``, ``converged_at_bound``, ``max_iter``, ...).
    at_bound : tuple of str
        Parameters held on a bound at the end (their standard errors are NaN).
    starts : tuple of (str, float)
        Every start tried and its cost after screening.
    lead_in : tuple of int
        Samples of each record left out of the residuals.
    """

    plant: WienerPlant
    structure: Structure
    parameter_names: tuple[str, ...]
    parameters: FloatArray
    covariance: FloatArray = field(repr=False)
    cost: float
    rmse: float
    nrmse: tuple[float, ...]
    adequacy: Whiteness
    iterations: int
    reason: StopReason
    at_bound: tuple[str, ...]
    starts: tuple[tuple[str, float], ...]
    lead_in: tuple[int, ...]
    samples: int
    backend: str
    warnings: tuple[str, ...] = ()
    confidence: float = 0.95

    @property
    def converged(self) -> bool:
        return self.reason in ("converged", "converged_at_bound")

    @property
    def standard_errors(self) -> dict[str, float]:
        se = np.sqrt(np.diag(self.covariance))
        return {n: float(v) for n, v in zip(self.parameter_names, se)}

    @property
    def correlation(self) -> FloatArray:
        """Correlation matrix of the fitted parameters."""
        se = np.sqrt(np.diag(self.covariance))
        with np.errstate(invalid="ignore", divide="ignore"):
            out: FloatArray = self.covariance / np.outer(se, se)
        return out

    def value(self, name: str) -> float:
        if name not in self.parameter_names:
            raise InvalidParameterError(
                f"no fitted parameter {name!r}; fitted: {', '.join(self.parameter_names)}"
            )
        return float(self.parameters[self.parameter_names.index(name)])

    def interval(self, name: str) -> tuple[float, float]:
        """Confidence interval of one parameter at ``confidence``."""
        v, se = self.value(name), self.standard_errors[name]
        z = z_value(self.confidence)
        return v - z * se, v + z * se

    def summary(self) -> str:
        kinds = ", ".join(c.kind for c in self.structure.terms)
        lines = [
            f"TimeDomainFit: Wiener cascade, G of degrees ({self.structure.m}, {self.structure.n})"
            f"{' with a fitted delay' if self.structure.delay else ''}"
            f"{', terms ' + kinds if kinds else ''}, "
            f"{self.samples} samples; Jacobian "
            f"{'exact (dual numbers)' if self.structure.exact else 'by central differences'}",
            f"  {self.reason} after {self.iterations} iterations; RMSE = {self.rmse:.4g}, "
            f"NRMSE = {', '.join(f'{v:.3g}' for v in self.nrmse)}",
        ]
        for n, v in zip(self.parameter_names, self.parameters):
            se = self.standard_errors[n]
            lines.append(f"  {n:>6} = {v: .6g} +- {se:.3g}{'  (on a bound)' if n in self.at_bound else ''}")
        a = self.adequacy
        lines.append(f"  whiteness: Q = {a.statistic:.4g} on {a.dof} dof, p = {a.p_value:.3g}")
        return with_warnings(lines, self.warnings)

    def to_dict(self) -> dict[str, Any]:
        return {
            "plant": self.plant.to_dict(),
            "parameters": dict(zip(self.parameter_names, (float(v) for v in self.parameters))),
            "standard_errors": self.standard_errors,
            "rmse": self.rmse,
            "nrmse": list(self.nrmse),
            "adequacy": self.adequacy.to_dict(),
            "reason": self.reason,
            "at_bound": list(self.at_bound),
            "iterations": self.iterations,
            "warnings": list(self.warnings),
        }


def whiteness(residuals: Sequence[FloatArray], lags: int = WHITENESS_LAGS) -> Whiteness:
    """The Ljung-Box test of :class:`Whiteness` over the records' residuals."""
    from scipy.stats import chi2  # type: ignore[import-untyped]

    q, dof = 0.0, 0
    for r in residuals:
        n = r.size
        lag = min(lags, n // 5)
        if lag < 1:
            continue
        e = r - r.mean()
        denom = float(e @ e)
        if denom == 0.0:
            continue
        rho = np.array([float(e[k:] @ e[:-k]) / denom for k in range(1, lag + 1)])
        q += n * (n + 2) * float(np.sum(rho**2 / (n - np.arange(1, lag + 1))))
        dof += lag
    p = float(chi2.sf(q, dof)) if dof else math.nan
    return Whiteness(q, dof, p)


StartLike = Union[WienerPlant, Any]


def _start_plants(
    start: Optional[StartLike],
    records: Sequence[RecordLike],
    order: Optional[tuple[int, int]],
    delay: Optional[bool],
) -> list[tuple[WienerPlant, str]]:
    """The starts: a plant as given, or the sine path's estimates (identify, then fit_transfer_function of
    the order asked, else of several orders: ``_starts.sine_starts``)."""
    if isinstance(start, WienerPlant):
        return [(start.normalized(), "given")]
    from ..identification import identify
    from ..result import IdentificationResult

    if start is None:
        sines = [r for r in records if isinstance(r, Recording)]
        if not sines:
            raise InvalidParameterError(
                "no start: give start= (a WienerPlant, or an IdentificationResult of sine experiments), or "
                "include sine Recordings among the records so that identify can provide one"
            )
        start = identify(sines, method="refined")
    if not isinstance(start, IdentificationResult):
        raise InvalidParameterError(
            f"start must be a WienerPlant or an IdentificationResult, got {type(start).__name__}"
        )
    plants = sine_starts(start, order, delay)
    return [(p, f"sine path (identify + fit_transfer_function, {lbl})") for p, lbl in plants]


def _alternatives(plant: WienerPlant, structure: Structure) -> list[tuple[str, FloatArray]]:
    """The start and its variants in mu at the same saturation level and the same beta/gamma split."""
    theta = structure.pack(plant)
    out = [("start", theta)]
    h = plant.hysteresis
    level = (h.beta + h.gamma) ** (-1.0 / h.mu)
    for mu in ALTERNATIVE_MU:
        if abs(mu - h.mu) < 0.15:
            continue
        total = level ** (-mu)
        alt = theta.copy()
        k = structure.m + structure.n + 2
        alt[k], alt[k + 1], alt[k + 2] = (
            total * h.beta / (h.beta + h.gamma),
            total * h.gamma / (h.beta + h.gamma),
            mu,
        )
        out.append((f"mu = {mu}", alt))
    return out


def fit_time_domain(
    records: Union[RecordLike, Sequence[RecordLike]],
    *,
    start: Optional[StartLike] = None,
    order: Optional[tuple[int, int]] = None,
    delay: Optional[bool] = None,
    estimate_w0: bool = False,
    terms: Sequence[Union[type[Term], Term, str]] = (),
    lead_in: Optional[float] = None,
    substeps: int = 2,
    max_iter: int = 100,
    multistart: bool = True,
    noise_sd: Optional[float] = None,
    confidence: float = 0.95,
    backend: Backend = "rust",
    should_stop: Optional[Callable[[], bool]] = None,
) -> TimeDomainFit:
    """Fit the Wiener cascade (parametric G, Bouc-Wen) to records ``(t, u, y)`` of any waveform.

    Parameters
    ----------
    records : TimeRecord, Recording, (t, u, y) tuple, or a sequence of them
        Each starts from rest at its first sample unless ``lead_in`` or ``estimate_w0`` says otherwise.
    start : WienerPlant or IdentificationResult, optional
        Where the search starts.  Default: the sine path's estimate when sine ``Recording`` s are among
        ``records`` (:func:`~bouc_wen_id.identify`, then ``fit_transfer_function`` of order ``order``).
    order : (m, n), optional
        Degrees of G (default: the start's).
    delay : bool, optional
        Fit the delay (default: when the start has one).
    estimate_w0 : bool
        Fit the initial hysteretic state (a record cut from a longer run); G's states start at 0.
    terms : sequence of term classes, terms or code names
        The library's terms to fit beside the cascade: any term of the registry with a time-domain form, at
        any of its places (``"viscous@x"``, ``Viscous.at(Place.X)``); the input distortion has none and is
        refused by name.  They start at the start plant's values (keeping its fixed settings, e.g. a
        friction's smoothing), else at a given instance's value (``Viscous(0.01)``: e.g. the value a
        diagnosis named), else 0, within their admissible and physical ranges (the search's bounds).
        The output terms on u (offset, stiffness, viscous damping, inertia) have exact Jacobian columns;
        with any other term the Jacobian is a central difference of the simulator with terms (module
        ``timedomain._terms``).  Default: the start plant's terms.
    lead_in : float, optional
        Seconds at each record's start left out of the residuals (G's transient from a state that is not
        rest).  Default 0: the records start from rest.
    substeps : int
        RK4 steps per sample interval.
    max_iter : int
        Levenberg-Marquardt iterations of the final run.
    multistart : bool
        Also screen the start with other values of mu at the same saturation level (:data:`ALTERNATIVE_MU`).
    noise_sd : float, optional
        The known output noise (covariance ``noise_sd^2 (J^T J)^-1``, Cramer-Rao); default the residual RMS.
    should_stop : callable, optional
        Polled once an iteration; True stops with the best so far (``"cancelled"``); Ctrl-C as everywhere.

    Raises
    ------
    InvalidParameterError, NonFiniteError, TimeAxisError, InsufficientDataError, BudgetExceededError
        Bad records (see :class:`TimeRecord`), a record shorter than the start model's memory, no start,
        bad options, or a fit above the step budget.
    """
    # One unit per quantity (later ones converted, unrelated refused); the fitted plant states them.
    recs = as_time_records(records)
    joined = harmonise(_raw_items(records), stacklevel=3)
    raw = joined.items
    if any(a is not b for a, b in zip(raw, _raw_items(records))):
        recs = as_time_records(raw)
    substeps = count("substeps", substeps, 1)
    max_iter = count("max_iter", max_iter, 1)
    confidence = positive_number("confidence", confidence)
    get_backend(backend)
    lead_in_s = None if lead_in is None else nonnegative_number("lead_in", lead_in)
    sd = None if noise_sd is None else positive_number("noise_sd", noise_sd)
    candidates = _start_plants(start, raw, order, delay)
    kinds = _term_classes(terms) if terms else tuple(type(t) for t in candidates[0][0].terms)
    given = _given_terms(terms)
    lead = lead_ins(recs, lead_in_s)
    scale = float(np.std(np.concatenate([r.y for r in recs]))) or 1.0
    # the step budget before any work: the order screen, then one start's screening and its final run
    check_work(recs, substeps, (len(candidates) * (SCREEN_ITER + 1) + (2 * SCREEN_ITER + 1) * 4) * 16)
    ranked, screened = rank_starts(
        candidates,
        lambda p: _structure(p, order, delay, estimate_w0, kinds, given),
        lambda st: Problem(st, recs, lead, substeps, backend, scale),
        substeps,
        should_stop,
    )

    def fit_one(plant: WienerPlant, origin: str) -> Union[TimeDomainFit, str]:
        structure = _structure(plant, order, delay, estimate_w0, kinds, given)
        return _fit_from(plant, origin, structure, recs, lead, scale, substeps, max_iter, multistart,
                         backend, should_stop, sd, confidence)  # fmt: skip

    fit = _first_stable(ranked, fit_one)
    fit = _settling_note(replace(fit, starts=(*screened, *fit.starts)), raw, lead_in_s)
    if not joined.units:
        return fit
    return replace(fit, plant=fit.plant.with_units(joined.units), warnings=(*joined.notes, *fit.warnings))


def _settling_note(fit: TimeDomainFit, raw: Sequence[Any], lead_in: Optional[float]) -> TimeDomainFit:
    """A warning when the residuals are not white and the sine recordings' declared settling was fitted:
    a record whose first sample is not rest (a cosine switched on, an input running before the record)
    leaves a start the model, simulated from rest, does not have, and G's order and the terms trade
    against it (reviewer 35: a viscous value half the true one). identify, diagnose and
    ``Diagnosis.to_model`` leave the settling out."""
    settle = settling_lead_in(raw)
    if lead_in is not None or settle is None or not fit.adequacy.rejects(0.01):
        return fit
    note = (
        f"the residuals are not white (p = {fit.adequacy.p_value:.2g}) and the recordings' declared settling "
        f"is among them: a record that does not start from rest biases G and the terms; lead_in={settle:.4g} "
        "leaves it out as identify and diagnose do"
    )
    warnings.warn(note, PoorFitWarning, stacklevel=3)
    return replace(fit, warnings=(*fit.warnings, note))


def _first_stable(
    ranked: Sequence[tuple[WienerPlant, str]],
    fit_one: Callable[[WienerPlant, str], Union[TimeDomainFit, str]],
) -> TimeDomainFit:
    """The fit from the first start (best first) whose G ends asymptotically stable."""
    failed: list[str] = []
    for plant, origin in ranked:
        fit = fit_one(plant, origin)
        if not isinstance(fit, str):
            return fit
        failed.append(f"{origin}: {fit}")
    raise NotConvergedError(
        "the time-domain fit ended with G not asymptotically stable from every start ("
        + "; ".join(failed)
        + "): the records pull a pole of G to the origin, which a model with a sine steady state cannot "
        "hold; fit another order (order=), give start=, or add the term the records ask for (diagnose)"
    )


def _structure(
    plant: WienerPlant,
    order: Optional[tuple[int, int]],
    delay: Optional[bool],
    estimate_w0: bool,
    kinds: tuple[type[Term], ...],
    given: tuple[Term, ...],
) -> Structure:
    m, n = order if order is not None else _degrees(plant)
    fit_delay = bool(plant.linear.delay > 0.0) if delay is None else bool(delay)
    return Structure(m, n, fit_delay, bool(estimate_w0), kinds, (*given, *plant.terms))


def _fit_from(
    plant: WienerPlant,
    origin: str,
    structure: Structure,
    recs: Sequence[TimeRecord],
    lead: list[int],
    scale: float,
    substeps: int,
    max_iter: int,
    multistart: bool,
    backend: Backend,
    should_stop: Optional[Callable[[], bool]],
    sd: Optional[float],
    confidence: float,
) -> Union[TimeDomainFit, str]:
    """The fit from one start plant (its mu variants screened, the best run to convergence), or why its
    G ended not asymptotically stable (a denominator coefficient on its bound 0)."""
    check_records(recs, lead, structure.unpack(structure.pack(plant)))
    starts = _alternatives(plant, structure) if multistart else _alternatives(plant, structure)[:1]
    check_work(recs, substeps, (len(starts) * (2 * SCREEN_ITER + 1) + 2 * max_iter + 1) * 16)
    problem = Problem(structure, recs, lead, substeps, backend, scale)
    # The start simulated once outside the search: a term the simulator refuses is named here, not
    # taken for a step the search rejects.
    problem.simulate(starts[0][1], 0)
    max_delay = min(r.duration for r in recs) / 2.0
    best, tried = _search(problem, starts, max_iter, max_delay, should_stop)
    m, n = structure.m, structure.n
    den = np.concatenate([[1.0], best[0][m + 1 : m + 1 + n]])
    if n and (np.any(den <= 0.0) or np.any(np.roots(den).real >= 0.0)):
        names = [f"a{i + 1}" for i in range(n) if den[i + 1] <= 0.0]
        return f"den = {den.tolist()}" + (f" ({', '.join(names)} on the bound 0)" if names else "")
    return _result(problem, best, tried, origin, sd, confidence)


def _term_classes(terms: Sequence[Union[type[Term], Term, str]]) -> tuple[type[Term], ...]:
    """Term classes from classes, instances or code names of the registry (any place, ``"viscous@x"``)."""
    if isinstance(terms, (str, Term)) or (isinstance(terms, type) and issubclass(terms, Term)):
        terms = (terms,)
    return tuple(term_class(t) for t in terms)


def _given_terms(terms: Sequence[Union[type[Term], Term, str]]) -> tuple[Term, ...]:
    """The term instances among ``terms``: their fixed settings are kept and their values start the search
    when the start plant does not hold the term."""
    if isinstance(terms, Term):
        return (terms,)
    if isinstance(terms, (str, type)):
        return ()
    return tuple(t for t in terms if isinstance(t, Term))


def _raw_items(records: Any) -> list[Any]:
    """The user's items, one per record (to find the sine Recordings among them)."""
    if isinstance(records, (TimeRecord, Recording)):
        return [records]
    if (
        isinstance(records, tuple)
        and len(records) == 3
        and not isinstance(records[0], (TimeRecord, Recording, tuple))
    ):
        return [records]
    return list(records)


def _degrees(plant: WienerPlant) -> tuple[int, int]:
    num = np.trim_zeros(np.asarray(plant.linear.num, dtype=float), "f")
    return max(num.size - 1, 0), plant.linear.den.size - 1


def _search(
    problem: Problem,
    starts: list[tuple[str, FloatArray]],
    max_iter: int,
    max_delay: float,
    should_stop: Optional[Callable[[], bool]],
) -> tuple[tuple[FloatArray, LMResult], tuple[tuple[str, float], ...]]:
    """Screen every start for :data:`SCREEN_ITER` iterations, then run the best to convergence."""
    free = problem.structure.free
    tried: list[tuple[str, float]] = []
    screened: list[tuple[float, FloatArray]] = []
    for label, theta in starts:
        lo, hi = problem.structure.bounds(theta, max_delay)
        fun = problem.fun(theta)
        try:
            run = levenberg_marquardt(
                fun,
                theta[free],
                lo[free],
                hi[free],
                max_iter=SCREEN_ITER if len(starts) > 1 else max_iter,
                should_stop=should_stop,
            )
        except Exception as exc:  # a start the model cannot even simulate is skipped, not fatal
            if len(starts) == 1:
                raise
            tried.append((f"{label} (failed: {type(exc).__name__})", math.inf))
            continue
        tried.append((label, 2.0 * run.cost * problem.scale**2))
        screened.append((run.cost, problem.full(run.p, theta)))
        if len(starts) == 1:
            return (problem.full(run.p, theta), run), tuple(tried)
    if not screened:
        raise InvalidParameterError("no start could be simulated: give a start closer to the data")
    theta = min(screened, key=lambda c: c[0])[1]
    lo, hi = problem.structure.bounds(theta, max_delay)
    run = levenberg_marquardt(
        problem.fun(theta), theta[free], lo[free], hi[free], max_iter=max_iter, should_stop=should_stop
    )
    return (problem.full(run.p, theta), run), tuple(tried)


def _coloured_note(
    cov: FloatArray,
    jac: FloatArray,
    resid: Sequence[FloatArray],
    free: NDArray[np.bool_],
    adequacy: Whiteness,
    apply: bool,
) -> str:
    """Widen ``cov`` in place to the Newey-West standard errors when the residuals are not white
    (:mod:`._coloured`); the note that says so, or "" (white residuals, a known noise level, a singular
    J^T J: the covariance is kept)."""
    if not apply or not adequacy.rejects(COLOURED_LEVEL) or not np.any(free):
        return ""
    sizes = np.cumsum([r.size for r in resid])[:-1]
    blocks = np.split(jac[:, free], sizes)
    lags = _coloured.bandwidth(resid)
    hac = _coloured.hac_covariance(blocks, list(resid), lags)
    sub = np.ix_(free, free)
    before = np.sqrt(np.diag(cov[sub]))
    cov[sub] = _coloured.widened(cov[sub], hac)
    grow = float(np.max(np.sqrt(np.diag(cov[sub])) / before))
    return (
        f"the residuals are not white (p = {adequacy.p_value:.2g}): the standard errors count their "
        f"correlation (Newey-West, {lags} lags; up to {grow:.3g}x the white-noise ones); coloured noise "
        "leaves the estimates unbiased, a missing part of the model does not"
    )


def _result(
    problem: Problem,
    best: tuple[FloatArray, LMResult],
    tried: tuple[tuple[str, float], ...],
    origin: str,
    noise_sd: Optional[float],
    confidence: float,
) -> TimeDomainFit:
    theta, run = best
    s = problem.structure
    free = s.free
    names = tuple(n for n, f in zip(s.names, free) if f)
    resid = [
        (problem.simulate(theta, i)[0] - r.y)[k:]
        for i, (r, k) in enumerate(zip(problem.records, problem.lead))
    ]
    allr = np.concatenate(resid)
    samples = allr.size
    dof = max(samples - int(free.sum()), 1)
    sigma2 = noise_sd**2 if noise_sd is not None else float(allr @ allr) / dof
    # The LM covariance is in units of the scaled residuals: rescale to sigma2 (J^T J)^-1 in y's units.
    jac = run.jacobian * problem.scale
    cov, singular = free_covariance(jac, ~run.at_bound, sigma2)
    adequacy = whiteness(resid)
    coloured = _coloured_note(cov, jac, resid, ~run.at_bound, adequacy, noise_sd is None and not singular)
    nrmse = tuple(
        float(np.linalg.norm(e) / max(np.linalg.norm(r.y[k:] - r.y[k:].mean()), np.finfo(float).tiny))
        for e, r, k in zip(resid, problem.records, problem.lead)
    )
    notes: list[str] = []
    if singular:
        notes.append("J^T J is singular: some parameters are not identifiable from these records")
    at_bound = tuple(n for n, b in zip(names, run.at_bound) if b)
    if at_bound:
        notes.append(f"the search ended on a bound of {', '.join(at_bound)}")
    if not run.converged:
        warnings.warn(f"the time-domain fit stopped: {run.reason}", ConvergenceWarning, stacklevel=3)
    for w in notes:
        warnings.warn(w, IdentifiabilityWarning, stacklevel=3)
    if coloured:
        notes.append(coloured)
    cov.setflags(write=False)
    params = theta[free].copy()
    params.setflags(write=False)
    return TimeDomainFit(
        plant=s.unpack(theta),
        structure=s,
        parameter_names=names,
        parameters=params,
        covariance=cov,
        cost=float(allr @ allr),
        rmse=float(np.sqrt(np.mean(allr**2))),
        nrmse=nrmse,
        adequacy=adequacy,
        iterations=run.iterations,
        reason=run.reason,
        at_bound=at_bound,
        starts=tuple((f"{origin}: {lbl}", c) for lbl, c in tried),
        lead_in=tuple(problem.lead),
        samples=samples,
        backend=problem.backend,
        warnings=tuple(notes),
        confidence=confidence,
    )


def cramer_rao_bound(
    plant: WienerPlant,
    records: Union[RecordLike, Sequence[RecordLike]],
    noise_sd: float,
    *,
    structure: Structure,
    lead_in: Optional[float] = None,
    substeps: int = 2,
    backend: Backend = "rust",
) -> tuple[tuple[str, ...], FloatArray]:
    """The Cramer-Rao bound ``noise_sd^2 (J^T J)^-1`` of the fitted parameters at ``plant`` on the inputs
    of ``records`` (white Gaussian output noise of standard deviation ``noise_sd``).

    Returns the parameter names and the bound's covariance matrix.
    """
    recs = as_time_records(records)
    sd = positive_number("noise_sd", noise_sd)
    theta = structure.pack(plant)
    problem = Problem(structure, recs, lead_ins(recs, lead_in), count("substeps", substeps, 1), backend)
    _, jac = problem.residuals(theta)
    names = tuple(n for n, f in zip(structure.names, structure.free) if f)
    return names, sd**2 * np.linalg.inv(jac.T @ jac)
