"""The search: each candidate's Fisher blocks, the design score, and the greedy and exchange phases."""

from __future__ import annotations

import math
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..model import WienerPlant
from ..uncertainty import CramerRao, experiment_fisher
from ._settings import _check_g_budget, _Grid, _Settings

FloatArray = NDArray[np.float64]

#: Fraction of the budget the greedy phase spends per step (then single periods at the end).
CHUNK_FRACTION = 1.0 / 50.0
#: Prior precision of the vague prior, relative and per unit noise variance: 1 / (10^4 theta)^2 (keeps a
#: rank-deficient design's criterion finite during the search; absent from the reported bounds).
VAGUE_PRIOR = 1e-8
#: Exchange iterations at most (each keeps the best improving move; it stops earlier when none improves).
MAX_EXCHANGES = 200
#: A move must lower the log-criterion by more than this to count as an improvement.
IMPROVEMENT_TOL = 1e-9


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
