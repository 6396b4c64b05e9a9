"""Parameters that follow an operating variable (issue #21 item 3): one joint fit over several levels.

At each level ``v_l`` of an operating variable (a coil current, a temperature, a pre-load) the same
experiments were run: experiment ``i`` of every level is the same test (stroke, frequency).  The augmented
model of design.md 9.1 is fitted to all levels at once, every parameter a polynomial of degree ``d`` (0, 1 or
2) in the variable, in coordinates where a polynomial stays admissible:

* the Bouc-Wen element by ``w_u = (beta + gamma)^(-1/mu)`` (the saturation level, in units of the
  output: a yield force; kept > 0), ``log(mu - 1)`` (mu > 1) and ``log rho``,
  ``rho = (beta - gamma) / (beta + gamma) > 0`` (the edge ``beta = gamma`` the fits of a damper often end
  on is approached, never crossed; a start on an edge begins at :data:`EDGE_START` from it);
* each term by its own parameter (:data:`bouc_wen_id.augmented.TERM_NAMES`, in physical units);
* each experiment's linear part by ``log |g_i|`` (its sign fixed by the start; or ``log(|g_i| / w_u)``
  with ``relative_gains``) and ``phi_i``.

Both are in ``z = (v - centre) / half_range`` of the fitted levels (``z`` in ``[-1, 1]`` over them). The
monotone spline is the shape-constrained one of Ramsay's I-splines (*Monotone regression splines in action*,
Statistical Science 3(4), 1988): ``f(z) = c_0 + c_1 I_0(z) + c_2 I_1(z)`` with the quadratic I-splines of
knots ``-1, 1`` (the integrals of the two linear half-hats ``(1 - z)/2`` and ``(1 + z)/2``, each rising from
0 to 1 over the levels), held at its end values beyond them: outside the tested range every parameter is
taken at the nearest tested level's value, never extrapolated. With ``c_1, c_2`` of one sign the function is
monotone: each coordinate's direction is the slope's sign in the joint degree-1 fit, which also starts the
spline (over the levels the line is a spline with ``c_1 = c_2``: the spline never fits the levels worse than
it), and the fit holds the two coefficients to it (bounds of the trust-region solver). Per-level fits do not
set the direction: a parameter traded against a gain can trend either way from level to level. Three
coefficients, as a quadratic (the same functions between the extreme levels, a quadratic whose slope keeps one
sign there), but it cannot turn back between the levels, and beyond them it stays where a polynomial
extrapolates (on the MR damper a linear or quadratic law extrapolated to 0 or 1 A can leave the model's range:
the prediction fails; the spline's does not). An interior knot would add a coefficient that three or four
levels cannot determine (the held-out fits of five levels have four). :func:`fit_operating` runs the
joint least squares (SciPy's trust-region reflective, the model and its Jacobian from the Rust core's
:func:`~bouc_wen_id.augmented.augmented_output`), started from per-level fits; the coefficients' covariance is
the Gauss-Newton one scaled by the residual variance (``s^2 (J^T J)^-1``, the misfit taken as white), and an
interval of a parameter at ``v`` is the delta method's (normal, 95 % by default; for the spline a coefficient
held on its bound keeps its unconstrained variance, so the band is not narrowed by the constraint).
:func:`select_degree` chooses the form by leave-one-level-out among the polynomial degrees and the monotone
spline: the one whose fits on the other levels predict each held-out level best. A held-out level is predicted
whole (:meth:`OperatingFit.params_at`), or with its own ``(g_i, phi_i)`` refitted and the physics frozen
(:func:`refit_own`, the held-out protocol of design.md 10.4).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Optional, Union

import numpy as np
from numpy.typing import NDArray

from .augmented import TERM_NAMES, AugExperiment, AugParams, augmented_output
from .errors import BoucWenIdError, InsufficientDataError, InvalidParameterError
from .terms import parse_terms

__all__ = [
    "HYSTERESIS_COORDINATES",
    "MONOTONE",
    "FORMS",
    "OperatingFit",
    "DegreeChoice",
    "fit_operating",
    "held_out_score",
    "select_degree",
    "refit_own",
    "nrmse",
    "coordinates_of",
    "n_basis",
]

FloatArray = NDArray[np.float64]

#: The Bouc-Wen element's coordinates, ahead of the terms' parameters.
HYSTERESIS_COORDINATES = ("w_u", "log_mu_minus_1", "log_rho")
#: How far from an edge (mu = 1, beta = gamma) a start on it begins: ``mu - 1`` and ``rho`` at least this.
EDGE_START = 1e-3
#: The smallest ``mu - 1`` a polynomial gives (below it mu would round to 1, outside the model).
MU_GAP = 1e-9
#: Highest polynomial degree.
MAX_DEGREE = 2
#: Two-sided normal quantile of a 95 % interval.
Z95 = 1.959963984540054
#: The monotone spline's name where a degree is asked for (``fit_operating(..., degree=MONOTONE)``).
MONOTONE = "monotone"
#: Every form :func:`select_degree` tries by default: the polynomial degrees and the monotone spline.
FORMS: tuple[Union[int, str], ...] = (0, 1, 2, MONOTONE)
#: Levels the spline needs (as many as its coefficients).
MONOTONE_MIN_LEVELS = 3

#: A polynomial degree or :data:`MONOTONE`.
Form = Union[int, str]


def _ispline(z: float) -> tuple[float, float]:
    """The quadratic I-splines of knots -1, 1 at ``z``, held at their end values beyond (module docstring)."""
    z = min(max(z, -1.0), 1.0)
    return 0.25 * (3.0 + 2.0 * z - z * z), 0.25 * (1.0 + z) ** 2


def n_basis(form: Form) -> int:
    """Coefficients per coordinate: ``degree + 1``, or 3 for the monotone spline."""
    return 3 if form == MONOTONE else int(form) + 1


def _basis(z: float, form: Form) -> FloatArray:
    if form == MONOTONE:
        return np.array([1.0, *_ispline(z)], dtype=np.float64)
    return np.array([z**k for k in range(int(form) + 1)], dtype=np.float64)


def _check_form(form: object) -> Form:
    if form == MONOTONE:
        return MONOTONE
    if isinstance(form, bool) or not isinstance(form, (int, np.integer)) or not 0 <= form <= MAX_DEGREE:
        raise InvalidParameterError(f"degree = {form!r} must be 0, 1, {MAX_DEGREE} or {MONOTONE!r}")
    return int(form)


def _levels_needed(form: Form) -> int:
    return MONOTONE_MIN_LEVELS if form == MONOTONE else int(form) + 1


def coordinates_of(
    params: AugParams, relative_gains: bool = False
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(shared, log|g|, phi)`` coordinates of one level's :class:`AugParams` (module docstring); with
    ``relative_gains`` the middle one is ``log(|g| / w_u)``."""
    s = params.beta + params.gamma
    if not s > 0.0:
        raise InvalidParameterError(f"beta + gamma = {s} must be > 0")
    w_u = s ** (-1.0 / params.mu)
    rho = (params.beta - params.gamma) / s
    shared = np.concatenate(
        [[w_u, math.log(max(params.mu - 1.0, EDGE_START)), math.log(max(rho, EDGE_START))], params.values]
    )
    log_g = np.log(np.abs(params.gains)) - (math.log(w_u) if relative_gains else 0.0)
    return shared, log_g, np.asarray(params.phases, dtype=np.float64)


def _params_from(
    shared: FloatArray,
    log_g: FloatArray,
    phi: FloatArray,
    signs: FloatArray,
    terms: tuple[str, ...],
    relative_gains: bool = False,
) -> tuple[AugParams, FloatArray]:
    """The :class:`AugParams` of coordinates, and ``d[beta, gamma, mu] / d[its 3 coordinates]``."""
    w_u, lm, lr = (float(v) for v in shared[:3])
    if not w_u > 0.0:
        raise InvalidParameterError(f"w_u = {w_u} must be > 0 (a saturation level)")
    try:
        # mu - 1 floored at MU_GAP (derivative 0 there): a polynomial far out in log(mu - 1) would round mu
        # to 1.
        gap, dgap = (math.exp(lm), 1.0) if lm > math.log(MU_GAP) else (MU_GAP, 0.0)
        mu = 1.0 + gap
        rho = math.exp(lr)
        log_w_u = math.log(w_u)
        s = math.exp(-mu * log_w_u)
    except OverflowError:
        raise InvalidParameterError(
            f"the coordinates (w_u = {w_u}, log(mu - 1) = {lm}, log rho = {lr}) overflow the model: the "
            "function of the variable was extrapolated too far"
        ) from None
    beta, gamma = 0.5 * s * (1.0 + rho), 0.5 * s * (1.0 - rho)
    ds = np.array(
        [-mu * s / w_u, -log_w_u * s * (mu - 1.0) * dgap, 0.0]
    )  # d s / d(w_u, log(mu - 1), log rho)
    jac = np.zeros((3, 3))
    jac[0] = 0.5 * (1.0 + rho) * ds + np.array([0.0, 0.0, 0.5 * s * rho])
    jac[1] = 0.5 * (1.0 - rho) * ds - np.array([0.0, 0.0, 0.5 * s * rho])
    jac[2] = [0.0, (mu - 1.0) * dgap, 0.0]
    params = AugParams(
        beta,
        gamma,
        mu,
        terms,
        np.asarray(shared[3:], dtype=np.float64),
        signs * np.exp(log_g) * (w_u if relative_gains else 1.0),
        phi,
    )
    return params, jac


@dataclass(frozen=True)
class OperatingFit:
    """A joint fit over levels of an operating variable (module docstring).

    ``coef`` holds one row of :func:`n_basis` coefficients per coordinate (``degree + 1`` polynomial ones, or
    the monotone spline's four), in the order :attr:`names`: :data:`HYSTERESIS_COORDINATES`, the terms, then
    ``log_g_i`` and ``phi_i`` per experiment. ``degree`` is the polynomial degree or :data:`MONOTONE`;
    ``directions`` the spline's direction per coordinate (+1 rising, -1 falling; empty for a polynomial).
    """

    levels: FloatArray
    degree: Form
    terms: tuple[str, ...]
    signs: FloatArray
    centre: float
    half_range: float
    coef: FloatArray
    covariance: FloatArray
    cost: float
    residual_variance: float
    iterations: int
    #: The gains' coordinates are ``log(|g_i| / w_u)`` (:func:`fit_operating`).
    relative_gains: bool = False
    directions: FloatArray = field(default_factory=lambda: np.zeros(0))

    @property
    def experiments(self) -> int:
        return int(self.signs.size)

    @property
    def names(self) -> tuple[str, ...]:
        own = [f"{k}_{i}" for i in range(self.experiments) for k in ("log_g", "phi")]
        return HYSTERESIS_COORDINATES + self.terms + tuple(own)

    def _z(self, v: float) -> float:
        return (float(v) - self.centre) / self.half_range

    def coordinate(self, name: str, v: float) -> float:
        """The coordinate ``name`` (one of :attr:`names`) at the variable's value ``v``."""
        k = self._index(name)
        return float(self.coef[k] @ _basis(self._z(v), self.degree))

    def interval(self, name: str, v: float, z: float = Z95) -> tuple[float, float, float]:
        """``(value, low, high)`` of coordinate ``name`` at ``v``: the delta method, ``z`` standard errors."""
        k = self._index(name)
        b = _basis(self._z(v), self.degree)
        n = n_basis(self.degree)
        block = self.covariance[k * n : (k + 1) * n, k * n : (k + 1) * n]
        value = float(self.coef[k] @ b)
        se = math.sqrt(max(float(b @ block @ b), 0.0))
        return value, value - z * se, value + z * se

    def _index(self, name: str) -> int:
        if name not in self.names:
            raise InvalidParameterError(f"unknown coordinate {name!r}; the coordinates are {self.names}")
        return self.names.index(name)

    def params_at(self, v: float) -> AugParams:
        """The model at the variable's value ``v`` (every parameter from its polynomial)."""
        return self._evaluate(v)[0]

    def _evaluate(self, v: float) -> tuple[AugParams, FloatArray]:
        values = self.coef @ _basis(self._z(v), self.degree)
        n_shared = 3 + len(self.terms)
        own = values[n_shared:].reshape(-1, 2)
        return _params_from(
            values[:n_shared], own[:, 0], own[:, 1], self.signs, self.terms, self.relative_gains
        )


def nrmse(experiment: AugExperiment, params: AugParams, i: int) -> float:
    """``|ybar - y| / |ybar - mean(ybar)|`` of experiment ``i`` under ``params``."""
    y = augmented_output(experiment, params, i)
    return float(
        np.linalg.norm(experiment.ybar - y) / np.linalg.norm(experiment.ybar - np.mean(experiment.ybar))
    )


def refit_own(experiment: AugExperiment, params: AugParams, i: int) -> AugParams:
    """``params`` with experiment ``i``'s own ``(g_i, phi_i)`` refitted to it, the physics frozen."""
    from scipy.optimize import least_squares  # type: ignore[import-untyped]

    def model(x: FloatArray) -> AugParams:
        gains, phases = params.gains.copy(), params.phases.copy()
        gains[i], phases[i] = x
        return replace(params, gains=gains, phases=phases)

    def res(x: FloatArray) -> FloatArray:
        return np.asarray(augmented_output(experiment, model(x), i) - experiment.ybar)

    def jac(x: FloatArray) -> FloatArray:
        return np.asarray(augmented_output(experiment, model(x), i, jacobian=True).own_jacobian)

    x0 = np.array([params.gains[i], params.phases[i]])
    sol = least_squares(res, x0, jac=jac, method="lm", max_nfev=200)
    return model(np.asarray(sol.x))


def _check(
    levels: Sequence[float], experiments: Sequence[Sequence[AugExperiment]], starts: Sequence[AugParams]
) -> int:
    if not (len(levels) == len(experiments) == len(starts)):
        raise InvalidParameterError(
            f"{len(levels)} levels, {len(experiments)} experiment lists and {len(starts)} starts: one each"
        )
    if len(levels) < 1:
        raise InsufficientDataError("an operating fit needs at least one level")
    m = len(experiments[0])
    if m < 1 or any(len(e) != m for e in experiments):
        raise InvalidParameterError("every level must hold the same experiments, in the same order")
    if any(s.gains.size != m for s in starts):
        raise InvalidParameterError(f"every start needs {m} gains and phases")
    if len(set(float(v) for v in levels)) != len(levels):
        raise InvalidParameterError("the levels of the operating variable must be distinct")
    return m


class _Problem:
    """The stacked residual and Jacobian of a joint fit over levels."""

    def __init__(
        self,
        levels: FloatArray,
        experiments: Sequence[Sequence[AugExperiment]],
        terms: tuple[str, ...],
        signs: FloatArray,
        degree: Form,
        centre: float,
        half_range: float,
        relative_gains: bool,
    ) -> None:
        self.levels, self.experiments, self.terms, self.signs = levels, experiments, terms, signs
        self.relative_gains = relative_gains
        self.degree, self.centre, self.half_range = degree, centre, half_range
        self.n_shared = 3 + len(terms)
        self.n_coord = self.n_shared + 2 * signs.size
        #: What a refused trial point returns (set from the start's residual once it is known).
        self.refused: Optional[tuple[FloatArray, FloatArray]] = None
        #: The spline's direction per coordinate (set by :func:`_start`).
        self.directions = np.zeros(0)

    def fit_of(self, theta: FloatArray, cov: FloatArray, cost: float, s2: float, nfev: int) -> OperatingFit:
        coef = theta.reshape(self.n_coord, n_basis(self.degree))
        return OperatingFit(
            self.levels,
            self.degree,
            self.terms,
            self.signs,
            self.centre,
            self.half_range,
            coef,
            cov,
            cost,
            s2,
            nfev,
            self.relative_gains,
            self.directions,
        )

    def evaluate(self, theta: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Residual and Jacobian; a trial point the model refuses (no loop, an inadmissible value) gets a
        large finite residual, so that the trust region shrinks away from it."""
        try:
            return self._evaluate(theta)
        except (BoucWenIdError, OverflowError):
            if self.refused is None:
                raise
            return self.refused

    def _evaluate(self, theta: FloatArray) -> tuple[FloatArray, FloatArray]:
        fit = self.fit_of(theta, np.zeros((0, 0)), 0.0, 0.0, 0)
        rows, jacs = [], []
        for v, exps in zip(self.levels, self.experiments):
            params, jac3 = fit._evaluate(float(v))
            basis = _basis(fit._z(float(v)), self.degree)
            for i, e in enumerate(exps):
                out = augmented_output(e, params, i, jacobian=True)
                sw = math.sqrt(e.weight)
                rows.append(sw * (out.y - e.ybar))
                dcoord = np.zeros((e.ybar.size, self.n_coord))
                dcoord[:, :3] = out.jacobian[:, :3] @ jac3
                dcoord[:, 3 : self.n_shared] = out.jacobian[:, 3:]
                k = self.n_shared + 2 * i
                dcoord[:, k] = out.own_jacobian[:, 0] * params.gains[i]
                if self.relative_gains:  # g_i = sign w_u exp(log_g_i): through w_u too
                    dcoord[:, 0] += out.own_jacobian[:, 0] * params.gains[i] / float(fit.coordinate("w_u", v))
                dcoord[:, k + 1] = out.own_jacobian[:, 1]
                jacs.append(sw * (dcoord[:, :, None] * basis[None, None, :]).reshape(e.ybar.size, -1))
        return np.concatenate(rows), np.vstack(jacs)


def _start(problem: _Problem, starts: Sequence[AugParams]) -> FloatArray:
    """Each coordinate's polynomial fitted (least squares) to its per-level start values."""
    z = (problem.levels - problem.centre) / problem.half_range
    design = np.array([_basis(float(zi), problem.degree) for zi in z])
    values = []
    for s in starts:
        shared, log_g, phi = coordinates_of(s, problem.relative_gains)
        values.append(np.concatenate([shared, np.column_stack([log_g, phi]).ravel()]))
    coef = np.linalg.lstsq(design, np.array(values), rcond=None)[0].T
    return np.asarray(coef.ravel(), dtype=np.float64)


def _bounds(direction: float) -> tuple[FloatArray, FloatArray]:
    """The spline's coefficient bounds for one coordinate: the intercept free, the rest of ``direction``'s
    sign."""
    inf = math.inf
    if direction > 0.0:
        return np.array([-inf, 0.0, 0.0]), np.full(3, inf)
    return np.full(3, -inf), np.array([inf, 0.0, 0.0])


def fit_operating(
    levels: Sequence[float],
    experiments: Sequence[Sequence[AugExperiment]],
    starts: Sequence[AugParams],
    degree: Form,
    *,
    relative_gains: bool = False,
    max_nfev: int = 200,
) -> OperatingFit:
    """One joint fit of every level, each parameter a polynomial of ``degree`` in the variable, or a monotone
    spline (``degree="monotone"``; module docstring).

    Parameters
    ----------
    levels : sequence of float
        The operating variable's value at each level (distinct).
    experiments : sequence of sequences of AugExperiment
        Per level, the same experiments in the same order (experiment ``i`` is one test condition).
    starts : sequence of AugParams
        Per level, a fit of that level alone (:func:`~bouc_wen_id.augmented.fit_augmented`); the same terms
        at every level. The polynomials start as least-squares fits to them; the gains' signs are the first
        start's.
    degree : int or "monotone"
        0, 1 or 2, at most ``len(levels) - 1``; or :data:`MONOTONE` (at least 3 levels).
    relative_gains : bool
        Take each gain relative to the saturation level, ``log(|g_i| / w_u)`` (the inverse of the travel to
        the loop's knee), instead of ``log |g_i|``: for a device whose yield level follows the variable while
        the knee stays at a similar travel (an MR damper: its force level follows the current, not the
        stiffness of its loop's knee relative to it).

    Raises
    ------
    InvalidParameterError
        Mismatched lengths, repeated levels, different terms, a degree out of range.
    InsufficientDataError
        Fewer levels than ``degree + 1`` (3 for the spline).
    """
    from scipy.optimize import least_squares

    _check(levels, experiments, starts)
    degree = _check_form(degree)
    if len(levels) < _levels_needed(degree):
        what = "the monotone spline" if degree == MONOTONE else f"a degree-{degree} polynomial"
        raise InsufficientDataError(f"{what} needs {_levels_needed(degree)} levels, got {len(levels)}")
    terms = parse_terms(starts[0].terms, TERM_NAMES)
    if any(s.terms != terms for s in starts):
        raise InvalidParameterError("every level's start must carry the same terms, in the same order")
    lv = np.asarray(levels, dtype=np.float64)
    lo, hi = float(lv.min()), float(lv.max())
    half = 0.5 * (hi - lo) if hi > lo else 1.0
    signs = np.where(np.asarray(starts[0].gains) < 0.0, -1.0, 1.0)
    problem = _Problem(lv, experiments, terms, signs, degree, 0.5 * (hi + lo), half, bool(relative_gains))
    if degree == MONOTONE:
        # The joint line sets each coordinate's direction and is the spline's start (c = (a0 - a1, a1, a1)
        # is the line a0 + a1 z exactly): the spline is never worse than the line on the fitted levels.
        line = fit_operating(
            levels, experiments, starts, 1, relative_gains=relative_gains, max_nfev=max_nfev
        ).coef
        problem.directions = np.where(line[:, 1] < 0.0, -1.0, 1.0)
        theta0 = np.column_stack([line[:, 0] - line[:, 1], line[:, 1], line[:, 1]]).ravel()
    else:
        theta0 = _start(problem, starts)
    bounds: tuple[FloatArray, FloatArray] = (np.full(theta0.size, -math.inf), np.full(theta0.size, math.inf))
    if degree == MONOTONE:
        pairs = [_bounds(float(d)) for d in problem.directions]
        bounds = (np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs]))
        theta0 = np.clip(theta0, *bounds)
    r0, j0 = problem.evaluate(theta0)
    problem.refused = (np.full_like(r0, 1e3 * max(float(np.max(np.abs(r0))), 1.0)), np.zeros_like(j0))
    cache: dict[bytes, tuple[FloatArray, FloatArray]] = {theta0.tobytes(): (r0, j0)}

    def both(theta: FloatArray) -> tuple[FloatArray, FloatArray]:
        key = theta.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = problem.evaluate(theta)
        return cache[key]

    sol = least_squares(
        lambda th: both(th)[0],
        theta0,
        jac=lambda th: both(th)[1],
        method="trf",
        x_scale="jac",
        max_nfev=max_nfev,
        bounds=bounds,
    )
    r, jac = both(np.asarray(sol.x))
    dof = max(r.size - sol.x.size, 1)
    s2 = float(r @ r) / dof
    cov = s2 * np.linalg.pinv(jac.T @ jac)
    return problem.fit_of(np.asarray(sol.x), cov, float(r @ r), s2, int(sol.nfev))


@dataclass(frozen=True)
class DegreeChoice:
    """:func:`select_degree`'s outcome: the form (a degree or :data:`MONOTONE`), and per form tried the
    held-out score of each level (the mean squared NRMSE of its experiments predicted whole by the fit on
    the other levels)."""

    degree: Form
    scores: dict[Form, list[float]]

    def total(self, degree: Form) -> float:
        return float(np.mean(self.scores[degree]))


def held_out_score(fit: OperatingFit, level: float, experiments: Sequence[AugExperiment]) -> float:
    """Mean squared NRMSE of ``experiments`` predicted whole at ``level``."""
    params = fit.params_at(level)
    return float(np.mean([nrmse(e, params, i) ** 2 for i, e in enumerate(experiments)]))


def select_degree(
    levels: Sequence[float],
    experiments: Sequence[Sequence[AugExperiment]],
    starts: Sequence[AugParams],
    degrees: Sequence[Form] = FORMS,
    *,
    relative_gains: bool = False,
    max_nfev: int = 200,
) -> DegreeChoice:
    """The form (polynomial degree or monotone spline, :data:`FORMS` by default) whose fits on all levels but
    one predict the held-out level best (leave-one-level-out); ties go to the polynomial of lowest degree.

    A form needs one level more than its fit does (``degree + 2``; 4 for the spline); those it cannot try
    are skipped. A prediction that fails (an inadmissible model) scores infinity.

    Raises
    ------
    InsufficientDataError
        Fewer than two levels: nothing can be held out.
    """
    _check(levels, experiments, starts)
    if len(levels) < 2:
        raise InsufficientDataError("choosing a degree by held-out level needs at least two levels")
    scores: dict[Form, list[float]] = {}
    for d in (_check_form(f) for f in degrees):
        if len(levels) < _levels_needed(d) + 1:
            continue
        row = []
        for out in range(len(levels)):
            keep = [j for j in range(len(levels)) if j != out]
            fit = fit_operating(
                [levels[j] for j in keep],
                [experiments[j] for j in keep],
                [starts[j] for j in keep],
                d,
                relative_gains=relative_gains,
                max_nfev=max_nfev,
            )
            try:
                row.append(held_out_score(fit, levels[out], experiments[out]))
            except BoucWenIdError:
                row.append(math.inf)
        scores[d] = row
    if not scores:
        raise InsufficientDataError(f"no degree of {list(degrees)} can be tried on {len(levels)} levels")
    best = min(scores, key=lambda d: (float(np.mean(scores[d])), n_basis(d), d == MONOTONE))
    return DegreeChoice(best, scores)
