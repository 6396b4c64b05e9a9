"""The Wiener cascade fitted to time-domain records by output error (issue #20, model class 1).

Model (alpha-normalised, as :func:`~bouc_wen_id.identify` reports it): ``x = G u`` with
``G(s) = exp(-tau s) (b_0 s^m + ... + b_m) / (s^n + a_1 s^(n-1) + ... + a_n)`` (the form
:func:`~bouc_wen_id.fit_transfer_function` returns), Bouc-Wen (2a) with alpha = 1 on ``x``, ``y = w``.
Each record is simulated from rest at its first sample (``xs = 0``, ``w = w0``; ``w0`` fitted on request)
by the Rust kernel ``timedomain_sensitivities`` (RK4 on the Catmull-Rom interpolant of ``u``, with the exact
Jacobian of the discrete map), the residuals ``y_sim - y`` after an optional lead-in are stacked over the
records, and :func:`~bouc_wen_id.timedomain.levenberg_marquardt` minimises their sum of squares.

Parameter vector (the kernel's layout): ``[b_0..b_m, a_1..a_n, tau, beta, gamma, mu, w0]``; ``tau`` is held
at its start value unless ``delay=True``, ``w0`` at 0 unless ``estimate_w0=True``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from .. import budget as _budget
from .._backend import Backend, get_backend
from ..errors import InvalidParameterError, NonFiniteError
from ..model import BoucWen, TransferFunction, WienerPlant
from ..terms import Inertia, Offset, Stiffness, Term, Viscous, core_terms
from ._lm import LMResult
from ._records import TimeRecord, check_memory, lead_in_samples
from ._terms import REGRESSOR_TERMS, difference_jacobian, refuse, term_bounds, term_memory, time_domain_terms

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Largest denominator degree (rust/timedomain.rs MAX_ORDER).
MAX_ORDER = 4
#: Bounds of mu (the kernel needs mu >= 1; beyond 10 the loop is a square and mu is not seen).
MU_BOUNDS = (1.0, 10.0)
#: Time constants of the slowest pole counted as G's memory (with the delay).
MEMORY_TIME_CONSTANTS = 3.0
#: The output terms on u fitted with exact regressor columns (``y = y0 + w + k u + c udot + m uddot``); every
#: other time-domain term of the registry is fitted too, by differences of the simulator with terms
#: (``_terms``).
OUTPUT_TERMS: tuple[type[Term], ...] = REGRESSOR_TERMS


@dataclass(frozen=True)
class Structure:
    """The model class: numerator degree ``m``, denominator degree ``n``, whether the delay and ``w0`` are
    fitted."""

    m: int
    n: int
    delay: bool = False
    estimate_w0: bool = False
    terms: tuple[type[Term], ...] = ()
    #: Terms whose fixed settings (a friction's smoothing) the fitted ones keep; by class, optional.
    templates: tuple[Term, ...] = ()

    def __post_init__(self) -> None:
        if not (0 <= self.m <= self.n <= MAX_ORDER):
            raise InvalidParameterError(
                f"the orders must satisfy 0 <= m <= n <= {MAX_ORDER}, got m = {self.m}, n = {self.n}"
            )
        allowed = time_domain_terms()
        for cls in self.terms:
            if not (isinstance(cls, type) and issubclass(cls, Term)):
                raise InvalidParameterError(f"terms must be term classes, got {cls!r}")
            if cls not in allowed:
                raise refuse(cls)
        if len(set(self.terms)) != len(self.terms):
            raise InvalidParameterError("each term at most once")

    @property
    def exact(self) -> bool:
        """Whether the Jacobian is the dual-number kernel's (every term a regressor term) or differences."""
        return all(cls in REGRESSOR_TERMS for cls in self.terms)

    @property
    def core_size(self) -> int:
        """Length of the kernel's parameter vector ``m + n + 6``."""
        return self.m + self.n + 6

    @property
    def size(self) -> int:
        """Length of the full parameter vector: the kernel's and one value per term."""
        return self.core_size + len(self.terms)

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the full vector's entries."""
        b = tuple(f"b{k}" for k in range(self.m + 1))
        a = tuple(f"a{j + 1}" for j in range(self.n))
        return (*b, *a, "delay", "beta", "gamma", "mu", "w0", *(c.symbol for c in self.terms))

    @property
    def free(self) -> BoolArray:
        """Which entries are fitted."""
        out = np.ones(self.size, dtype=bool)
        out[self.m + self.n + 1] = self.delay
        out[self.core_size - 1] = self.estimate_w0
        return out

    def pack(self, plant: WienerPlant) -> FloatArray:
        """The full vector of an (alpha-normalised) plant of this structure.

        Raises
        ------
        InvalidParameterError
            A plant with terms, or whose G is not of degrees ``(m, n)`` (after trimming leading zeros).
        """
        extra = [t for t in plant.terms if type(t) not in self.terms]
        if extra:
            raise InvalidParameterError(
                f"the start holds terms the structure does not fit: {', '.join(t.kind for t in extra)}"
            )
        p = plant.normalized()
        num = np.trim_zeros(np.asarray(p.linear.num, dtype=float), "f")
        den = np.asarray(p.linear.den, dtype=float)
        num, den = num / den[0], den / den[0]
        if den.size - 1 != self.n or num.size - 1 > self.m:
            raise InvalidParameterError(
                f"the start's G has degrees ({num.size - 1}, {den.size - 1}); "
                f"the structure asks ({self.m}, {self.n})"
            )
        b = np.concatenate([np.zeros(self.m + 1 - num.size), num])
        h = p.hysteresis
        # a term the start plant holds starts at its value, else at a given template's (a term instance
        # given to the fit, e.g. the diagnosis's value), else at 0
        held = (*p.terms, *self.templates)
        values = [next((t.value for t in held if type(t) is cls), 0.0) for cls in self.terms]
        return np.concatenate([b, den[1:], [p.linear.delay, h.beta, h.gamma, h.mu, h.w0], values])

    def unpack(self, theta: FloatArray) -> WienerPlant:
        """The plant of a full vector (alpha = 1)."""
        m, n = self.m, self.n
        num = np.asarray(theta[: m + 1], dtype=float)
        den = np.concatenate([[1.0], theta[m + 1 : m + 1 + n]])
        tau, beta, gamma, mu, w0 = (float(v) for v in theta[m + 1 + n : self.core_size])
        terms = tuple(self.make_term(cls, float(v)) for cls, v in zip(self.terms, theta[self.core_size :]))
        return WienerPlant(TransferFunction(num, den, tau), BoucWen(beta, gamma, mu, 1.0, w0), terms)

    def make_term(self, cls: type[Term], value: float) -> Term:
        """The term ``cls`` at ``value``, with the fixed settings of its template (validated)."""
        for t in self.templates:
            if type(t) is cls:
                return t.with_value(value)
        return cls(value)  # type: ignore[call-arg]

    def bounds(self, theta0: FloatArray, max_delay: float) -> tuple[FloatArray, FloatArray]:
        """Box bounds: denominator coefficients > 0 (necessary for stability), ``0 <= tau <= max_delay``,
        ``beta > 0``, ``mu`` in :data:`MU_BOUNDS`; the rest free."""
        lo = np.full(self.size, -np.inf)
        hi = np.full(self.size, np.inf)
        m, n = self.m, self.n
        lo[m + 1 : m + 1 + n] = 0.0
        lo[m + 1 + n], hi[m + 1 + n] = 0.0, max(max_delay, float(theta0[m + 1 + n]) + 1e-12)
        lo[m + n + 2] = 0.0
        lo[m + n + 4], hi[m + n + 4] = MU_BOUNDS
        for j, cls in enumerate(self.terms):
            lo[self.core_size + j], hi[self.core_size + j] = term_bounds(cls)
        return lo, hi

    def scales(self, theta: FloatArray, y_scale: float, u_scale: float, dt: float) -> FloatArray:
        """Natural magnitude of each entry (the finite-difference steps' floor): G's coefficients their
        block's size, the delay one sample, beta and gamma their sum's size, ``w0`` the output RMS, each
        term its own units at the data's output and input RMS (:meth:`Term.scale_factor`)."""
        m, n = self.m, self.n
        out: FloatArray = np.abs(np.asarray(theta, dtype=np.float64)).copy()
        b, a = out[: m + 1], out[m + 1 : m + 1 + n]
        out[: m + 1] = max(float(b.max()), 1e-12)
        if n:
            out[m + 1 : m + 1 + n] = np.maximum(a, max(float(a.max()), 1e-12) * 1e-3)
        out[m + 1 + n] = dt
        bg = max(abs(float(theta[m + n + 2])) + abs(float(theta[m + n + 3])), 1e-12)
        out[m + n + 2 : m + n + 4] = bg
        out[m + n + 4] = 1.0
        out[m + n + 5] = y_scale
        mu = float(theta[m + n + 4])
        for j, cls in enumerate(self.terms):
            out[self.core_size + j] = cls.scale_factor(y_scale, u_scale, mu)
        return out


def term_regressors(rec: TimeRecord, terms: Sequence[type[Term]]) -> FloatArray:
    """``(N, T)``: each term's regressor at the samples (1, ``u``, ``udot``, ``uddot``), from the Catmull-Rom
    interpolant at ``t = k dt`` as the simulator with terms evaluates it (the undelayed input)."""
    u, dt = rec.u, rec.dt
    slopes = np.empty_like(u)
    slopes[1:-1] = (u[2:] - u[:-2]) / (2.0 * dt)
    slopes[0], slopes[-1] = (u[1] - u[0]) / dt, (u[-1] - u[-2]) / dt
    q = np.arange(u.size) * dt / dt
    k = np.floor(q).astype(int)
    s = q - k
    last = u.size - 1
    inside = k < last
    kk = np.minimum(k, last - 1)
    u0, u1, m0, m1 = u[kk], u[kk + 1], slopes[kk], slopes[kk + 1]
    s2, s3 = s * s, s * s * s
    val = (
        (2 * s3 - 3 * s2 + 1) * u0
        + (s3 - 2 * s2 + s) * dt * m0
        + (-2 * s3 + 3 * s2) * u1
        + (s3 - s2) * dt * m1
    )
    der = (
        ((6 * s2 - 6 * s) * u0 + (-6 * s2 + 6 * s) * u1) / dt
        + (3 * s2 - 4 * s + 1) * m0
        + (3 * s2 - 2 * s) * m1
    )
    der2 = ((12 * s - 6) * u0 + (6 - 12 * s) * u1) / (dt * dt) + ((6 * s - 4) * m0 + (6 * s - 2) * m1) / dt
    columns = {
        Offset: np.ones(u.size),
        Stiffness: np.where(inside, val, u[last]),
        Viscous: np.where(inside, der, 0.0),
        Inertia: np.where(inside, der2, 0.0),
    }
    return np.stack([columns[cls] for cls in terms], axis=1)


def memory(plant: WienerPlant) -> float:
    """The model's memory (s): G's delay plus :data:`MEMORY_TIME_CONSTANTS` time constants of its slowest
    pole, plus as many of a sensor lag's."""
    den = np.asarray(plant.linear.den, dtype=float)
    lag = term_memory(plant.terms)
    if den.size < 2:
        return float(plant.linear.delay) + lag
    slowest = float(np.min(np.abs(np.real(np.roots(den)))))
    return float(plant.linear.delay) + lag + (MEMORY_TIME_CONSTANTS / slowest if slowest > 0 else math.inf)


@dataclass
class Problem:
    """The stacked residuals of a structure over records, for the search and for the bounds."""

    structure: Structure
    records: Sequence[TimeRecord]
    lead: Sequence[int]
    substeps: int
    backend: Backend
    scale: float = 1.0

    #: ``"auto"``: exact when the structure allows (:attr:`Structure.exact`), else differences;
    #: ``"difference"`` forces the differences (to test them against the exact Jacobian).
    jacobian: str = "auto"

    def simulate(self, theta: FloatArray, i: int) -> tuple[FloatArray, FloatArray]:
        """``(y_sim, J)`` of record ``i`` at the full vector ``theta`` (every free column; held ones 0 when
        differenced)."""
        s = self.structure
        if self.jacobian == "difference" or not s.exact:
            return self._difference(theta, i)
        core = get_backend(self.backend).timedomain
        rec = self.records[i]
        y, jac = core.timedomain_sensitivities(
            s.m,
            s.n,
            np.ascontiguousarray(theta[: s.core_size], dtype=np.float64),
            np.ascontiguousarray(rec.u),
            rec.dt,
            self.substeps,
        )
        y, jac = np.asarray(y, dtype=np.float64), np.asarray(jac, dtype=np.float64)
        if not s.terms:
            return y, jac
        reg = term_regressors(rec, s.terms)
        return y + reg @ theta[s.core_size :], np.hstack([jac, reg])

    def output(self, theta: FloatArray, i: int) -> FloatArray:
        """``y`` of record ``i`` by the library's simulator with terms (the map ``simulate_input`` runs)."""
        s, rec = self.structure, self.records[i]
        plant = s.unpack(theta)
        h, lin = plant.hysteresis, plant.linear
        core = get_backend(self.backend).paper
        args = (lin.num, lin.den, lin.delay, 1.0, h.beta, h.gamma, h.mu, h.w0, np.ascontiguousarray(rec.u))
        _, _, y = core.simulate_sampled(*args, rec.dt, self.substeps, terms=core_terms(plant.terms))
        return np.asarray(y, dtype=np.float64)

    def _difference(self, theta: FloatArray, i: int) -> tuple[FloatArray, FloatArray]:
        s, rec = self.structure, self.records[i]
        lo, hi = s.bounds(theta, math.inf)
        u_scale = float(np.std(np.concatenate([r.u for r in self.records]))) or 1.0
        scales = s.scales(theta, self.scale, u_scale, rec.dt)
        return difference_jacobian(lambda th: self.output(th, i), theta, s.free, scales, lo, hi)

    def full(self, free_values: FloatArray, theta0: FloatArray) -> FloatArray:
        theta = np.array(theta0, dtype=np.float64, copy=True)
        theta[self.structure.free] = free_values
        return theta

    def residuals(self, theta: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Stacked ``(y_sim - y) / scale`` after each lead-in, and their Jacobian on the free entries."""
        free = self.structure.free
        rs, js = [], []
        for i, rec in enumerate(self.records):
            y, jac = self.simulate(theta, i)
            k = self.lead[i]
            rs.append((y[k:] - rec.y[k:]) / self.scale)
            js.append(jac[k:, free] / self.scale)
        return np.concatenate(rs), np.concatenate(js, axis=0)

    def fun(self, theta0: FloatArray) -> Callable[[FloatArray], tuple[FloatArray, FloatArray]]:
        def f(free_values: FloatArray) -> tuple[FloatArray, FloatArray]:
            try:
                return self.residuals(self.full(free_values, theta0))
            except (NonFiniteError, InvalidParameterError):  # a trial the model cannot take: rejected
                n = sum(len(r) - k for r, k in zip(self.records, self.lead))
                return np.full(n, np.inf), np.zeros((n, int(self.structure.free.sum())))

        return f


def check_work(records: Sequence[TimeRecord], substeps: int, evaluations: int) -> None:
    """Refuse a fit above the step budget: every evaluation simulates every record with sensitivities."""
    samples = sum(len(r) for r in records)
    _budget.check_steps(
        "the time-domain fit (evaluations x samples x substeps)", evaluations * samples * max(substeps, 1)
    )


def check_records(records: Sequence[TimeRecord], lead: Sequence[int], start: WienerPlant) -> None:
    """Each record must outlast its lead-in and the start model's memory."""
    mem = memory(start)
    for rec, k in zip(records, lead):
        check_memory(rec, mem, "the start model (delay + 3 time constants of its slowest pole)")
        if len(rec) - k < 2:
            raise InvalidParameterError(
                f"the lead-in leaves {len(rec) - k} samples of {rec.name or 'a record'}; shorten it"
            )


def lead_ins(records: Sequence[TimeRecord], lead_in: Optional[float]) -> list[int]:
    return [lead_in_samples(r, lead_in) for r in records]


def covariance_on_names(lm: LMResult, structure: Structure) -> FloatArray:
    """The LM covariance (free entries) spread on the full vector (zeros for the held ones)."""
    full = np.zeros((structure.size, structure.size))
    free = structure.free
    full[np.ix_(free, free)] = lm.covariance
    return full
