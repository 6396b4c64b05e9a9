"""What the experiments could not have seen: a detection limit per candidate term and place.

When the diagnosis names nothing for a term, the user needs the size below which the design would not have
named it. Each candidate of the first selection step is tested by an F-test (select.py) that rejects when
its cost drop exceeds ``F_c s2``: ``s2`` the test's own residual scale per dof, floored at the noise floor
as the test floors it, ``F_c`` the F(1, dof) quantile of the level the step really runs at
(:func:`test_targets`; ``alpha`` or ``alpha / 2`` on the targeted step, Bonferroni over its candidates,
one-sided for a term confined to ``>= 0`` whose p is halved, two-sided otherwise); the
step also requires the term to explain :data:`~.select.MATERIAL_SHARE` of the excess, so the threshold is
the larger of the two. The cost drop a true value ``v`` produces on noise-free data is the part of the
term's trace the plain model cannot absorb: the trace (plain model plus the term at ``v``, minus the plain
model), weighted, with its projection on the plain model's Jacobian (Bouc-Wen parameters, each
experiment's |G| and phi) removed (:class:`_Profile`). :attr:`DetectionLimit.limit` is the value whose
unabsorbed size reaches the threshold (detected with 50 % power), :attr:`DetectionLimit.limit_90` the
one that reaches it with 90 % power. Where the plain model's parameters move far (a sensor lag, a delay in
G that each experiment's phase absorbs beyond first order), the projection is corrected by two refits of
the plain model (:func:`_refined`); the diagnosis asks for that only when it named nothing (the limits are
then the finding). It is the F-test's limit: naming also needs the held-out and the law tests
(docs/diagnosis.md, "Detection limits", has the calibration by simulation). ``absorbed`` is the share of
the term's raw trace the plain model takes up. :attr:`DetectionLimit.named_90` is the value at which the term
also fits better than every other candidate with 90 % probability (named_limit.py: a rival sharing its
unabsorbed trace takes its place; inf for a twin), and ``not_named`` says why a candidate whose own test
passed on these data was not named (docs/diagnosis.md, "Named at the stated size").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit, augmented_output
from ..errors import BoucWenIdError, BudgetExceededError
from ..terms import TERMS
from . import free_dc, named_limit
from .bounds_said import refused_by_bound
from .design_hint import DesignHint, design_hint
from .fitting import LINEAR_TERMS, Scale, fit_from, physical, regressor
from .result import TERM_LABELS, term_symbol_unit
from .select import BOUNDARY_TERMS, MATERIAL_SHARE, NOISE_FLOOR, Step, dof_of

#: Normal quantile of the power of :attr:`DetectionLimit.limit_90`.
Z_90 = 1.2815515655446004
#: Share of a term's raw trace absorbed by the plain model above which its limit says so.
ABSORBED_SAID = 0.95
#: Under free DCs (free_dc.py), a trace whose projection keeps less than this share of its raw energy was
#: taken whole by the DCs (an offset's: 1e-32-1e-28 measured); what is left is rounding, nothing seen. The
#: smallest real leftover measured (a sensor lag at 1e-3) keeps 9e-5.
ABSORBED_ROUNDING = 1e-20
#: Candidates whose physical range is ``>= 0`` (a rival taking a trace only below 0 is refused;
#: named_limit.py).
NON_NEGATIVE = frozenset(k for k, cls in TERMS.items() if cls.physical[0] == 0.0)
#: Detection limits named in the verdict (the rest are in the JSON and the detailed report).
VERDICT_LIMITS = 4


def test_targets(
    level: float, one_sided: bool, dof: int, s2_fit: float, share_gate: float = 0.0
) -> tuple[float, float, float]:
    """``(thr, t90, s2)``: the unabsorbed size (chi2 units) the candidate's own test needs to pass half the
    time, the one it passes with 90 % probability, and the residual variance per dof its test divides by.

    The test (:func:`.select.f_test`) is ``F = drop / max(s2_fit, NOISE_FLOOR)`` against ``F(1, dof)`` at
    ``level`` (the step's level over its candidates; the p of a term confined to ``>= 0`` halved): ``s2_fit``
    floored as the test floors it. Without that floor (before session 37) a residual below the noise floor
    (coloured noise: the weights are the floor at the low harmonics and the rest of the residual is far
    below it, chi2/dof 0.07-0.11 under AR(1) 0.8 noise) lowered the limits' threshold 10x below the test's
    own, and the stated 90 % value passed its test in 0 of 32 draws (docs/diagnosis.md, "Coverage of the
    90 % value")."""
    from scipy.special import fdtri  # type: ignore[import-untyped]

    s2 = max(s2_fit, NOISE_FLOOR) if math.isfinite(s2_fit) else NOISE_FLOOR
    p = min(2.0 * level if one_sided else level, 1.0)
    crit = float(fdtri(1.0, float(max(dof, 1)), 1.0 - p))
    thr = max(crit * s2, share_gate)
    return thr, (math.sqrt(thr) + Z_90 * math.sqrt(s2)) ** 2, s2


def infinite_note(seen: bool) -> str:
    """Why a candidate has no limit: not detectable within its range, or, when its own test passed on these
    data (``seen``), that the linearised profile did not reach the target within the range: a method
    failure, not a property of the data (review 35m, F1: "not detectable" beside "its own test passed")."""
    if seen:
        return (
            "no limit could be computed: the linearised profile did not reach its target within the term's "
            "admissible range"
        )
    return "not detectable within the term's admissible range"


@dataclass(frozen=True)
class DetectionLimit:
    """The smallest value of one candidate term (at its place) the design detects at the test's level."""

    term: str
    symbol: str
    unit: str
    #: Value at 50 % power (physical units; the sign of the term's physical range; inf: not detectable).
    limit: float
    #: Value at 90 % power.
    limit_90: float
    #: The candidate's fitted value and standard error at the first step (physical units).
    value: float
    standard_error: float
    #: The level of the term's own F-test (the step's level over its candidates), and one- or two-sided.
    level: float
    one_sided: bool
    #: Share of the term's trace absorbed by the plain model's parameters (0-1; NaN when unknown).
    absorbed: float
    #: Why the limit is infinite or undefined ("" when finite).
    note: str = ""
    #: Corrected by refits of the plain model (True), or the first-order projection alone (False: the verdict
    #: named physics, so the limits are context, not the finding; they can read low where most is absorbed).
    refined: bool = True
    #: What would see the 50 % limit with 90 % power (more periods; design_hint.py), for a term the plain
    #: model absorbs at least :data:`ABSORBED_SAID` of; None otherwise.
    hint: Optional[DesignHint] = None
    #: Value at which the verdict names the term at its place with 90 % probability, its test passing and
    #: its fit beating every other candidate's (named_limit.py; inf: a twin of ``rival``, never told from it;
    #: NaN: not computed). At least :attr:`limit_90`.
    named_90: float = math.nan
    #: The candidate whose unabsorbed trace shares most of this one's, and that share (0-1).
    rival: str = ""
    rival_share: float = math.nan
    #: The candidate's own adjusted p at the first step, and why it was not named where that p passed its
    #: level ("" when it did not pass, or when it was named): the data detected it, the verdict did not.
    p_adjusted: float = math.nan
    not_named: str = ""

    def summary_tail(self) -> str:
        """The summary's detection-limit line's tail: the value at which it is told from its rival
        (named_limit.py), and its own test's pass on these data when it was not named."""
        out = named_limit.named_text(self)
        if self.detected_here:
            out += f"; its own test passed on these data (p adj {self.p_adjusted:.2g}), not named: "
            out += self.not_named
        return out

    @property
    def detected_here(self) -> bool:
        """Its own test passed on these data (p adj below its step's level) but it was not named."""
        return bool(self.not_named)

    @property
    def label(self) -> str:
        return TERM_LABELS.get(self.term, self.term)

    def __str__(self) -> str:
        if not math.isfinite(self.limit):
            return f"{self.label}: no detection limit ({self.note})"
        pct = "> 99.9" if self.absorbed >= 0.999 else f"{100 * self.absorbed:.3g}"
        ab = f" ({pct} % absorbed by the plain model)" if self.absorbed >= ABSORBED_SAID else ""
        return f"{self.label} |{self.symbol}| < {self.limit:.2g} {self.unit}".rstrip() + ab

    def to_dict(self) -> dict[str, Any]:
        def n(v: float) -> Optional[float]:
            return v if math.isfinite(v) else None

        return {
            "term": self.term,
            "label": self.label,
            "symbol": self.symbol,
            "unit": self.unit,
            "limit": n(self.limit),
            "limit_90": n(self.limit_90),
            "power": 0.5,
            "value": n(self.value),
            "standard_error": n(self.standard_error),
            "level": self.level,
            "one_sided": self.one_sided,
            "absorbed": n(self.absorbed),
            "note": self.note,
            "refined": self.refined,
            "design_hint": None if self.hint is None else self.hint.to_dict(),
            "named_90": n(self.named_90),
            "not_told_from": self.rival if self.named_90 == math.inf else "",
            "rival": self.rival,
            "rival_share": n(self.rival_share),
            "p_adjusted": n(self.p_adjusted),
            "not_named": self.not_named,
        }


class _Profile:
    """The part of a term's trace the plain model cannot absorb, linearised at the plain fit: ``lam(v)`` is
    the weighted squared residual of (the plain model plus the term at ``v``) minus the plain model, after
    projecting out the plain model's own Jacobian (Bouc-Wen parameters and each experiment's |G|, phi).
    Exact to first order in the plain parameters' moves; the term's own nonlinearity is kept (a sensor lag
    is a delay in G to first order, absorbed by the phase: what remains grows as tau^2)."""

    def __init__(self, exps: Sequence[AugExperiment], base: AugFit, substeps: int) -> None:
        m = len(exps)
        self.exps, self.base, self.substeps = exps, base, substeps
        self.seen: dict[tuple[str, float], tuple[float, float]] = {}
        self.vectors: dict[tuple[str, float], np.ndarray] = {}
        self.unit: dict[str, list[np.ndarray]] = {}  # a linear term's regressors (:meth:`_trace`)
        blocks, self.y0, self.sw = [], [], []
        for i, e in enumerate(exps):
            out = augmented_output(e, base.params, i, substeps=substeps, jacobian=True)
            x = np.zeros((e.ybar.size, out.jacobian.shape[1] + 2 * m))
            x[:, : out.jacobian.shape[1]] = out.jacobian
            x[:, out.jacobian.shape[1] + 2 * i : out.jacobian.shape[1] + 2 * i + 2] = out.own_jacobian
            blocks.append(x)
            self.y0.append(np.asarray(out.y))
            self.sw.append(math.sqrt(e.weight))
        self.blocks = blocks  # each experiment's Jacobian (design_hint.py)
        # A wandering baseline's free DCs (free_dc.py): the traces and the Jacobian projected as the fits
        # project them, so a term whose trace is only those DCs (an offset) is not detectable there.
        _, projected = free_dc.project(exps, self.y0, blocks)
        xa = np.vstack([sw * x for sw, x in zip(self.sw, projected or blocks)])
        xa = xa / (np.linalg.norm(xa, axis=0) + 1e-300)
        u, sv, _ = np.linalg.svd(xa, full_matrices=False)
        self.q = u[:, sv > 1e-10 * sv[0]]

    def __call__(self, term: str, v: float) -> tuple[float, float]:
        """``(lam, raw)``: the unabsorbed and the raw squared size of the term at scaled value ``v``; each
        (term, v) evaluated once (the search, its refinement and the absorbed share ask for the same)."""
        if (term, v) not in self.seen:
            self.seen[(term, v)] = self._sizes(term, v)
        return self.seen[(term, v)]

    def _trace(self, term: str, v: float) -> list[np.ndarray]:
        """Each experiment's trace of ``term`` at scaled ``v``: the model's output with the term minus the
        plain model's; for a linear term (:data:`.fitting.LINEAR_TERMS`: its output is ``v`` times its
        regressor, the model's loop untouched) ``v`` times the regressor, evaluated once per term instead of
        once per value (the search asks for 10-20 values a term; the two agree to 1e-11 of the trace)."""
        if term not in LINEAR_TERMS:
            par = self.base.params.with_term(term, v)
            return [
                np.asarray(augmented_output(e, par, i, substeps=self.substeps)) - y0
                for i, (e, y0) in enumerate(zip(self.exps, self.y0))
            ]
        if term not in self.unit:
            self.unit[term] = [
                regressor(term, e, self.base.params, i, self.substeps) for i, e in enumerate(self.exps)
            ]
        return [v * g for g in self.unit[term]]

    def _sizes(self, term: str, v: float) -> tuple[float, float]:
        diffs = self._trace(term, v)
        r = np.concatenate([sw * d for sw, d in zip(self.sw, diffs)])
        raw = float(r @ r)  # as drawn: what the free DCs take (free_dc.py) counts as absorbed
        r = np.concatenate([sw * d for sw, d in zip(self.sw, free_dc.project(self.exps, diffs)[0])])
        c = self.q.T @ r
        kept = float(r @ r)
        lam = max(kept - float(c @ c), 0.0)
        left = r - self.q @ c
        if free_dc.count(self.exps) and kept <= ABSORBED_ROUNDING * raw:
            lam = 0.0  # the free DCs took it all (an offset's trace): rounding, which would grow with v
            left = np.zeros_like(r)
        self.vectors[(term, v)] = left
        return lam, raw

    def vector(self, term: str, v: float) -> np.ndarray:
        """The unabsorbed trace (weighted, the plain model's Jacobian projected out) at scaled ``v``."""
        self(term, v)
        return self.vectors[(term, v)]

    def exact(self, term: str, v: float) -> float:
        """The unabsorbed size without linearising: the plain model refitted (from the base) to the noise-free
        output of the base plus the term at ``v``; NaN when the fit fails."""
        par = self.base.params.with_term(term, v)
        ys = [
            np.asarray(augmented_output(e, par, i, substeps=self.substeps)) for i, e in enumerate(self.exps)
        ]
        f = fit_from([replace(e, ybar=y) for e, y in zip(self.exps, ys)], self.base.params, self.substeps)
        return f.cost if f is not None else math.nan


#: Doublings of the search for the value whose unabsorbed trace reaches the target, and the log-log
#: interpolations that refine it within its factor-2 bracket (a few per cent).
EXPAND_MAX = 60
REFINE = 3


def _solve(profile: _Profile, term: str, guess: float, targets: Sequence[float]) -> tuple[list[float], float]:
    """Scaled values where ``lam`` reaches each target (inf: not within the term's admissible range), and
    the share of the raw trace absorbed at the first."""
    seen: dict[float, float] = {}

    def lam(v: float) -> float:
        if v not in seen:
            try:
                seen[v] = profile(term, v)[0]
            except BudgetExceededError:
                raise
            except (BoucWenIdError, ValueError, FloatingPointError):
                seen[v] = math.nan
        return seen[v]

    v = guess
    for _ in range(EXPAND_MAX):  # down until below the smaller target, then up until above the larger
        if not (lam(v) >= min(targets)):
            break
        v /= 2.0
    for _ in range(EXPAND_MAX):
        if not math.isfinite(lam(v)) or lam(v) >= max(targets):
            break
        v *= 2.0
    out: list[float] = []
    for t in targets:
        above = [x for x, y in seen.items() if math.isfinite(y) and y >= t]
        below = [x for x, y in seen.items() if math.isfinite(y) and 0 < y < t]
        if not above or not below:
            out.append(math.inf)
            continue
        lower = [x for x in below if x < min(above)]
        if not lower:  # no bracket (lam not monotone there): not located
            out.append(math.inf)
            continue
        a, b = max(lower), min(above)
        for _ in range(REFINE):
            la, lb = math.log(lam(a)), math.log(lam(b))
            w = (math.log(t) - la) / (lb - la) if lb > la else 0.5
            mid = math.exp(math.log(a) + min(max(w, 0.05), 0.95) * (math.log(b) - math.log(a)))
            if not lam(mid) > 0.0:  # nothing left unabsorbed there (free DCs, free_dc.py) or no model
                break
            if lam(mid) < t:
                a = mid
            else:
                b = mid
        out.append(b if abs(lam(b) - t) < abs(lam(a) - t) else a)
    absorbed = math.nan
    if math.isfinite(out[0]):
        lam0, raw = profile(term, out[0])
        absorbed = 1.0 - lam0 / raw if raw > 0 else math.nan
    return out, absorbed


def _refined(profile: _Profile, term: str, v1: float, targets: Sequence[float]) -> tuple[float, float]:
    """The linearised limit corrected by two refits (:meth:`_Profile.exact`): the plain model absorbs more
    than its Jacobian says where its parameters move far (a sensor lag through a steep phase of G). The
    unabsorbed size is taken as a power of the value between the two refits (its exponent from the
    linearised profile at first); both limits are read from it."""
    t50, t90 = targets
    if not math.isfinite(v1):
        return math.inf, math.inf
    try:
        k = math.log(profile(term, 2.0 * v1)[0] / profile(term, v1)[0]) / math.log(2.0)
        l1 = profile.exact(term, v1)
        if not (math.isfinite(k) and k > 0 and math.isfinite(l1) and l1 > 0):
            raise ValueError(term)
        v2 = v1 * (t50 / l1) ** (1.0 / k)
        l2 = profile.exact(term, v2)
        if math.isfinite(l2) and l2 > 0 and abs(math.log(v2 / v1)) > 1e-3:
            k = max(math.log(l2 / l1) / math.log(v2 / v1), 0.25)
        else:
            v2, l2 = v1, l1
    except BudgetExceededError:
        raise
    except (BoucWenIdError, ValueError, FloatingPointError, ZeroDivisionError):
        return v1, v1 * (t90 / t50) ** 0.5  # the linearised limit, 90 % from a linear trace
    v50 = v2 * (t50 / l2) ** (1.0 / k)
    return v50, v50 * (t90 / t50) ** (1.0 / k)


def detection_limits(
    exps: Sequence[AugExperiment],
    base: AugFit,
    steps: Sequence[Step],
    s: Scale,
    units: tuple[str, str],
    alpha: float,
    substeps: int,
    refine: bool = True,
    seconds: Optional[list[float]] = None,
) -> tuple[DetectionLimit, ...]:
    """Every candidate of the first selection step with its detection limit (module docstring); empty when
    no step ran (the plain model accepted with no targeted step). ``base``: the step's starting model;
    ``seconds``: each experiment's measured time (the design hint's cheapest single experiment)."""
    from scipy.special import ndtri

    if not steps:
        return ()
    st = steps[0]
    level = 0.5 * alpha if st.targeted else alpha
    n = max(len(st.trials), 1)
    excess = max(st.before_cost - st.before_dof, 0.0)
    profile = _Profile(exps, base, substeps)
    out = []
    probes: dict[
        str, tuple[float, float, float, float, float]
    ] = {}  # term: scaled lim90, probe, t90, thr, s2
    for tr in st.trials:
        one = tr.term in BOUNDARY_TERMS
        z_c = float(ndtri(1.0 - (level / n if one else level / (2 * n))))
        sym, unit = term_symbol_unit(tr.term, *units)
        fit = tr.fit
        v, se = physical(fit, s, tr.term) if fit is not None else (math.nan, math.nan)
        dof = dof_of(exps, fit) if fit is not None else st.before_dof - 1
        s2_fit = fit.cost / dof if fit is not None and dof > 0 else NOISE_FLOOR
        share_gate = 0.0 if (st.targeted and excess <= 0) else MATERIAL_SHARE * excess
        thr, t90, s2 = test_targets(level / n, one, dof, s2_fit, share_gate)
        targets = [thr, t90]
        se_scaled = fit.standard_error(tr.term) if fit is not None else math.nan
        guess = z_c * se_scaled if math.isfinite(se_scaled) and se_scaled > 0 else 1e-3
        (lim, lim90), absorbed = _solve(profile, tr.term, guess, targets)
        hint = _hint(profile, tr.term, lim, absorbed, targets, seconds)
        if refine:
            lim, lim90 = _refined(profile, tr.term, lim, targets)
        factor = abs(s.factor(tr.term, base.params.mu))
        if fit is not None:
            probes[tr.term] = (lim90, lim if math.isfinite(lim) else guess, targets[1], thr, s2)
        seen = tr.p_adjusted < level and tr.share >= MATERIAL_SHARE  # its threshold's two parts passed here
        why = named_limit.why_not_named(tr, st.chosen or "") if seen and st.chosen != tr.term else ""
        note = infinite_note(seen) if not math.isfinite(lim) else ""
        if refused_by_bound(tr, level):  # detected, beyond its range: no |v| < limit (bounds_said.py)
            lim, lim90, why = math.inf, math.inf, ""
            note = f"fits with {sym} = {v:.3g} {unit}".rstrip() + ", outside its physical range (not named)"
        out.append(
            DetectionLimit(
                tr.term,
                sym,
                unit,
                lim * factor,
                lim90 * factor,
                v,
                se,
                level / n,
                one,
                absorbed,
                note,
                refine,
                hint,
                p_adjusted=tr.p_adjusted,
                not_named=why,
            )
        )
    return tuple(_with_separation(profile, out, probes))


def _with_separation(
    profile: _Profile,
    lims: Sequence[DetectionLimit],
    probes: dict[str, tuple[float, float, float, float, float]],
) -> list[DetectionLimit]:
    """Each limit with the value at which its term is named at its place (named_limit.py): its unabsorbed
    trace at its 90 % value against every other fitted candidate's (at its own limit, or its test's size)."""
    rivals: dict[str, np.ndarray] = {}
    for term, (_, probe, _, _, _) in probes.items():
        try:
            rivals[term] = profile.vector(term, probe)
        except BudgetExceededError:
            raise
        except (BoucWenIdError, ValueError, FloatingPointError):
            continue
    out = []
    for lim in lims:
        if lim.term not in probes or not math.isfinite(lim.limit_90) or lim.term not in rivals:
            out.append(lim)
            continue
        v90, _, t90, thr, s2 = probes[lim.term]
        try:
            r_t = profile.vector(lim.term, v90)
        except BudgetExceededError:
            raise
        except (BoucWenIdError, ValueError, FloatingPointError):
            out.append(lim)
            continue
        others = {k: r for k, r in rivals.items() if k != lim.term}
        sep = named_limit.separation(r_t, others, v90, t90, thr, s2, NON_NEGATIVE)
        named = sep.named_90 * lim.limit_90 / v90 if math.isfinite(sep.named_90) else math.inf
        out.append(replace(lim, named_90=max(named, lim.limit_90), rival=sep.rival, rival_share=sep.share))
    return out


def _hint(
    profile: _Profile, term: str, lim: float, absorbed: float, targets: Sequence[float], seconds: Any
) -> Optional[DesignHint]:
    """design_hint.py's factors where the plain model absorbs most of the term (None elsewhere)."""
    if not (math.isfinite(lim) and absorbed >= ABSORBED_SAID):
        return None
    try:
        return design_hint(profile, term, lim, targets[0], targets[1], seconds)
    except BudgetExceededError:
        raise
    except (BoucWenIdError, ValueError, FloatingPointError, np.linalg.LinAlgError):
        return None


def most_relevant(limits: Sequence[DetectionLimit], count: int = VERDICT_LIMITS) -> list[DetectionLimit]:
    """The candidates whose fitted value is largest against its own limit (closest to being detected),
    finite limits first."""

    def key(lim: DetectionLimit) -> tuple[int, float]:
        r = abs(lim.value) / lim.limit if math.isfinite(lim.limit) and lim.limit > 0 else -1.0
        return (0 if math.isfinite(lim.limit) else 1, -(r if math.isfinite(r) else -1.0))

    return sorted(limits, key=key)[:count]


__all__ = ["DetectionLimit", "detection_limits", "infinite_note", "most_relevant"]
