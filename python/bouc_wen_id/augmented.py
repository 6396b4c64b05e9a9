"""The augmented model: the Wiener-Bouc-Wen plant plus extra physical terms, fitted jointly (design.md 9).

Per sine experiment ``i`` on its averaged period's grid ``theta_j = 2 pi j/P``::

    y_j = y0 + H_tau[ w_j + k u_j + c udot_j + m uddot_j + f tanh(udot_j / (eps |U| omega)) ]_j

with the measured input ``u_j = U cos(theta_j + psi)``, the hysteresis ``w`` of the latent
``x_j = U g_i cos(theta_j - phi_i)`` (asymmetry ``delta`` and play ``b`` act inside it) and ``H_tau`` the
periodic first-order sensor lag.  The mechanical terms can also act across the hysteretic element, on x
(``"viscous@x"`` etc., :attr:`bouc_wen_id.terms.Place.X`): ``k x``, ``c xdot``, ``m xddot``,
``f tanh(xdot / (eps |A| omega))``, their value shared, their phase following each experiment's ``(g, phi)``.
Each term has one parameter, shared by every experiment in physical units;
an inactive term is absent (not zero).  :func:`fit_augmented` runs the joint Levenberg-Marquardt of design.md
9.3 (Rust core, or the NumPy reference with ``backend="numpy"``) and returns the estimates with their Fisher
information and covariance.

Example
-------
>>> start = AugParams(0.8, 0.2, 1.6, ("offset",), np.array([0.0]), gains, phases)  # doctest: +SKIP
>>> fit = fit_augmented(experiments, start)  # doctest: +SKIP
>>> fit.params.value("offset"), fit.standard_error("offset")  # doctest: +SKIP
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType
from typing import Any, Literal, Optional, Union, overload

import numpy as np
from numpy.typing import NDArray

from ._backend import get_backend
from .errors import InsufficientDataError, InvalidParameterError, ZeroAmplitudeError
from .terms import COULOMB_SMOOTHING, COULOMB_SMOOTHING_MAX, STEADY_TERM_NAMES, TERMS, parse_terms
from .validation import frozen_array, real_number

__all__ = [
    "TERM_NAMES",
    "TERM_SYMBOLS",
    "TERM_UNITS",
    "HYSTERESIS_NAMES",
    "term_unit",
    "AugExperiment",
    "AugParams",
    "AugFit",
    "AugOutput",
    "fit_augmented",
    "augmented_output",
]

FloatArray = NDArray[np.float64]

#: The terms the augmented model takes (those seen on the averaged steady period; degradation is fitted from
#: the period-by-period record instead), from the registry :data:`bouc_wen_id.terms.TERMS`.
TERM_NAMES: tuple[str, ...] = STEADY_TERM_NAMES

#: The shared hysteresis parameters ahead of the terms' parameters.
HYSTERESIS_NAMES: tuple[str, ...] = ("beta", "gamma", "mu")

#: Symbol of each term's parameter (design.md 9.1), from the term value types.
TERM_SYMBOLS: Mapping[str, str] = MappingProxyType({name: TERMS[name].symbol for name in TERM_NAMES})

#: Unit template of each term's parameter (``{y}``, ``{u}``: the output's and the input's units), from the
#: term value types; format with :func:`term_unit`.
TERM_UNITS: Mapping[str, str] = MappingProxyType({name: TERMS[name].unit for name in TERM_NAMES})


def term_unit(
    name: str, *, y: str = "[y]", u: str = "[u]", x: Optional[str] = None, w: Optional[str] = None
) -> str:
    """The unit of term ``name``'s parameter with the given channel units.

    In the identified model (alpha = 1) w and x have the output's units, which the templates write as
    ``{y}``; ``x`` and ``w`` are accepted for callers that name them.
    """
    parse_terms([name], TERM_NAMES)
    return TERM_UNITS[name].format(y=y, u=u, x=y if x is None else x, w=y if w is None else w)


@dataclass(frozen=True)
class AugExperiment:
    """One sine experiment as the augmented fit sees it.

    Parameters
    ----------
    ybar : ndarray, shape (P,)
        Averaged output over one period, on ``t_j = j T/P``, with its DC (``offset_y`` added back).
    amplitude : float
        Input amplitude U (units of u, non-zero).
    frequency : float
        Angular frequency omega (rad/s, > 0).
    grid_phase : float
        Phase psi (rad) of the input on the grid: ``u_j = U cos(2 pi j/P + psi)``.
    weight : float
        Weight of each squared residual, ``N / sigma^2`` (periods averaged over noise variance), > 0.
    source : str
        Where the experiment came from (for messages).
    waveform : ndarray, shape (2 K,), optional
        The measured input's harmonics beyond the fundamental, ``[Re c_2, Im c_2, Re c_3, ...]`` with
        ``u = U Re[e^{i z} + sum_k c_k e^{i k z}]``, ``z = 2 pi j/P + psi`` (design.md 9.5): what the
        ``distortion`` term scales. Empty (the default) for a pure sine.
    substeps : int, optional
        This experiment's own RK4 steps per sample of the loop solvers (>= 1). When set it is used in
        place of the ``substeps`` a fit or an output call is given, so a coarse grid can take more steps
        per sample than the fine grids fitted with it (the diagnosis sets one per experiment). None (the
        default): the call's count.
    input_shape : ndarray, shape (1 + 2 K,), optional
        The measured input as the mechanical terms on u see it (review 35): ``[dc, Re c_2, Im c_2, ...]``,
        its mean relative to ``U`` (seen by the stiffness alone: a spring acts on the whole displacement,
        a dashpot and a mass on its derivatives) then its own harmonics as ``waveform``'s. Unlike
        ``waveform`` (x's, carried through G, scaled by the ``distortion`` term) it is never carried:
        the terms on u act on u. Empty (the default): the pure sine.
    """

    ybar: FloatArray
    amplitude: float
    frequency: float
    grid_phase: float
    weight: float
    source: str = ""
    waveform: FloatArray = field(default_factory=lambda: np.zeros(0))
    substeps: Optional[int] = None
    input_shape: FloatArray = field(default_factory=lambda: np.zeros(0))

    def __post_init__(self) -> None:
        ybar = frozen_array("ybar", self.ybar)
        if ybar.size < 4:
            raise InsufficientDataError(f"ybar has {ybar.size} samples per period; at least 4 are needed")
        amplitude = real_number("amplitude", self.amplitude)
        if amplitude == 0.0:
            raise ZeroAmplitudeError("the input amplitude U is 0: nothing excites the plant")
        frequency = real_number("frequency", self.frequency)
        if frequency <= 0.0:
            raise InvalidParameterError(f"frequency = {frequency} rad/s must be > 0")
        weight = real_number("weight", self.weight)
        if weight <= 0.0:
            raise InvalidParameterError(f"weight = {weight} must be > 0 (N / noise variance)")
        object.__setattr__(self, "ybar", ybar)
        object.__setattr__(self, "amplitude", amplitude)
        object.__setattr__(self, "frequency", frequency)
        object.__setattr__(self, "grid_phase", real_number("grid_phase", self.grid_phase))
        object.__setattr__(self, "weight", weight)
        wave = np.array(self.waveform, dtype=np.float64).ravel()
        if wave.size % 2 or not np.all(np.isfinite(wave)):
            raise InvalidParameterError(
                "waveform must hold finite (re, im) pairs of the harmonics k = 2, 3, ..."
            )
        wave.flags.writeable = False
        object.__setattr__(self, "waveform", wave)
        shape = np.array(self.input_shape, dtype=np.float64).ravel()
        if (shape.size and shape.size % 2 == 0) or not np.all(np.isfinite(shape)):
            raise InvalidParameterError(
                "input_shape must hold the input's finite mean relative to U, then (re, im) pairs of its "
                "harmonics k = 2, 3, ... (an odd length), or nothing"
            )
        shape.flags.writeable = False
        object.__setattr__(self, "input_shape", shape)
        if self.substeps is not None:
            object.__setattr__(self, "substeps", _count("substeps", self.substeps, 1))


@dataclass(frozen=True)
class AugParams:
    """Parameters of the augmented model.

    Parameters
    ----------
    beta, gamma, mu : float
        Bouc-Wen parameters (alpha = 1).
    terms : tuple of str
        Active terms (code names of :data:`TERM_NAMES`), in the order of ``values``.
    values : ndarray, shape (T,)
        One parameter per term, units :data:`TERM_UNITS`.
    gains : ndarray, shape (m,)
        Signed ``g_i`` with ``x_i = U_i g_i cos(theta_j - phi_i)``.
    phases : ndarray, shape (m,)
        ``phi_i`` (rad, grid frame).
    smoothing : float
        The dry friction's smoothing ``eps`` (``f tanh(v / (eps Vmax))``, at either place): a setting
        of the Coulomb terms that the refinement does not move (the diagnosis profiles it:
        ``diagnosis/coulomb_width.py``); in ``(0, 0.5]``, default 1 %.
    """

    beta: float
    gamma: float
    mu: float
    terms: tuple[str, ...]
    values: FloatArray
    gains: FloatArray
    phases: FloatArray
    smoothing: float = COULOMB_SMOOTHING

    def __post_init__(self) -> None:
        eps = real_number("smoothing", self.smoothing)
        if not 0.0 < eps <= COULOMB_SMOOTHING_MAX:
            raise InvalidParameterError(f"smoothing eps = {eps} must be in (0, {COULOMB_SMOOTHING_MAX}]")
        object.__setattr__(self, "smoothing", eps)
        for name in HYSTERESIS_NAMES:
            object.__setattr__(self, name, real_number(name, getattr(self, name)))
        terms = parse_terms(self.terms, TERM_NAMES)
        values = frozen_array("values", self.values)
        if values.size != len(terms):
            raise InvalidParameterError(f"{len(terms)} terms {terms} but {values.size} values")
        gains = frozen_array("gains", self.gains)
        phases = frozen_array("phases", self.phases)
        if gains.size != phases.size:
            raise InvalidParameterError(f"{gains.size} gains but {phases.size} phases")
        object.__setattr__(self, "terms", terms)
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "gains", gains)
        object.__setattr__(self, "phases", phases)

    @property
    def shared(self) -> FloatArray:
        """``[beta, gamma, mu, q_1 .. q_T]``, the order of the Fisher matrix's shared block."""
        return np.concatenate([[self.beta, self.gamma, self.mu], self.values])

    @property
    def names(self) -> tuple[str, ...]:
        """Names of :attr:`shared`: ``beta, gamma, mu`` and the terms."""
        return HYSTERESIS_NAMES + self.terms

    def value(self, name: str) -> float:
        """The value of a shared parameter (``beta``, ``gamma``, ``mu`` or an active term)."""
        if name in HYSTERESIS_NAMES:
            return float(getattr(self, name))
        parse_terms([name], TERM_NAMES)
        if name not in self.terms:
            raise InvalidParameterError(f"term {name!r} is not active; the active terms are {self.terms}")
        return float(self.values[self.terms.index(name)])

    def with_term(self, name: str, value: float = 0.0) -> AugParams:
        """A new :class:`AugParams` with term ``name`` appended at ``value`` (already active: an error)."""
        return AugParams(
            self.beta,
            self.gamma,
            self.mu,
            self.terms + (name,),
            np.append(self.values, real_number(name, value)),
            self.gains,
            self.phases,
            self.smoothing,
        )

    def only(self, names: Iterable[str]) -> AugParams:
        """The same model with only those of its terms that are in ``names`` (in its own order)."""
        keep = set(parse_terms(tuple(names), TERM_NAMES))
        cols = [k for k, t in enumerate(self.terms) if t in keep]
        return replace(self, terms=tuple(self.terms[k] for k in cols), values=self.values[cols])


@dataclass(frozen=True)
class AugFit:
    """Outcome of :func:`fit_augmented`.

    Attributes
    ----------
    params : AugParams
        The estimates.
    cost : float
        Weighted residual sum of squares (chi-square of the averaged data).
    iterations : int
        Accepted plus rejected LM iterations.
    converged : bool
        Whether a stopping rule other than the iteration cap ended the search.
    fisher : ndarray, shape (3 + T + 2m, 3 + T + 2m)
        ``J^T W J`` ordered ``[beta, gamma, mu, q_1 .. q_T, g_0, phi_0, g_1, phi_1, ...]``.
    covariance : ndarray
        Its inverse, NaN-filled when the Fisher matrix is singular.
    outputs : tuple of ndarray
        Model outputs ``y_i`` at the estimates.
    stop : str
        The stopping rule that ended the search: ``"ftol"`` (the cost stopped decreasing), ``"xtol"`` (the
        step became negligible), ``"no_decrease"`` (no step decreases the cost), ``"max_iter"``.
    active : tuple of str
        The constraints the estimates sit on and that hold them there, e.g. ``"beta=gamma"`` (the Bouc-Wen
        condition beta >= gamma), ``"mu=lower"``, ``"sensor_lag=0"``, ``"play=upper"``: the data pull the
        model beyond its admissible range there.
    """

    params: AugParams
    cost: float
    iterations: int
    converged: bool
    fisher: FloatArray
    covariance: FloatArray
    outputs: tuple[FloatArray, ...] = field(default_factory=tuple)
    stop: str = "ftol"
    active: tuple[str, ...] = ()

    def standard_error(self, name: str) -> float:
        """Standard error of a shared parameter (``beta``, ``gamma``, ``mu`` or an active term); NaN when
        the Fisher matrix is singular."""
        names = self.params.names
        if name not in names:
            if name not in HYSTERESIS_NAMES:
                parse_terms([name], TERM_NAMES)
            raise InvalidParameterError(f"{name!r} is not a fitted parameter; the fitted ones are {names}")
        i = names.index(name)
        return float(np.sqrt(self.covariance[i, i]))


def _auto_substeps(p: int) -> int:
    """RK4 steps per sample of the loop solvers: a step of at most 2 pi/2048 rad (identify's rule)."""
    return max(2, math.ceil(2048 / p))


#: Smallest reciprocal condition number of the Jacobi-scaled Fisher matrix that is inverted (as design.md 5).
COVARIANCE_RCOND_MIN = 1e-12


def _fit_substeps(exps: Sequence[AugExperiment], substeps: Optional[int]) -> int:
    """The count of a fit's experiments without their own: the largest need (auto), or the one given."""
    if substeps is None:
        return max(_auto_substeps(e.ybar.size) for e in exps)
    return _count("substeps", substeps, 1)


def _covariance(fisher: FloatArray) -> FloatArray:
    """``fisher^-1``, NaN-filled when the Jacobi-scaled matrix is not positive definite or its reciprocal
    condition number is below :data:`COVARIANCE_RCOND_MIN` (a direction the data do not fix)."""
    nan = np.full_like(fisher, np.nan)
    diag = np.diag(fisher)
    if not np.all(np.isfinite(fisher)) or np.any(diag <= 0.0):
        return nan
    d = np.sqrt(diag)
    scaled = fisher / np.outer(d, d)
    eig = np.linalg.eigvalsh(0.5 * (scaled + scaled.T))
    if eig[0] <= COVARIANCE_RCOND_MIN * eig[-1]:
        return nan
    cov = np.linalg.inv(scaled) / np.outer(d, d)
    return np.asarray(0.5 * (cov + cov.T), dtype=np.float64)


def _rust_kinds(terms: Sequence[str]) -> list[str]:
    """The kinds the core parses for these code names (the registry's :attr:`Term.rust_kind`)."""
    return [TERMS[t].rust_kind for t in terms]


def _count(name: str, value: int, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise InvalidParameterError(f"{name} = {value!r} must be an integer >= {minimum}")
    return int(value)


def _input_shape(experiment: AugExperiment) -> dict[str, Any]:
    """The core's ``input_shape`` keyword when the experiment's measured input is not a pure sine."""
    return {"input_shape": experiment.input_shape} if experiment.input_shape.size else {}


def _smoothing(params: AugParams) -> dict[str, Any]:
    """The core's ``coulomb_smoothing`` keyword when ``params`` sets another width than the default."""
    return {} if params.smoothing == COULOMB_SMOOTHING else {"coulomb_smoothing": params.smoothing}


def _fit_inputs(experiments: Sequence[AugExperiment], start: AugParams) -> tuple[AugExperiment, ...]:
    """:func:`fit_augmented`'s experiments as a tuple, checked against ``start`` (named errors)."""
    exps = tuple(experiments)
    if not exps:
        raise InsufficientDataError("fit_augmented needs at least one experiment")
    for i, e in enumerate(exps):
        if not isinstance(e, AugExperiment):
            raise InvalidParameterError(f"experiments[{i}] is a {type(e).__name__}, not an AugExperiment")
    if not isinstance(start, AugParams):
        raise InvalidParameterError(f"start is a {type(start).__name__}, not an AugParams")
    if start.gains.size != len(exps):
        raise InvalidParameterError(
            f"{len(exps)} experiments but the start has {start.gains.size} gains and phases"
        )
    return exps


def fit_augmented(
    experiments: Sequence[AugExperiment],
    start: AugParams,
    *,
    max_iter: int = 200,
    substeps: Optional[int] = None,
    mu_lo: float = 1.0,
    mu_hi: float = float("inf"),
    backend: Literal["rust", "numpy"] = "rust",
    stall: tuple[float, ...] = (0, 0.0),
) -> AugFit:
    """Joint Levenberg-Marquardt of the augmented model over every experiment (design.md 9.3).

    Parameters
    ----------
    experiments : sequence of AugExperiment
        At least one.
    start : AugParams
        Starting point: its terms are the ones fitted; one gain and phase per experiment.
    max_iter : int
        Iteration cap (accepted plus rejected steps).
    substeps : int, optional
        RK4 steps per sample of the loop solvers; default ``max(2, ceil(2048/P))`` for the largest need.
        An experiment with its own :attr:`AugExperiment.substeps` is evaluated at that count instead.
    mu_lo, mu_hi : float
        The admissible mu bracket ``(mu_lo, mu_hi]``, ``mu_lo >= 1``.
    backend : {"rust", "numpy"}
        The Rust core or the NumPy reference.
    stall : tuple
        ``(window, rtol[, step_rtol])``: the core's stall rules (stop ``"stall"``; :func:`_stall`), 0: off.

    Returns
    -------
    AugFit

    Raises
    ------
    InvalidParameterError
        Mismatched lengths, an inadmissible start, a bad bracket or backend.
    InsufficientDataError
        No experiment.
    """
    exps = _fit_inputs(experiments, start)
    max_iter = _count("max_iter", max_iter, 1)
    steps = _fit_substeps(exps, substeps)
    mu_lo, mu_hi = float(mu_lo), float(mu_hi)
    if not math.isfinite(mu_lo) or mu_lo < 1.0 or math.isnan(mu_hi) or mu_hi <= mu_lo:
        raise InvalidParameterError(
            f"the mu bracket ({mu_lo}, {mu_hi}] must have a finite lower end >= 1 below its upper end"
        )
    core = get_backend(backend).augmented
    shared, gains, phases, cost, iterations, converged, fisher, outputs, stop, active = core.augmented_refine(
        [e.ybar for e in exps],
        np.array([e.amplitude for e in exps]),
        np.array([e.frequency for e in exps]),
        np.array([e.grid_phase for e in exps]),
        np.array([e.weight for e in exps]),
        _rust_kinds(start.terms),
        start.shared,
        np.asarray(start.gains),
        np.asarray(start.phases),
        max_iter=max_iter,
        substeps=steps,
        mu_lo=mu_lo,
        mu_hi=mu_hi,
        waveforms=[e.waveform for e in exps],
        experiment_substeps=[steps if e.substeps is None else e.substeps for e in exps],
        **_shapes(exps),
        **_smoothing(start),
        **_stall(stall),
    )
    shared = np.asarray(shared, dtype=np.float64)
    params = AugParams(
        float(shared[0]),
        float(shared[1]),
        float(shared[2]),
        start.terms,
        shared[3:],
        gains,
        phases,
        start.smoothing,
    )
    fisher = np.asarray(fisher, dtype=np.float64)
    fisher.flags.writeable = False
    covariance = _covariance(fisher)
    covariance.flags.writeable = False
    outs = tuple(np.asarray(y, dtype=np.float64) for y in outputs)
    for y in outs:
        y.flags.writeable = False
    return AugFit(
        params,
        float(cost),
        int(iterations),
        bool(converged),
        fisher,
        covariance,
        outs,
        str(stop),
        tuple(str(a) for a in active),
    )


@dataclass(frozen=True)
class AugOutput:
    """The model output on one experiment's grid with its derivatives (:func:`augmented_output`).

    Attributes
    ----------
    y : ndarray, shape (P,)
        The model output (units of the output).
    jacobian : ndarray, shape (P, 3 + T)
        ``dy / d[beta, gamma, mu, q_1 .. q_T]`` (the order of :attr:`AugParams.shared`).
    own_jacobian : ndarray, shape (P, 2)
        ``dy / d(g_i, phi_i)``, the experiment's own gain and phase.
    """

    y: FloatArray
    jacobian: FloatArray
    own_jacobian: FloatArray


def _stall(stall: tuple[float, ...]) -> dict[str, Any]:
    """The refinement's stall keywords of the rules that are on (none otherwise): ``window > 0``, from the
    second window of that many iterations on, stop at a window's end when it lowered the cost by at most
    ``rtol`` of it (the damping runs on across the windows); ``step_rtol > 0``, stop after an accepted step
    that lowered the cost by at most that fraction of it when the Gauss-Newton step from its end predicts no
    larger decrease (``rust/refine.rs`` ``Options``)."""
    window, rtol, step = (*stall, 0.0)[:3]
    out: dict[str, Any] = {"stall_window": int(window), "stall_rtol": float(rtol)} if window else {}
    return {**out, "step_rtol": float(step)} if step else out


def _shapes(exps: Sequence[AugExperiment]) -> dict[str, Any]:
    """The refinement's ``input_shapes`` keyword when some experiment's input is not a pure sine (none
    otherwise, so a backend without it still fits pure sines)."""
    if not any(e.input_shape.size for e in exps):
        return {}
    return {"input_shapes": [e.input_shape for e in exps]}


@overload
def augmented_output(
    experiment: AugExperiment,
    params: AugParams,
    i: int,
    *,
    substeps: Optional[int] = None,
    jacobian: Literal[False] = False,
    backend: Literal["rust", "numpy"] = "rust",
) -> FloatArray: ...
@overload
def augmented_output(
    experiment: AugExperiment,
    params: AugParams,
    i: int,
    *,
    substeps: Optional[int] = None,
    jacobian: Literal[True],
    backend: Literal["rust", "numpy"] = "rust",
) -> AugOutput: ...
def augmented_output(
    experiment: AugExperiment,
    params: AugParams,
    i: int,
    *,
    substeps: Optional[int] = None,
    jacobian: bool = False,
    backend: Literal["rust", "numpy"] = "rust",
) -> Union[FloatArray, AugOutput]:
    """The model output ``y`` on ``experiment``'s grid with ``params`` and experiment index ``i``'s gain and
    phase (shape (P,), units of the output); with ``jacobian=True`` an :class:`AugOutput` holding its
    derivatives too.

    Parameters
    ----------
    experiment : AugExperiment
        Its grid, amplitude, frequency, grid phase and waveform are used (not its ``ybar``).
    params : AugParams
        The model; ``params.gains[i]`` and ``params.phases[i]`` are the experiment's own.
    i : int
        Index of the experiment's gain and phase in ``params``.
    substeps : int, optional
        RK4 steps per sample; default ``max(2, ceil(2048/P))``; the experiment's own
        :attr:`AugExperiment.substeps` when it has one.
    jacobian : bool
        Return the derivatives too.
    backend : {"rust", "numpy"}
        The Rust core or the NumPy reference.

    Raises
    ------
    InvalidParameterError
        A wrong type, an index out of range, a bad count or backend, an inadmissible model.
    """
    if not isinstance(experiment, AugExperiment):
        raise InvalidParameterError(f"experiment is a {type(experiment).__name__}, not an AugExperiment")
    if not isinstance(params, AugParams):
        raise InvalidParameterError(f"params is a {type(params).__name__}, not an AugParams")
    if isinstance(i, bool) or not isinstance(i, (int, np.integer)) or not 0 <= i < params.gains.size:
        raise InvalidParameterError(f"i = {i!r} must index one of the {params.gains.size} gains")
    p = experiment.ybar.size
    steps = _auto_substeps(p) if substeps is None else _count("substeps", substeps, 1)
    if experiment.substeps is not None:
        steps = experiment.substeps
    y, jac, own = get_backend(backend).augmented.augmented_output(
        p,
        experiment.amplitude,
        experiment.frequency,
        experiment.grid_phase,
        _rust_kinds(params.terms),
        params.shared,
        float(params.gains[i]),
        float(params.phases[i]),
        steps,
        experiment.waveform,
        **_input_shape(experiment),
        **_smoothing(params),
    )
    out = np.asarray(y, dtype=np.float64)
    if not jacobian:
        return out
    return AugOutput(out, np.asarray(jac, dtype=np.float64), np.asarray(own, dtype=np.float64))
