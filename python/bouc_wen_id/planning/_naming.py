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
linear model. The rivals are the candidates of the step the diagnosis would run (:func:`family`) whose trace
is linear in their value (:func:`linear_rivals`): each is tested at its own critical value (one-sided for a
term whose fitted range is ``>= 0``, two-sided otherwise, as diagnosis/select.py) and the step's choice is
the candidate passing its tests with the largest cost drop, so a linear rival named instead (wrong physics)
is modelled. Not modelled: nonlinear rivals (a series dashpot, pinching, play, Dahl friction, ...)
being named instead, and nonlinearity beyond the refit's scaling; where such a rival resembles the term the
chance over-predicts (docs/power.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np
from numpy.typing import NDArray

from ..diagnosis.candidates import step_candidates
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
    z_critical,
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
    #: non-centrality), and the term being the step's choice (its held-out test improving, no rival with a
    #: larger cost drop passing its own) given that it passed.
    chance: float
    f_pass: float
    named_given_f: float
    #: The chance that a rival (a linear candidate, ``rivals``) is the step's choice instead.
    rival_named: float
    rivals: tuple[str, ...]
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
            "named_given_f": self.named_given_f,
            "rival_named": self.rival_named,
            "rivals": list(self.rivals),
            "law_refusal": self.law_refusal,
            "fold_lams": list(self.fold_lams),
            "weakest_fold": self.weakest_fold if self.fold_lams else None,
            "draws": self.draws,
            "seed": self.seed,
        }


@dataclass(frozen=True)
class _Linear:
    """A design in the linearised model: each experiment's ``A_i`` (k, 4 + R, 4 + R) at weight ``N_i /
    sigma^2``; columns the Bouc-Wen parameters, the term, then its ``R`` linear rivals. ``one_sided`` per
    candidate (the term, then the rivals): only positive values are named; ``bounded``: the term's fitted
    range is ``>= 0``."""

    a: FloatArray
    ridge: FloatArray
    #: Each candidate's critical value (the term, then the rivals): its own test's at the step's level.
    z_c: tuple[float, ...]
    one_sided: tuple[bool, ...]
    bounded: bool


def _roots(blocks: FloatArray) -> FloatArray:
    """``A_i`` with ``A_i^T A_i = blocks[i]`` (symmetric square roots: the blocks may be singular)."""
    w, v = np.linalg.eigh(blocks)
    out: FloatArray = np.sqrt(np.clip(w, 0.0, None))[:, :, None] * np.swapaxes(v, 1, 2)
    return out


def _fit(s: FloatArray, g: FloatArray, ridge: FloatArray, col: int) -> FloatArray:
    """Least squares from the normal equations (``g``: draws x p) on the Bouc-Wen columns and ``col`` (none
    when negative: the plain model); the other coefficients 0."""
    idx = [0, 1, 2] + ([col] if col >= 0 else [])
    sr = s[np.ix_(idx, idx)] + np.diag(np.append(ridge, [0.0] * (len(idx) - 3)))
    theta = np.zeros_like(g)
    theta[:, idx] = np.linalg.solve(sr, g[:, idx].T).T
    return theta


def _statistic(s: FloatArray, g: FloatArray, ridge: FloatArray, col: int) -> FloatArray:
    """Per draw, the signed root of the cost drop of adding column ``col`` to the plain model."""
    sbb = s[:3, :3] + np.diag(ridge)
    w = np.linalg.solve(sbb, s[:3, col])
    info = float(s[col, col] - s[col, :3] @ w)
    out: FloatArray = (g[:, col] - g[:, :3] @ w) / math.sqrt(max(info, 1e-300))
    return out


def _held_out(
    lin: _Linear, a: FloatArray, z: FloatArray, s: FloatArray, g: FloatArray, col: int
) -> BoolArray:
    """Per draw, whether adding column ``col`` lowers the summed held-out cost (leave one experiment out, the
    physics fitted on the others; each experiment's own columns are already projected out)."""
    c0 = np.zeros(z.shape[0])
    c1 = np.zeros(z.shape[0])
    for j in range(a.shape[0]):
        sj, rest = a[j].T @ a[j], g - np.einsum("ij,di->dj", a[j], z[:, j])
        t0 = _fit(s - sj, rest, lin.ridge, -1)
        t1 = _fit(s - sj, rest, lin.ridge, col)
        if col == 3 and lin.bounded:  # fitted range >= 0: clipped there, the fold's fit is the plain one
            t1 = np.where((t1[:, 3] < 0.0)[:, None], t0, t1)
        c0 += np.sum((z[:, j] - t0 @ a[j].T) ** 2, axis=1)
        c1 += np.sum((z[:, j] - t1 @ a[j].T) ** 2, axis=1)
    return np.asarray(c1 < c0, dtype=np.bool_)


def _named(lin: _Linear, e: FloatArray, factor: float) -> tuple[BoolArray, BoolArray, BoolArray]:
    """Per draw (``e``: draws x k x (4 + R) standard normal), with every experiment's periods times
    ``factor``: whether the term's F-test passes, whether the term is the step's choice (the candidate that
    passes its F-test and the held-out test with the largest cost drop, as diagnosis/select.py orders them),
    and whether a rival is chosen instead."""
    a = math.sqrt(factor) * lin.a
    z = a[None, :, :, 3] + e  # theta = (0, 0, 0, 1, 0 ...): z_i = A_i[:, 3] + e_i
    s = np.einsum("kij,kil->jl", a, a)
    g = np.einsum("kij,dki->dj", a, z)
    cols = range(3, a.shape[2])
    score = np.full((z.shape[0], len(cols)), -np.inf)
    f_ok = np.zeros(z.shape[0], dtype=np.bool_)
    for n, col in enumerate(cols):
        d = _statistic(s, g, lin.ridge, col)
        ok = d > lin.z_c[n] if lin.one_sided[n] else np.abs(d) > lin.z_c[n]
        if col == 3:
            f_ok = np.array(ok, dtype=np.bool_)  # a copy: ``ok`` is narrowed below
        if a.shape[0] > 1 and np.any(ok):
            ok &= _held_out(lin, a, z, s, g, col)
        score[:, n] = np.where(ok, d**2, -np.inf)
    chosen = np.argmax(score, axis=1)
    any_ok = np.isfinite(score.max(axis=1))
    return f_ok, any_ok & (chosen == 0), any_ok & (chosen != 0)


def _linear(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    power: DetectionPower,
    noise_sd: float,
    substeps: int,
    rivals: Sequence[str],
) -> _Linear:
    blocks = np.array(
        [
            experiment_block(
                prior, e.frequency, e.amplitude, e.samples_per_period, term, size, substeps, rivals
            )
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
    sided = (power.one_sided or physical_side(term), *(_one_sided(t) for t in rivals))
    z_c = (power.z_c, *(z_critical(t, power.level) for t in rivals))
    return _Linear(_roots(blocks), VAGUE_PRIOR / scale**2, z_c, sided, TERMS[term].bounds[0] == 0.0)


def _one_sided(term: str) -> bool:
    """Whether only one sign of the term is named: its fitted range is ``>= 0`` or its physical one is."""
    return TERMS[term].bounds[0] == 0.0 or physical_side(term)


def linear_rivals(term: str, candidates: Sequence[str]) -> tuple[str, ...]:
    """The candidates the step tests beside ``term`` whose trace is linear in their value (modelled exactly
    in the linearised model); the others (a series dashpot, pinching, Dahl friction, ...) are not."""
    return tuple(t for t in candidates if t != term and getattr(TERMS[t], "linear", False))


def family(term: str, candidates: Union[int, Sequence[str]]) -> tuple[int, tuple[str, ...]]:
    """The step's candidate count (its Bonferroni family) and the term's linear rivals for the diagnosis run
    with ``candidates``: a sequence of term names (as :func:`~bouc_wen_id.diagnose` takes them; the term
    must be among them), or a count. A count of 1 is the term alone (no rival); any other count is taken as
    the diagnosis's own list on pure sines (its linear rivals modelled; where the user's list is shorter this
    counts rivals it does not have, and the chance is on the low side: give the names instead)."""
    if isinstance(candidates, (int, np.integer)) and not isinstance(candidates, bool):
        n = count("candidates", int(candidates), 1)
        return n, () if n == 1 else linear_rivals(term, step_candidates(pure_sines=True))
    from ..diagnosis.run import _check_candidates

    if candidates is None or isinstance(candidates, (str, bytes, float, bool)):
        raise InvalidParameterError(
            f"candidates must be a count or a sequence of term names, got {candidates!r}"
        )
    step = step_candidates(_check_candidates(candidates), pure_sines=True)
    if term not in step:
        raise InvalidParameterError(
            f"candidates {list(candidates)!r} do not include {term!r}: the diagnosis would never name it"
        )
    return len(step), linear_rivals(term, step)


def _fold_lams(lin: _Linear) -> tuple[float, ...]:
    s_all = np.einsum("kij,kil->jl", lin.a, lin.a)
    out = []
    for j in range(lin.a.shape[0] if lin.a.shape[0] > 1 else 0):
        s = s_all - lin.a[j].T @ lin.a[j]
        sbb = s[:3, :3] + np.diag(lin.ridge)
        out.append(max(float(s[3, 3] - s[3, :3] @ np.linalg.solve(sbb, s[:3, 3])), 0.0))
    return tuple(out)


def _setup(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    power: DetectionPower,
    noise_sd: float,
    substeps: int,
    rivals: Optional[Sequence[str]],
    candidates: Union[int, Sequence[str]],
    draws: int,
    seed: int,
) -> tuple[_Linear, FloatArray, tuple[str, ...]]:
    """The linearised design and its seeded standard normal draws; the rivals ``rivals`` (those linear in
    their value), or when None those of the step the diagnosis runs with ``candidates`` (:func:`family`)."""
    if not design:
        raise InvalidParameterError("design has no experiments")
    rv = family(term, candidates)[1] if rivals is None else linear_rivals(term, rivals)
    lin = _linear(prior, design, term, size, power, noise_sd, substeps, rv)
    n = count("draws", draws, 100)
    return lin, np.random.default_rng(seed).standard_normal((n, *lin.a.shape[:2])), rv


def naming_chance(
    prior: WienerPlant,
    design: Sequence[Any],
    term: str,
    size: float,
    *,
    noise_sd: float,
    alpha: float = 0.05,
    candidates: Union[int, Sequence[str]] = DEFAULT_CANDIDATES,
    substeps: int = 8,
    power: Optional[DetectionPower] = None,
    rivals: Optional[Sequence[str]] = None,
    draws: int = NAMING_DRAWS,
    seed: int = 0,
) -> NamingChance:
    """The predicted chance that :func:`~bouc_wen_id.diagnose` names ``term`` at ``size`` on ``design``
    (module docstring); ``power``: the design's :func:`~._power.detection_power`, computed when not given;
    ``candidates``: the diagnosis's candidates, a count or their names (:func:`family`: the rivals modelled
    follow them); ``rivals``: the candidates tested beside it, overriding those (only those linear in
    their value are modelled, :func:`linear_rivals`; ``()``: none); ``seed``: of the draws."""
    n_cand = family(term, candidates)[0]
    pw = power or detection_power(
        prior, design, term, size, noise_sd=noise_sd, alpha=alpha, candidates=n_cand, substeps=substeps
    )
    lin, e, rv = _setup(
        prior, design, pw.term, pw.size, pw, noise_sd, substeps, rivals, candidates, draws, seed
    )
    f_ok, named, rival = _named(lin, e, 1.0)
    law = LAW_ALPHA if len(design) > 1 else 0.0
    f = float(np.mean(f_ok))
    chosen = float(np.mean(named))
    return NamingChance(
        pw.term, pw.size, chosen * (1.0 - law), f, float(np.mean(named & f_ok)) / f if f > 0 else math.nan,
        float(np.mean(rival)), rv, law, _fold_lams(lin), e.shape[0], seed,
    )  # fmt: skip


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
    rivals: Optional[Sequence[str]] = None,
    candidates: Union[int, Sequence[str]] = DEFAULT_CANDIDATES,
    draws: int = NAMING_DRAWS,
    seed: int = 0,
) -> float:
    """The factor on every experiment's periods that brings the predicted chance to name to ``target``
    (bisection in log on the same seeded draws); inf when a thousandfold does not. ``rivals``,
    ``candidates``: as :func:`naming_chance`'s."""
    if not 0.0 < target < 1.0:
        raise InvalidParameterError(f"target = {target:g} must be within (0, 1)")
    lin, e, _ = _setup(prior, design, term, size, power, noise_sd, substeps, rivals, candidates, draws, seed)
    keep = 1.0 - (LAW_ALPHA if len(design) > 1 else 0.0)

    def chance(f: float) -> float:
        return float(np.mean(_named(lin, e, f)[1])) * keep

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


__all__ = ["NAMING_DRAWS", "NamingChance", "family", "linear_rivals", "naming_chance", "naming_factor"]
