"""Plan sine experiments: the design that minimises a Cramer-Rao criterion within a test-time budget.

From a prior guess of the plant and the noise level, :func:`plan_experiment` chooses the frequencies
(within a band), the amplitudes (within the actuator's amplitude and rate limits), the samples per period
(within a sampling-rate limit) and the number of averaged periods of each experiment so that the
Cramer-Rao bound (:func:`bouc_wen_id.cramer_rao`) of what the user cares about is smallest, while the
total test time ``sum_i overhead + (settle_periods + N_i) 2 pi / omega_i`` stays within the budget.

Why it is cheap
---------------
The Fisher information of experiment i is ``(N_i / sigma^2) F_i`` with ``F_i`` the 5 x 5 block of one
averaged period (:func:`bouc_wen_id.uncertainty.experiment_fisher`), in the parameters
``[beta, gamma, mu, |G_i|, phi_i]``.  The gain and phase of experiment i are its own, so eliminating
them leaves the Bouc-Wen information ``sum_i (N_i / sigma^2) S_i`` with ``S_i = A_i - B_i D_i^-1 B_i^T``
the Schur complement of the block (``A`` the Bouc-Wen 3 x 3 part, ``D`` the gain-phase 2 x 2 part): the
designs are scored with 3 x 3 inverses of sums of precomputed matrices, and the covariance of
``(|G_i|, phi_i)`` is ``sigma^2 D_i^-1 / N_i + K_i C K_i^T`` with ``K_i = D_i^-1 B_i^T`` and ``C`` the
Bouc-Wen covariance.  The reported standard errors are then recomputed by :func:`cramer_rao` itself.

Criteria (``target``), all on the alpha-normalised model, all to minimise
----------------------------------------------------------------------
``"beta"``, ``"gamma"``, ``"mu"``
    The relative variance ``var(theta) / theta^2`` of that parameter (the variance itself for a zero
    parameter).
``"bouc_wen"``
    The geometric mean of the relative variances, ``det(C_rel)^(1/3)`` with
    ``C_rel = C / (theta theta^T)``: D-optimal on (beta, gamma, mu), invariant to their units.
``"G"``
    G is pinned only where it is tested, so "G over the band" is scored on a fixed grid: the
    ``n_frequencies`` log-spaced frequencies of the band are ALL tested, and the criterion is the mean
    over them of ``var(|G|) / |G|^2 + var(phi)`` (the relative variance of the complex G(j omega)).
    The planner then chooses the amplitude and the periods of each.

Algorithm
---------
Candidates: ``n_frequencies`` frequencies log-spaced over the band times ``n_amplitudes`` amplitudes
``(1/L, 2/L, ..., 1) x U_max(omega)``, with ``U_max(omega) = min(max_amplitude, max_rate / omega)``. Every
experiment is sampled at the lab's rate ``sample_rate``: a frequency is moved to ``omega = 2 pi
sample_rate / (d P)`` with P a whole number of samples per period (at least
:data:`MIN_SAMPLES_PER_PERIOD`, at most ``max_samples_per_period``) and d = 1, or the smallest whole
decimation that brings P under the cap.  Frequencies whose settling and ``min_periods`` alone exceed the
budget are no candidates.  At most one experiment per frequency.  A greedy phase spends the budget in
chunks (about 1/50 of it): at each step it either adds periods to an experiment or opens a new one (paying
its overhead and settling), whichever lowers the log-criterion most per second of test time.  A
Fedorov-style exchange phase then tries budget-neutral moves (another amplitude at the same frequency,
periods moved between experiments, an experiment closed and its time given to another, an experiment moved
to an unused frequency) and keeps the best improving one until none improves; the greedy phase then spends
what is left, down to single periods. The search is local: when the naive design (below) scores better, it
is the plan. Everything is deterministic.  A vague prior (relative standard deviation 10^4) keeps the
criterion finite while the design cannot yet identify every parameter; it is not in the reported bounds.

Assumptions of the bound (as :func:`cramer_rao`): white Gaussian output noise of the same standard
deviation at any sampling rate (so more samples per period carry more information; a noise that is
filtered before sampling does not gain as much), the steady loop after ``settle_periods``, and unbiased
estimators.  The bound is local: it is only as good as the prior plant.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal, Optional

import numpy as np
from numpy.typing import NDArray

from ._backend import Backend
from .errors import InvalidParameterError
from .model import Recording, SinePlan, WienerPlant
from .uncertainty import CramerRao, cramer_rao, experiment_fisher
from .validation import count, nonnegative_number, positive_number, real_number

__all__ = ["Target", "PlannedExperiment", "Design", "ExperimentPlan", "plan_experiment", "TARGETS"]

FloatArray = NDArray[np.float64]
Target = Literal["beta", "gamma", "mu", "bouc_wen", "G"]
TARGETS: tuple[str, ...] = ("beta", "gamma", "mu", "bouc_wen", "G")

#: Fewest samples per period a candidate may have: the averaged period must resolve the loop's
#: harmonics (the identification's spectral derivative and phase search work on it).
MIN_SAMPLES_PER_PERIOD = 16
#: Fraction of the budget the greedy phase spends per step (then single periods at the end).
CHUNK_FRACTION = 1.0 / 50.0
#: Prior precision of the vague prior, relative and per unit noise variance: 1 / (10^4 theta)^2 (keeps a
#: rank-deficient design's criterion finite during the search; absent from the reported bounds).
VAGUE_PRIOR = 1e-8
#: Largest candidate grid: the exchange phase weighs O(frequencies^2 x amplitudes) moves per iteration, so
#: a careless ``n_frequencies=10**6`` is refused at once instead of running for hours.
MAX_FREQUENCIES = 200
MAX_AMPLITUDES = 50
#: For ``"G"`` every grid point is an experiment, so the exchange phase weighs O(frequencies^2) moves
#: over designs of that many experiments: 200 took over 100 s (44 s with the vectorised score, and the
#: local search no longer beat the naive design), 100 take 7 s, 40 about 1 s.
MAX_FREQUENCIES_G = 40
#: Largest budget, s (about three years of test time): beyond it the periods and the information overflow
#: long before a design could be run (a budget of 1e300 s ran the search forever).
MAX_BUDGET = 1e8
#: Noise levels the planner computes with, in the output's units: the bound scales as noise_sd^2, whose
#: square must stay a float (1e-200 divided by zero, 1e300 overflowed); rescale the output's units outside.
NOISE_SD_RANGE = (1e-100, 1e100)
#: Exchange iterations at most (each keeps the best improving move; it stops earlier when none improves).
MAX_EXCHANGES = 200
#: A move must lower the log-criterion by more than this to count as an improvement.
IMPROVEMENT_TOL = 1e-9


@dataclass(frozen=True)
class PlannedExperiment:
    """One sine experiment of a design: ``u = amplitude cos(frequency t)``.

    ``frequency`` in rad/s; ``samples_per_period`` P (the sampling rate is ``P frequency / (2 pi)``
    Hz); ``settle_periods`` played and discarded, then ``periods`` N measured and averaged;
    ``overhead`` seconds of set-up counted against the budget.
    """

    frequency: float
    amplitude: float
    periods: int
    samples_per_period: int
    settle_periods: int
    overhead: float = 0.0

    @property
    def period(self) -> float:
        """One period, s."""
        return 2.0 * math.pi / self.frequency

    @property
    def duration(self) -> float:
        """Test time charged to the budget, s: overhead + (settle + N) periods."""
        return self.overhead + (self.settle_periods + self.periods) * self.period

    @property
    def sample_rate(self) -> float:
        """Sampling rate, Hz."""
        return self.samples_per_period / self.period

    def plan(self, noise_sd: float, seed: Optional[int] = 0, substeps: int = 4) -> SinePlan:
        """This experiment as a one-frequency :class:`SinePlan` (for :func:`bouc_wen_id.simulate`)."""
        return SinePlan(
            frequencies=[self.frequency],
            amplitudes=[self.amplitude],
            settle_periods=self.settle_periods,
            periods=self.periods,
            samples_per_period=self.samples_per_period,
            substeps=substeps,
            noise_sd=noise_sd,
            seed=seed,
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "frequency": self.frequency,
            "amplitude": self.amplitude,
            "periods": self.periods,
            "samples_per_period": self.samples_per_period,
            "settle_periods": self.settle_periods,
            "overhead": self.overhead,
            "duration": self.duration,
            "sample_rate": self.sample_rate,
        }


@dataclass(frozen=True, eq=False)
class Design:
    """A set of experiments with its predicted standard errors (Cramer-Rao) and its criterion value."""

    experiments: tuple[PlannedExperiment, ...]
    noise_sd: float
    predicted: CramerRao
    criterion: float
    total_time: float

    def plans(self, seed: Optional[int] = 0, substeps: int = 4) -> list[SinePlan]:
        """One :class:`SinePlan` per experiment (each its own N and P); the noise seeds are derived from
        ``seed`` by ``numpy.random.SeedSequence(seed).spawn`` (``None``: fresh entropy)."""
        if seed is None:
            return [e.plan(self.noise_sd, None, substeps) for e in self.experiments]
        children = np.random.SeedSequence(seed).spawn(len(self.experiments))
        return [
            e.plan(self.noise_sd, int(c.generate_state(1)[0]), substeps)
            for e, c in zip(self.experiments, children)
        ]

    def simulate(
        self, plant: WienerPlant, seed: Optional[int] = 0, substeps: int = 4, backend: Backend = "rust"
    ) -> list[Recording]:
        """Simulate every experiment on ``plant`` (e.g. the prior, or a truth for a Monte Carlo)."""
        from .simulation import simulate

        recs: list[Recording] = []
        for plan in self.plans(seed, substeps):
            recs.extend(simulate(plant, plan, backend=backend, workers=1))
        return recs

    def to_dict(self) -> dict[str, Any]:
        return {
            "experiments": [e.to_dict() for e in self.experiments],
            "noise_sd": self.noise_sd,
            "predicted_sd": self.predicted.to_dict(),
            "criterion": self.criterion,
            "total_time": self.total_time,
        }


@dataclass(frozen=True, eq=False)
class ExperimentPlan:
    """The planned design, the naive design of the same budget, and the constraints they obey.

    ``design`` is what to run; ``naive`` (None when the budget cannot hold it) is the comparison:
    evenly log-spaced frequencies over the band (for ``target="G"``: the same tested grid) at the
    largest allowed amplitude, the same number of experiments, the same periods N each, the same
    sampling-rate rule.  ``improvement`` is ``naive.criterion / design.criterion`` (>= 1 is a gain).
    """

    target: str
    prior: WienerPlant
    budget: float
    design: Design
    naive: Optional[Design]
    settings: dict[str, Any] = field(repr=False)

    @property
    def experiments(self) -> tuple[PlannedExperiment, ...]:
        return self.design.experiments

    @property
    def predicted(self) -> CramerRao:
        return self.design.predicted

    @property
    def total_time(self) -> float:
        return self.design.total_time

    @property
    def improvement(self) -> Optional[float]:
        if self.naive is None:
            return None
        return self.naive.criterion / self.design.criterion

    def plans(self, seed: Optional[int] = 0, substeps: int = 4) -> list[SinePlan]:
        """The planned experiments as :class:`SinePlan` s (see :meth:`Design.plans`)."""
        return self.design.plans(seed, substeps)

    def simulate(
        self,
        plant: Optional[WienerPlant] = None,
        seed: Optional[int] = 0,
        substeps: int = 4,
        backend: Backend = "rust",
    ) -> list[Recording]:
        """Simulate the planned experiments on ``plant`` (default: the prior)."""
        return self.design.simulate(self.prior if plant is None else plant, seed, substeps, backend)

    def summary(self) -> str:
        lines = [
            f"Experiment plan: target {self.target!r}, budget {self.budget:g} s "
            f"(used {self.design.total_time:.1f} s), noise sd {self.design.noise_sd:g}",
            f"  {'#':>2} {'omega rad/s':>11} {'f Hz':>8} {'U':>9} {'P':>5} {'fs Hz':>9} "
            f"{'settle':>6} {'N':>6} {'time s':>8} {'sd|G|/|G|':>10} {'sd phi':>9}",
        ]
        gains, _ = self.prior.normalized().linear.gain_phase([e.frequency for e in self.experiments])
        cr = self.design.predicted
        for i, e in enumerate(self.experiments):
            lines.append(
                f"  {i:>2} {e.frequency:>11.4g} {e.frequency / (2 * math.pi):>8.4g} {e.amplitude:>9.4g} "
                f"{e.samples_per_period:>5d} {e.sample_rate:>9.4g} {e.settle_periods:>6d} {e.periods:>6d} "
                f"{e.duration:>8.2f} {cr.gain[i] / gains[i]:>10.3g} {cr.phase[i]:>9.3g}"
            )
        h = self.prior.normalized().hysteresis
        lines.append("Predicted standard deviations (Cramer-Rao bound, alpha-normalised model):")
        lines.append(f"  {'':<9} {'prior':>10} {'planned':>12} {'naive':>12}")
        for name in ("beta", "gamma", "mu"):
            value = getattr(h, name)
            naive = "-" if self.naive is None else f"{getattr(self.naive.predicted, name):.3g}"
            lines.append(
                f"  {name:<9} {value:>10.4g} {getattr(cr, name):>12.3g} {naive:>12}"
                + (f"   ({getattr(cr, name) / abs(value):.2%} of the value)" if value else "")
            )
        naive_c = "-" if self.naive is None else f"{self.naive.criterion:.3g}"
        lines.append(
            f"  {'criterion':<9} {'':>10} {self.design.criterion:>12.3g} {naive_c:>12}   "
            f"({_CRITERION_TEXT[self.target]})"
        )
        if self.improvement is not None:
            lines.append(
                f"Naive design ({len(self.naive.experiments) if self.naive else 0} experiments at the "
                "largest "
                f"amplitude, equal periods): the planned one's criterion is {self.improvement:.3g}x smaller."
            )
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready description (format ``bouc_wen_id.plan``, version 1)."""
        return {
            "format": "bouc_wen_id.plan",
            "version": 1,
            "target": self.target,
            "criterion": _CRITERION_TEXT[self.target],
            "budget": self.budget,
            "prior": self.prior.to_dict(),
            "settings": self.settings,
            "design": self.design.to_dict(),
            "naive": None if self.naive is None else self.naive.to_dict(),
            "improvement": self.improvement,
        }

    def to_json(self, indent: int = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)


_CRITERION_TEXT = {
    "beta": "relative variance of beta",
    "gamma": "relative variance of gamma",
    "mu": "relative variance of mu",
    "bouc_wen": "geometric mean of the relative variances of beta, gamma, mu",
    "G": "mean over the tested grid of var|G|/|G|^2 + var(phi)",
}


def _scales(theta: FloatArray) -> FloatArray:
    """|theta|, with 1 in place of a zero parameter (its variance is then scored as it is)."""
    out: FloatArray = np.where(theta != 0, np.abs(theta), 1.0)
    return out


def criterion_value(target: str, prior: WienerPlant, frequencies: FloatArray, cr: CramerRao) -> float:
    """The criterion ``target`` (module docstring) of a bound ``cr`` for experiments at ``frequencies``."""
    norm = prior.normalized()
    h = norm.hysteresis
    s = _scales(np.array([h.beta, h.gamma, h.mu]))
    if target == "G":
        gains, _ = norm.linear.gain_phase(frequencies)
        return float(np.mean((cr.gain / gains) ** 2 + cr.phase**2))
    rel = cr.covariance[:3, :3] / np.outer(s, s)
    if target == "bouc_wen":
        sign, logdet = np.linalg.slogdet(rel)  # det itself under- or overflows at extreme noise levels
        return math.exp(float(logdet) / 3.0) if sign > 0 else 0.0
    i = ("beta", "gamma", "mu").index(target)
    return float(rel[i, i])


class _Search:
    """The candidate blocks and the design scoring of the greedy/exchange search.

    The search works at unit noise: the information ``sum_i N_i S_i`` is the true one times ``sigma^2``,
    so every criterion is the true one divided by ``sigma^2``, a constant that changes no comparison, and
    noise levels from 1e-100 to 1e100 neither divide by zero nor overflow.  The vague prior ``P`` is added
    at unit noise too, so it weighs the same against the data at any noise level and the design does not
    depend on sigma.  For ``"G"`` the per-point terms are precomputed: ``var(|G_i|)/|G_i|^2 + var(phi_i)`` is
    ``c_i / N_i + tr(C M_i)`` with ``c_i`` from ``D_i^-1`` and ``M_i = K_i^T W_i K_i``.
    """

    def __init__(self, target: str, prior: WienerPlant, grid: _Grid, st: _Settings) -> None:
        self.target = target
        omegas, amps, samples = grid.omegas, grid.amps, grid.samples
        self.omegas, self.amps, self.samples = omegas, amps, samples
        self.period = 2.0 * np.pi / omegas
        self.settle, self.overhead = st.settle, st.overhead
        norm = prior.normalized()
        h = norm.hysteresis
        self.theta_scale = _scales(np.array([h.beta, h.gamma, h.mu]))
        self.gains, _ = norm.linear.gain_phase(omegas)
        k, n_amp = amps.shape
        self.schur = np.zeros((k, n_amp, 3, 3))
        self.point = np.zeros((k, n_amp))  # c_i
        self.mmat = np.zeros((k, n_amp, 3, 3))  # M_i
        weight = np.diag([1.0, 1.0])
        for i in range(k):
            weight[0, 0] = 1.0 / self.gains[i] ** 2
            for a in range(n_amp):
                f = experiment_fisher(
                    norm,
                    float(omegas[i]),
                    float(amps[i, a]),
                    int(samples[i]),
                    substeps=st.substeps,
                    backend=st.backend,
                )
                dinv = np.linalg.pinv(f[3:, 3:])
                kmat = dinv @ f[3:, :3]
                self.schur[i, a] = f[:3, :3] - f[:3, 3:] @ kmat
                self.point[i, a] = dinv[0, 0] * weight[0, 0] + dinv[1, 1]
                self.mmat[i, a] = kmat.T @ weight @ kmat
        self.prior_precision = VAGUE_PRIOR * np.diag(1.0 / self.theta_scale**2)

    def cost(self, design: dict[int, tuple[int, int]]) -> float:
        return float(sum(self.overhead + (self.settle + n) * self.period[k] for k, (_, n) in design.items()))

    def score(self, design: dict[int, tuple[int, int]]) -> float:
        """log of the criterion at unit noise (with the vague prior)."""
        if design:
            cells = np.array([(k, a, n) for k, (a, n) in design.items()], dtype=np.int64)
            ks, aa, ns = cells[:, 0], cells[:, 1], cells[:, 2].astype(np.float64)
            info = self.prior_precision + np.einsum("i,ijk->jk", ns, self.schur[ks, aa])
        else:
            info = self.prior_precision.copy()
        try:
            cov = np.linalg.inv(info)
        except np.linalg.LinAlgError:
            return math.inf
        if self.target == "G":
            # Untested grid points have no estimate: the search opens all of them first.
            if not design:
                return math.inf
            total = float(np.sum(self.point[ks, aa] / ns)) + float(
                np.sum(cov * self.mmat[ks, aa].sum(axis=0))
            )
            value = total / len(design)
        else:
            rel = cov / np.outer(self.theta_scale, self.theta_scale)
            if self.target == "bouc_wen":
                sign, logdet = np.linalg.slogdet(rel)
                return float(logdet) / 3.0 if sign > 0 else math.inf
            i = ("beta", "gamma", "mu").index(self.target)
            value = float(rel[i, i])
        return math.log(value) if value > 0 else math.inf


def _spend(
    s: _Search,
    design: dict[int, tuple[int, int]],
    budget: float,
    chunk: float,
    min_periods: int,
    max_experiments: int,
    may_open: bool,
) -> dict[int, tuple[int, int]]:
    """Greedy: add periods or open experiments, best log-criterion drop per second, until none fits."""
    current = s.score(design)
    while True:
        rem = budget - s.cost(design)
        best: Optional[tuple[float, dict[int, tuple[int, int]], float]] = None
        options: list[tuple[dict[int, tuple[int, int]], float]] = []
        for k, (a, n) in design.items():
            dn = min(max(1, int(chunk // s.period[k])), int(rem // s.period[k]))
            if dn >= 1:
                options.append(({**design, k: (a, n + dn)}, dn * s.period[k]))
        if may_open and len(design) < max_experiments:
            for k in range(len(s.omegas)):
                if k in design:
                    continue
                n0 = max(min_periods, int(chunk // s.period[k]))
                price = s.overhead + (s.settle + n0) * s.period[k]
                if price > rem:
                    n0 = min_periods
                    price = s.overhead + (s.settle + n0) * s.period[k]
                    if price > rem:
                        continue
                for a in range(s.amps.shape[1]):
                    options.append(({**design, k: (a, n0)}, price))
        for cand, price in options:
            value = s.score(cand)
            rate = (current - value) / price
            if value < current - IMPROVEMENT_TOL and (best is None or rate > best[0]):
                best = (rate, cand, value)
        if best is None:
            return design
        design, current = best[1], best[2]


def _fill(
    s: _Search, design: dict[int, tuple[int, int]], k: int, budget: float
) -> Optional[dict[int, tuple[int, int]]]:
    """``design`` with experiment ``k``'s periods raised to use all the time left (None if none is left)."""
    a, n = design[k]
    extra = int((budget - s.cost(design)) // s.period[k])
    return {**design, k: (a, n + extra)} if extra >= 1 else None


def _exchange(
    s: _Search,
    design: dict[int, tuple[int, int]],
    budget: float,
    chunk: float,
    min_periods: int,
    fixed_frequencies: bool,
) -> dict[int, tuple[int, int]]:
    """Fedorov-style: apply the best improving budget-neutral move until none improves."""
    current = s.score(design)
    for _ in range(MAX_EXCHANGES):
        options: list[dict[int, tuple[int, int]]] = []
        for k, (a, n) in design.items():
            for b in range(s.amps.shape[1]):  # another amplitude at the same frequency
                if b != a:
                    options.append({**design, k: (b, n)})
            dn = max(1, int(chunk // s.period[k]))
            if n - dn >= min_periods:  # periods moved from k to j
                less = {**design, k: (a, n - dn)}
                for j in design:
                    if j != k:
                        moved = _fill(s, less, j, budget)
                        if moved is not None:
                            options.append(moved)
            if fixed_frequencies or len(design) < 2:
                continue
            rest = {j: v for j, v in design.items() if j != k}
            for j, (_aj, nj) in rest.items():  # k closed, its time given to j (at any amplitude)
                for b in range(s.amps.shape[1]):
                    moved = _fill(s, {**rest, j: (b, nj)}, j, budget)
                    if moved is not None:
                        options.append(moved)
            free = budget - s.cost(rest)
            for j in range(len(s.omegas)):  # k moved to an unused frequency j
                if j in design:
                    continue
                nj = int((free - s.overhead) // s.period[j]) - s.settle
                if nj >= min_periods:
                    for b in range(s.amps.shape[1]):
                        options.append({**rest, j: (b, nj)})
        best: Optional[tuple[float, dict[int, tuple[int, int]]]] = None
        for cand in options:
            value = s.score(cand)
            if value < current - IMPROVEMENT_TOL and (best is None or value < best[0]):
                best = (value, cand)
        if best is None:
            break
        current, design = best
    return design


@dataclass(frozen=True)
class _Settings:
    """The validated lab limits and search settings of one plan (:func:`plan_experiment`'s keywords)."""

    target: str
    lo: float
    hi: float
    max_amplitude: float
    noise_sd: float
    sample_rate: float
    max_rate: Optional[float]
    n_freq: int
    n_amp: int
    settle: int
    overhead: float
    p_cap: int
    min_n: int
    max_exp: int
    substeps: int
    backend: Backend

    @property
    def rate(self) -> float:
        """The rate limit, inf when there is none."""
        return math.inf if self.max_rate is None else self.max_rate

    @property
    def top(self) -> float:
        """The band's top, cut where the sampling rate no longer gives MIN_SAMPLES_PER_PERIOD per period."""
        return min(self.hi, 2.0 * math.pi * self.sample_rate / MIN_SAMPLES_PER_PERIOD)

    def to_dict(self, candidates: FloatArray) -> dict[str, Any]:
        return {
            "band": [self.lo, self.hi],
            "max_amplitude": self.max_amplitude,
            "max_rate": self.max_rate,
            "noise_sd": self.noise_sd,
            "sample_rate": self.sample_rate,
            "n_frequencies": self.n_freq,
            "n_amplitudes": self.n_amp,
            "settle_periods": self.settle,
            "overhead": self.overhead,
            "max_samples_per_period": self.p_cap,
            "min_periods": self.min_n,
            "max_experiments": self.max_exp,
            "substeps": self.substeps,
            "candidate_frequencies": candidates.tolist(),
        }


@dataclass(frozen=True)
class _Grid:
    """The candidates: frequencies on the lab's sampling rate, their samples per period and amplitudes."""

    omegas: FloatArray
    samples: NDArray[np.int64]
    amps: FloatArray
    lo: float  # the usable band: frequencies the budget can afford, sampled well enough
    top: float

    @property
    def period(self) -> FloatArray:
        out: FloatArray = 2.0 * np.pi / self.omegas
        return out


def plan_experiment(
    prior_plant: WienerPlant,
    budget: float,
    *,
    band: tuple[float, float],
    max_amplitude: float,
    noise_sd: float,
    sample_rate: float,
    target: Target = "bouc_wen",
    max_rate: Optional[float] = None,
    n_frequencies: int = 12,
    n_amplitudes: int = 4,
    settle_periods: int = 20,
    overhead: float = 0.0,
    max_samples_per_period: int = 512,
    min_periods: int = 5,
    max_experiments: Optional[int] = None,
    substeps: int = 8,
    backend: Backend = "rust",
) -> ExperimentPlan:
    """Plan sine experiments minimising the Cramer-Rao criterion ``target`` within a time budget.

    Parameters
    ----------
    prior_plant : WienerPlant
        The prior guess of the plant (a plain Wiener-Bouc-Wen plant, no terms).
    budget : float
        Total test time, s: ``sum_i overhead + (settle_periods + N_i) 2 pi / omega_i <= budget``
        (at most :data:`MAX_BUDGET`).
    band : (float, float)
        Lowest and highest angular frequency allowed, rad/s (low < high).  Frequencies whose settling
        and ``min_periods`` periods alone exceed the budget are not candidates.
    max_amplitude : float
        Largest input amplitude U the actuator allows (> 0; the planner uses positive amplitudes).
    noise_sd : float
        Prior standard deviation of the white output noise, per sample (within :data:`NOISE_SD_RANGE`).
    sample_rate : float
        The lab's sampling rate, Hz.  Every experiment is sampled at it: each candidate frequency is moved
        (by less than half a sample per period) so that a period holds a whole number P of samples; where
        P would exceed ``max_samples_per_period``, the experiment is sampled at ``sample_rate / d`` for
        the smallest whole d that fits (decimate the record by d).
    target : {"bouc_wen", "beta", "gamma", "mu", "G"}
        What to make precise (module docstring: the criteria).
    max_rate : float, optional
        Largest input rate ``U omega`` (a velocity limit, units of u per second).
    n_frequencies : int
        Log-spaced candidate frequencies over the band (for ``"G"``: the tested grid, all used), at most
        :data:`MAX_FREQUENCIES` (:data:`MAX_FREQUENCIES_G` for ``"G"``).
    n_amplitudes : int
        Candidate amplitudes per frequency: ``(1/L, ..., 1) x min(max_amplitude, max_rate / omega)``.
    settle_periods : int
        Periods played before the measured ones, in every experiment (charged to the budget).
    overhead : float
        Set-up time charged per experiment, s.
    max_samples_per_period : int
        Cap on P (the planner takes the most the sampling rate allows, up to this).
    min_periods : int
        Fewest periods N of an experiment (the identification estimates the noise from their spread).
    max_experiments : int, optional
        Most experiments in the design (default: ``n_frequencies``).
    substeps : int
        RK4 steps per sample of the sensitivities (as :func:`cramer_rao`).

    Returns
    -------
    ExperimentPlan
        The design (experiments, predicted standard errors, criterion, total time), the naive design of
        the same budget, and the settings; :meth:`ExperimentPlan.simulate` and
        :meth:`ExperimentPlan.plans` run it.

    Raises
    ------
    InvalidParameterError
        A non-finite or out-of-range argument, an empty band, a plant with terms, no frequency of the
        band sampled with at least :data:`MIN_SAMPLES_PER_PERIOD` samples per period, a budget too small
        for even one experiment (or, for ``"G"``, for every grid point), or a budget whose best design
        still cannot identify every parameter.
    """
    _check_prior(prior_plant, target)
    budget = _budget(budget)
    st = _settings(
        target, band, max_amplitude, noise_sd, sample_rate, max_rate, n_frequencies, n_amplitudes,
        settle_periods, overhead, max_samples_per_period, min_periods, max_experiments, substeps, backend,
    )  # fmt: skip
    grid = _grid(st, budget)
    search = _Search(target, prior_plant, grid, st)
    design = _search_design(search, st, grid, budget)
    experiments = _experiments(st, grid, design)
    planned = _design(st, prior_plant, experiments)
    if planned is None:
        raise InvalidParameterError(
            f"within budget = {budget:g} s no design found identifies every parameter (the Fisher "
            "information stays singular); raise the budget or widen the band"
        )
    naive = _naive(st, prior_plant, budget, len(experiments), grid)
    if naive is not None and naive.criterion < planned.criterion:
        planned = naive  # the search is local: never return a design worse than the naive one
    return ExperimentPlan(target, prior_plant, budget, planned, naive, st.to_dict(grid.omegas))


def _budget(budget: object) -> float:
    """The test-time budget, s: positive and at most :data:`MAX_BUDGET`."""
    out = positive_number("budget", budget)
    if out > MAX_BUDGET:
        raise InvalidParameterError(
            f"budget = {out:g} s is more than {MAX_BUDGET:g} s (about three years of test time): plan a "
            "part of it and repeat the design"
        )
    return out


def _experiments(
    st: _Settings, grid: _Grid, design: dict[int, tuple[int, int]]
) -> tuple[PlannedExperiment, ...]:
    """The searched design as experiments, by frequency."""
    return tuple(
        PlannedExperiment(
            float(grid.omegas[k]),
            float(grid.amps[k, a]),
            int(n),
            int(grid.samples[k]),
            st.settle,
            st.overhead,
        )
        for k, (a, n) in sorted(design.items())
    )


def _check_prior(prior_plant: object, target: object) -> None:
    """The prior must be a plain Wiener-Bouc-Wen plant and the target one of :data:`TARGETS`."""
    if not isinstance(prior_plant, WienerPlant):
        raise InvalidParameterError(f"prior_plant must be a WienerPlant, got {type(prior_plant).__name__}")
    if prior_plant.terms:
        raise InvalidParameterError(
            "plan_experiment plans for the plain Wiener-Bouc-Wen model (its Cramer-Rao bound); pass the "
            "prior plant without terms"
        )
    if target not in TARGETS:
        raise InvalidParameterError(f"target = {target!r} must be one of {', '.join(TARGETS)}")


def _settings(
    target: str,
    band: tuple[float, float],
    max_amplitude: float,
    noise_sd: float,
    sample_rate: float,
    max_rate: Optional[float],
    n_frequencies: int,
    n_amplitudes: int,
    settle_periods: int,
    overhead: float,
    max_samples_per_period: int,
    min_periods: int,
    max_experiments: Optional[int],
    substeps: int,
    backend: Backend,
) -> _Settings:
    """Every keyword of :func:`plan_experiment` checked, by name."""
    if isinstance(band, (str, bytes)) or np.ndim(band) != 1 or len(band) != 2:
        raise InvalidParameterError(f"band must be two frequencies (low, high) in rad/s, got {band!r}")
    lo, hi = real_number("band low", band[0]), real_number("band high", band[1])
    if not 0 < lo < hi:
        raise InvalidParameterError(f"band = ({lo}, {hi}) must satisfy 0 < low < high (rad/s): it is empty")
    noise = positive_number("noise_sd", noise_sd)
    if not NOISE_SD_RANGE[0] <= noise <= NOISE_SD_RANGE[1]:
        raise InvalidParameterError(
            f"noise_sd = {noise:g} is outside {NOISE_SD_RANGE[0]:g}..{NOISE_SD_RANGE[1]:g}, where the bound "
            "(which scales as noise_sd^2) stays a float: express the output in other units"
        )
    n_freq = count("n_frequencies", n_frequencies, 2, MAX_FREQUENCIES_G if target == "G" else MAX_FREQUENCIES)
    n_amp = count("n_amplitudes", n_amplitudes, 1, MAX_AMPLITUDES)
    return _Settings(
        target=target,
        lo=lo,
        hi=hi,
        max_amplitude=positive_number("max_amplitude", max_amplitude),
        noise_sd=noise,
        sample_rate=positive_number("sample_rate", sample_rate),
        max_rate=None if max_rate is None else positive_number("max_rate", max_rate),
        n_freq=n_freq,
        n_amp=n_amp,
        settle=count("settle_periods", settle_periods, 0),
        overhead=nonnegative_number("overhead", overhead),
        p_cap=count("max_samples_per_period", max_samples_per_period, MIN_SAMPLES_PER_PERIOD),
        min_n=count("min_periods", min_periods, 2),
        max_exp=n_freq if max_experiments is None else count("max_experiments", max_experiments, 2),
        substeps=count("substeps", substeps, 1),
        backend=backend,
    )


def _grid(st: _Settings, budget: float) -> _Grid:
    """The candidate frequencies, log-spaced over the band's usable part and put on the lab's rate."""
    top = st.top
    if top < st.lo:
        raise InvalidParameterError(
            f"sample_rate = {st.sample_rate:g} Hz gives fewer than {MIN_SAMPLES_PER_PERIOD} samples per "
            f"period at every frequency of the band ({st.lo:g}, {st.hi:g}) rad/s"
        )
    lo = st.lo
    if st.target == "G":
        _check_g_budget(st, np.geomspace(lo, top, st.n_freq) if top > lo else np.array([lo]), budget)
    else:
        # A frequency whose settling and fewest periods alone exceed the budget is no candidate.
        lo = max(lo, 2.0 * math.pi * (st.settle + st.min_n) / max(budget - st.overhead, 1e-300))
        if lo > top:
            _too_small(st, budget, top)
    omegas = np.unique(np.geomspace(lo, top, st.n_freq)) if top > lo else np.array([lo])
    omegas, samples = _on_lab_rate(omegas, st.sample_rate, st.p_cap, lo, top)
    u_max = np.minimum(st.max_amplitude, st.rate / omegas)
    amps = u_max[:, None] * (np.arange(1, st.n_amp + 1) / st.n_amp)[None, :]
    cheapest = float(np.min(st.overhead + (st.settle + st.min_n) * 2.0 * np.pi / omegas))
    if budget < cheapest:
        _too_small(st, budget, float(omegas[-1]))
    return _Grid(omegas, samples, amps, lo, top)


def _too_small(st: _Settings, budget: float, omega: float) -> None:
    cheapest = st.overhead + (st.settle + st.min_n) * 2.0 * math.pi / omega
    raise InvalidParameterError(
        f"budget = {budget:g} s is too small for even one experiment: the cheapest takes "
        f"{cheapest:.4g} s ({st.overhead:g} s overhead + {st.settle} settling + {st.min_n} measured "
        f"periods at {omega:.4g} rad/s)"
    )


def _check_g_budget(st: _Settings, omegas: FloatArray, budget: float) -> None:
    """Target "G" tests every grid point: the budget must hold each at ``min_periods``."""
    need = float(np.sum(st.overhead + (st.settle + st.min_n) * 2.0 * np.pi / omegas))
    if budget < need:
        raise InvalidParameterError(
            f"budget = {budget:g} s is too small to test every one of the {len(omegas)} grid frequencies "
            f"of target 'G' ({need:.4g} s at {st.min_n} periods each); raise the budget or lower "
            "n_frequencies"
        )


def _on_lab_rate(
    omegas: FloatArray, sample_rate: float, p_cap: int, lo: float, top: float
) -> tuple[FloatArray, NDArray[np.int64]]:
    """Frequencies moved so that a period holds a whole number P of samples at the lab's rate
    ``sample_rate / d`` (d = 1 unless P would exceed ``p_cap``), kept within ``[lo, top]``."""
    out_w: list[float] = []
    out_p: list[int] = []
    for w in omegas:
        full = 2.0 * math.pi * sample_rate / float(w)  # samples per period at the lab's rate
        d = max(1, math.ceil(full / p_cap * (1.0 - 1e-12)))
        p = max(MIN_SAMPLES_PER_PERIOD, min(p_cap, round(full / d)))
        for cand in (p, p - 1, p + 1):
            wc = 2.0 * math.pi * sample_rate / (d * cand)
            if MIN_SAMPLES_PER_PERIOD <= cand <= p_cap and lo * (1 - 1e-12) <= wc <= top * (1 + 1e-12):
                out_w.append(wc)
                out_p.append(cand)
                break
    if not out_w:
        raise InvalidParameterError(
            f"no frequency of the band ({lo:g}, {top:g}) rad/s holds a whole number of samples per period "
            f"at {sample_rate:g} Hz within {MIN_SAMPLES_PER_PERIOD}..{p_cap}; widen the band"
        )
    w_arr, idx = np.unique(np.array(out_w), return_index=True)
    return w_arr, np.array(out_p, dtype=np.int64)[idx]


def _search_design(s: _Search, st: _Settings, grid: _Grid, budget: float) -> dict[int, tuple[int, int]]:
    """Greedy spending, then exchanges and spending until the design settles (module docstring)."""
    chunk = CHUNK_FRACTION * budget
    fixed = st.target == "G"
    design: dict[int, tuple[int, int]] = {}
    if fixed:
        _check_g_budget(st, grid.omegas, budget)  # the grid moved onto the lab's rate
        # Open every grid point at min_periods, choosing its amplitude greedily, cheapest first.
        for k in np.argsort(grid.period):
            k = int(k)
            best = min(range(st.n_amp), key=lambda a: s.score({**design, k: (a, st.min_n)}))
            design[k] = (best, st.min_n)
    design = _spend(s, design, budget, chunk, st.min_n, st.max_exp, not fixed)
    for _ in range(3):
        before = dict(design)
        design = _exchange(s, design, budget, chunk, st.min_n, fixed)
        design = _spend(s, design, budget, 0.0, st.min_n, st.max_exp, not fixed)
        if design == before:
            break
    return design


def _design(st: _Settings, prior: WienerPlant, experiments: Sequence[PlannedExperiment]) -> Optional[Design]:
    """The design's exact bound by :func:`cramer_rao` (None when its Fisher matrix is singular)."""
    plans = [e.plan(st.noise_sd) for e in experiments]
    try:
        cr = cramer_rao(prior, plans, substeps=st.substeps, backend=st.backend)
    except InvalidParameterError:
        return None
    freqs = np.array([e.frequency for e in experiments])
    value = criterion_value(st.target, prior, freqs, cr)
    if not math.isfinite(value) or value <= 0:
        return None
    total = float(sum(e.duration for e in experiments))
    return Design(tuple(experiments), st.noise_sd, cr, value, total)


def _naive(st: _Settings, prior: WienerPlant, budget: float, count: int, grid: _Grid) -> Optional[Design]:
    """Evenly log-spaced frequencies of the usable band at the largest amplitude, equal N, fewer if the
    budget is short (for "G": the tested grid)."""
    fixed = st.target == "G"
    for m in range(max(count, 2), 1, -1):
        if fixed:
            omegas, samples = grid.omegas, grid.samples
        else:
            spaced = np.geomspace(grid.lo, grid.top, m)
            omegas, samples = _on_lab_rate(spaced, st.sample_rate, st.p_cap, grid.lo, grid.top)
        period = 2.0 * np.pi / omegas
        n = int((budget - float(np.sum(st.overhead + st.settle * period))) // float(np.sum(period)))
        if n < st.min_n:
            if fixed:
                return None
            continue
        amps = np.minimum(st.max_amplitude, st.rate / omegas)
        experiments = [
            PlannedExperiment(float(w), float(u), n, int(p), st.settle, st.overhead)
            for w, u, p in zip(omegas, amps, samples)
        ]
        return _design(st, prior, experiments)
    return None
