"""The predicted chance that the diagnosis *names* a term on a design, not only that its F-test passes.

The diagnosis names a term (diagnosis/select.py) when its F-test passes at the step's level, its value is
physical and away from the null (Wald), its law holds (one value across experiments) and it improves the
**held-out** fit: leave one experiment out, fit the physics on the others, refit only the held-out
experiment's own (|G|, phi), and the summed held-out cost must fall. The F-test's power (``_power``) is
therefore an upper bound on the chance to name; where one fold of the design barely sees the term (a sensor
lag fitted on one experiment, where G's phase absorbs it) the held-out test fails although the F-test passes.

The chance is computed in the linearised model ``_power`` already builds: each experiment's 4 x 4 block
``N_i M_i / sigma^2`` (``B_i'`` the Bouc-Wen columns and ``r_i'`` the term's trace at the planned size,
each experiment's own columns projected out) is the Gram matrix of its sufficient statistic ``z_i = A_i theta
+ e_i`` with ``A_i^T A_i`` the block, ``e_i`` standard normal and ``theta = (0, 0, 0, 1)`` the truth (the
prior's Bouc-Wen parameters, the term at its size). Seeded draws of ``e`` then give, per draw, the F-test's
statistic on the whole design (the term's projected ``z``; one-sided where only one sign is named) and each
fold's held-out costs of the plain model and of the model with the term (the term clipped at its bound where
its range is one-sided, as the fit is). The projection is first order; where the refit of the plain model
leaves less than it (``DetectionPower.lam`` below ``lam_linear``) the term's column is scaled by
``sqrt(lam / lam_linear)`` so the whole design's non-centrality is the refitted one. The law test, a test of
a true hypothesis here, refuses at its own level (``LAW_ALPHA``); the Wald test is the F-test's twin in the
linear model. Not modelled: a rival candidate fitting better and being named instead (wrong physics), and
nonlinearity beyond the refit's scaling.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ..diagnosis.select import LAW_ALPHA
from ..errors import InvalidParameterError
from ..model import WienerPlant
from ..terms import TERMS
from ..validation import count
from ._power import (
    DEFAULT_CANDIDATES,
    VAGUE_PRIOR,
    DetectionPower,
    detection_power,
    experiment_block,
    physical_side,
)

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Seeded draws of the linearised model per evaluation (the chance's Monte Carlo standard error is at most
#: 0.5 / sqrt(NAMING_DRAWS), 0.008).
NAMING_DRAWS = 4000


@dataclass(frozen=True)
class NamingChance:
    """The predicted chance that the diagnosis names the term on a design (module docstring)."""

    term: str
    size: float
    #: The chance to name, and its parts: the F-test passing (the linear model's, at the refitted
    #: non-centrality), and the held-out test improving given that it passed.
    chance: float
    f_pass: float
    held_out_given_f: float
    #: The law test's refusal rate of a true law (the chance carries ``1 - law_refusal``).
    law_refusal: float
    #: Each fold's non-centrality (the design less one experiment, linear, scaled as the whole design's),
    #: and the smallest.
    fold_lams: tuple[float, ...]
    draws: int
    seed: int

    @property
    def weakest_fold(self) -> float:
        return min(self.fold_lams) if self.fold_lams else math.nan

    def to_dict(self) -> dict[str, Any]:
        return {
            "term": self.term,
            "size": self.size,
            "chance": self.chance,
            "f_pass": self.f_pass,
            "held_out_given_f": self.held_out_given_f,
            "law_refusal": self.law_refusal,
            "fold_lams": list(self.fold_lams),
            "weakest_fold": self.weakest_fold if self.fold_lams else None,
            "draws": self.draws,
            "seed": self.seed,
        }


@dataclass(frozen=True)
class _Linear:
    """A design in the linearised model: each experiment's ``A_i`` (k, 4, 4) at weight ``N_i / sigma^2``."""

    a: FloatArray
    ridge: FloatArray
    z_c: float
    one_sided: bool
    bounded: bool


def _roots(blocks: FloatArray) -> FloatArray:
    """``A_i`` with ``A_i^T A_i = blocks[i]`` (symmetric square roots: the blocks may be singular)."""
    w, v = np.linalg.eigh(blocks)
    out: FloatArray = np.sqrt(np.clip(w, 0.0, None))[:, :, None] * np.swapaxes(v, 1, 2)
    return out


def _fit(s: FloatArray, g: FloatArray, ridge: FloatArray, with_term: bool) -> FloatArray:
    """Least squares from the normal equations (``g``: draws x 4); the plain model's has the term at 0."""
    sr = s + np.diag(np.append(ridge, 0.0))
    theta = np.zeros_like(g)
    if with_term:
        theta[:] = np.linalg.solve(sr, g.T).T
    else:
        theta[:, :3] = np.linalg.solve(sr[:3, :3], g[:, :3].T).T
    return theta


def _named(lin: _Linear, e: FloatArray, factor: float) -> tuple[BoolArray, BoolArray]:
    """Per draw: whether the F-test passes on the whole design and whether the held-out cost falls, with
    every experiment's periods times ``factor`` (``e``: draws x k x 4 standard normal)."""
    a = math.sqrt(factor) * lin.a
    z = a[None, :, :, 3] + e  # theta = (0, 0, 0, 1): z_i = A_i[:, 3] + e_i
    s = np.einsum("kij,kil->jl", a, a)
    g = np.einsum("kij,dki->dj", a, z)
    sbb = s[:3, :3] + np.diag(lin.ridge)
    w = np.linalg.solve(sbb, s[:3, 3])
    info = float(s[3, 3] - s[3, :3] @ w)
    d = (g[:, 3] - g[:, :3] @ w) / math.sqrt(max(info, 1e-300))
    f_ok: BoolArray = np.asarray(d > lin.z_c if lin.one_sided else np.abs(d) > lin.z_c, dtype=np.bool_)
    k = a.shape[0]
    if k < 2:
        return f_ok, np.ones(f_ok.shape, dtype=np.bool_)
    c0 = np.zeros(e.shape[0])
    c1 = np.zeros(e.shape[0])
    for j in range(k):
        gj = np.einsum("ij,di->dj", a[j], z[:, j])
        sj, rest = a[j].T @ a[j], g - gj
        t0 = _fit(s - sj, rest, lin.ridge, False)
        t1 = _fit(s - sj, rest, lin.ridge, True)
        if lin.bounded:  # the term's fitted range is >= 0: clipped there, the fold's fit is the plain one
            t1 = np.where((t1[:, 3] < 0.0)[:, None], t0, t1)
        c0 += np.sum((z[:, j] - t0 @ a[j].T) ** 2, axis=1)
        c1 += np.sum((z[:, j] - t1 @ a[j].T) ** 2, axis=1)
    return f_ok, np.asarray(c1 < c0, dtype=np.bool_)


def _linear(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    power: DetectionPower,
    noise_sd: float,
    substeps: int,
) -> _Linear:
    blocks = np.array(
        [
            experiment_block(prior, e.frequency, e.amplitude, e.samples_per_period, term, size, substeps)
            * (float(e.periods) / noise_sd**2)
            for e in design
        ]
    )
    if math.isfinite(power.lam) and power.lam_linear > 0.0:  # the refit's non-centrality, not the first order
        kappa = math.sqrt(max(power.lam, 0.0) / power.lam_linear)
        blocks[:, 3, :] *= kappa
        blocks[:, :, 3] *= kappa
    h = prior.normalized().hysteresis
    par = np.array([h.beta, h.gamma, h.mu])
    scale = np.where(par != 0, np.abs(par), 1.0)
    one = power.one_sided or physical_side(term)
    return _Linear(_roots(blocks), VAGUE_PRIOR / scale**2, power.z_c, one, TERMS[term].bounds[0] == 0.0)


def _fold_lams(lin: _Linear) -> tuple[float, ...]:
    s_all = np.einsum("kij,kil->jl", lin.a, lin.a)
    out = []
    for j in range(lin.a.shape[0] if lin.a.shape[0] > 1 else 0):
        s = s_all - lin.a[j].T @ lin.a[j]
        sbb = s[:3, :3] + np.diag(lin.ridge)
        out.append(max(float(s[3, 3] - s[3, :3] @ np.linalg.solve(sbb, s[:3, 3])), 0.0))
    return tuple(out)


def naming_chance(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    *,
    noise_sd: float,
    alpha: float = 0.05,
    candidates: int = DEFAULT_CANDIDATES,
    substeps: int = 8,
    power: Optional[DetectionPower] = None,
    draws: int = NAMING_DRAWS,
    seed: int = 0,
) -> NamingChance:
    """The predicted chance that :func:`~bouc_wen_id.diagnose` names ``term`` at ``size`` on ``design``
    (module docstring); ``power``: the design's :func:`~._power.detection_power`, computed when not given."""
    pw = power or detection_power(
        prior, design, term, size, noise_sd=noise_sd, alpha=alpha, candidates=candidates, substeps=substeps
    )
    n = count("draws", draws, 100)
    lin = _linear(prior, design, term, size, pw, noise_sd, substeps)
    e = np.random.default_rng(seed).standard_normal((n, lin.a.shape[0], 4))
    f_ok, ho = _named(lin, e, 1.0)
    law = LAW_ALPHA if len(design) > 1 else 0.0
    both = float(np.mean(f_ok & ho))
    f = float(np.mean(f_ok))
    return NamingChance(
        pw.term,
        pw.size,
        both * (1.0 - law),
        f,
        both / f if f > 0 else math.nan,
        law,
        _fold_lams(lin),
        n,
        seed,
    )


def naming_factor(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    target: float,
    *,
    noise_sd: float,
    power: DetectionPower,
    substeps: int = 8,
    draws: int = NAMING_DRAWS,
    seed: int = 0,
) -> float:
    """The factor on every experiment's periods that brings the predicted chance to name to ``target``
    (bisection in log on the same seeded draws); inf when a thousandfold does not."""
    if not 0.0 < target < 1.0:
        raise InvalidParameterError(f"target = {target:g} must be within (0, 1)")
    lin = _linear(prior, design, term, size, power, noise_sd, substeps)
    e = np.random.default_rng(seed).standard_normal((draws, lin.a.shape[0], 4))
    keep = 1.0 - (LAW_ALPHA if len(design) > 1 else 0.0)

    def chance(f: float) -> float:
        ok, ho = _named(lin, e, f)
        return float(np.mean(ok & ho)) * keep

    lo, hi = 1e-3, 1e3
    if chance(hi) < target:
        return math.inf
    if chance(lo) >= target:
        return lo
    for _ in range(30):
        mid = math.sqrt(lo * hi)
        lo, hi = (lo, mid) if chance(mid) >= target else (mid, hi)
        if hi / lo < 1.01:
            break
    return hi


__all__ = ["NAMING_DRAWS", "NamingChance", "naming_chance", "naming_factor"]
