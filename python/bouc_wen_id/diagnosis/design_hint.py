"""What would bring a detection limit down: more periods, everywhere or in one experiment (issue 18).

An "adequate" verdict quotes each candidate's 90 %-power limit (resolution.py). Where the plain model absorbs
most of a term's trace (a sensor lag is a delay in G to first order), the limit is the design's, and the user
asks what to record to see it. Two answers are cheap here, both computed from what limits.py already holds:

- **every experiment's periods times** ``f = t90 / t50`` (the 90 %- over the 50 %-power threshold of the
  term's test): the weights ``N_i / sigma^2`` scale together, the plain model's refit is unchanged by a common
  weight, so the non-centrality of any value grows exactly by ``f`` and the 50 % limit is then seen with 90 %
  power (the noise's own estimate aside);
- **one experiment's periods times** ``s_j``: the non-centrality is a sum over experiments after eliminating
  each one's own |G_i|, phi_i (planning/_power.py: ``S = sum_i M_i``, ``lam = S_rr - S_rb S_bb^-1 S_br``), so
  raising experiment j's weight by ``s_j`` is a 4 x 4 (3 + terms) update; ``s_j`` is solved at the first-order
  50 % limit (the projection the limit search uses before its refits), so it is first order.

A new frequency is not offered: the diagnosis has G only at the tested frequencies (each experiment's own);
``plan_detection`` (planning/_detect.py) designs that from a prior plant.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np

from ..augmented import augmented_output
from . import free_dc

#: Largest factor on one experiment's periods that is searched (beyond it, the option is not offered).
MAX_FACTOR = 1e4


@dataclass(frozen=True)
class DesignHint:
    """Factors on the periods that see a term's 50 %-power limit with 90 % power."""

    #: Every experiment's periods times this (exact: the non-centrality grows as a common weight).
    periods_factor: float
    #: The experiment whose periods alone raised by ``experiment_factor`` do it at least test time
    #: (-1: none within :data:`MAX_FACTOR`, or not computed under free DCs); first order.
    experiment: int = -1
    experiment_factor: float = math.nan

    def to_dict(self) -> dict[str, Any]:
        return {
            "periods_factor": self.periods_factor,
            "experiment": self.experiment,
            "experiment_factor": self.experiment_factor if math.isfinite(self.experiment_factor) else None,
        }


def _lam(s: Any) -> float:
    k = s.shape[0] - 1
    try:
        absorbed = float(s[k, :k] @ np.linalg.lstsq(s[:k, :k], s[:k, k], rcond=1e-12)[0])
    except np.linalg.LinAlgError:
        return math.nan
    return max(float(s[k, k]) - absorbed, 0.0)


def _blocks(profile: Any, term: str, v: float) -> list[Any]:
    """Each experiment's ``M_i`` (its own gain and phase eliminated) at the term's scaled value ``v``."""
    par = profile.base.params.with_term(term, v)
    n_shared = profile.blocks[0].shape[1] - 2 * len(profile.exps)
    out = []
    for i, (e, y0, sw, x) in enumerate(zip(profile.exps, profile.y0, profile.sw, profile.blocks)):
        r = np.asarray(augmented_output(e, par, i, substeps=profile.substeps)) - y0
        own = x[:, n_shared + 2 * i : n_shared + 2 * i + 2]
        u, sv, _ = np.linalg.svd(own, full_matrices=False)
        q = u[:, sv > 1e-10 * max(float(sv[0]), 1e-300)]
        cols = np.column_stack([x[:, :n_shared], r])
        cols = sw * (cols - q @ (q.T @ cols))
        out.append(cols.T @ cols)
    return out


def _factor(total: Any, block: Any, target: float) -> float:
    """The factor ``s`` on one experiment's weight at which the non-centrality reaches ``target``."""
    if not _lam(total + (MAX_FACTOR - 1.0) * block) >= target:
        return math.inf
    lo, hi = 1.0, MAX_FACTOR
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        if _lam(total + (mid - 1.0) * block) >= target:
            hi = mid
        else:
            lo = mid
        if hi / lo < 1.001:
            break
    return hi


def design_hint(
    profile: Any,
    term: str,
    v_first_order: float,
    t50: float,
    t90: float,
    seconds: Optional[list[float]] = None,
) -> DesignHint:
    """The factors (module docstring) for ``term`` whose first-order 50 % limit is ``v_first_order`` (scaled);
    ``seconds``: each experiment's measured time, to pick the cheapest single experiment (default: equal)."""
    f = t90 / t50
    if free_dc.count(profile.exps) or not math.isfinite(v_first_order):
        return DesignHint(f)
    blocks = _blocks(profile, term, v_first_order)
    total = sum(blocks)
    if not _lam(total) > 0.0:
        return DesignHint(f)
    secs = seconds if seconds is not None and len(seconds) == len(blocks) else [1.0] * len(blocks)
    best, best_cost, best_s = -1, math.inf, math.nan
    for j, b in enumerate(blocks):
        s = _factor(total, b, t90 * _lam(total) / t50)  # relative to what the projection gives at the limit
        cost = (s - 1.0) * secs[j]
        if math.isfinite(s) and cost < best_cost:
            best, best_cost, best_s = j, cost, s
    return DesignHint(f, best, best_s)


__all__ = ["DesignHint", "design_hint"]
