"""``diagnose``: locate the mismatch, name the physics, model it, prove the fit improves (design.md 10)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

import numpy as np

from ..augmented import AugExperiment, AugFit
from ..errors import InvalidParameterError
from ..terms import DIAGNOSIS_CANDIDATES, Distortion
from .data import DiagExperiment, prepare
from .drift import (
    DEGRADATION,
    DegradationTest,
    corrected,
    degradation_test,
    detrended,
    drift_data,
    strengths,
)
from .fitting import (
    Scale,
    best_of,
    carry_through_g,
    fit_from,
    fit_plain,
    physical,
    scale_of,
    scaled,
    substeps_for,
)
from .locate import Localisation, adequacy_p, locate
from .progress import Progress, reporter
from .result import Diagnosis, ModelSummary, NamedTerm, Status, term_symbol_unit
from .select import ALPHA, FoldCache, forward_select, held_out

#: The named terms must remove at least this share of the plain model's excess residual for the verdict
#: "explained" when the final model is still rejected.
EXPLAINED_FRACTION = 0.9
#: Between this share and EXPLAINED_FRACTION the verdict is "partly explained" (the terms are named, and the
#: structure left is located); below it "unexplained" (the terms are reported as partial, not named).
PARTLY_EXPLAINED_FRACTION = 0.5
#: Every candidate: the steady-loop terms, then degradation, tested in drift space (design.md 10.6).
ALL_CANDIDATES: tuple[str, ...] = DIAGNOSIS_CANDIDATES
#: Passes of the virgin-strength correction of the averaged periods once degradation is named.
CORRECTION_PASSES = 2
#: Why degradation was not tested when the data hold no period-by-period record.
NO_BLOCKS = (
    "degradation not tested: it is seen only in the period-by-period record (at least 2 blocks of periods "
    "per experiment), and these data are averaged periods only"
)


def _check_candidates(candidates: Optional[Sequence[str]]) -> tuple[str, ...]:
    if candidates is None:
        return ALL_CANDIDATES
    out = tuple(candidates)
    bad = [c for c in out if c not in ALL_CANDIDATES]
    if bad or len(set(out)) != len(out):
        raise InvalidParameterError(
            f"candidates must be distinct names among {', '.join(ALL_CANDIDATES)}; got {list(out)!r}"
        )
    return out


def _localise(
    exps: Sequence[DiagExperiment], sx: Sequence[AugExperiment], fit: AugFit, s: Scale
) -> Localisation:
    outs = [np.asarray(y) * s.y for y in fit.outputs]
    amps = [e.amplitude * g for e, g in zip(sx, fit.params.gains)]
    n = 3 + len(fit.params.terms) + 2 * len(sx)
    return locate(exps, outs, amps, list(fit.params.phases), n)


def _summary(
    exps: Sequence[DiagExperiment], sx: Sequence[AugExperiment], fit: AugFit, s: Scale, units: tuple[str, str]
) -> ModelSummary:
    par = fit.params
    terms = []
    for t in par.terms:
        v, se = physical(fit, s, t)
        sym, unit = term_symbol_unit(t, *units)
        terms.append(NamedTerm(t, sym, v, se, unit))
    dof = sum(e.ybar.size for e in sx) - (3 + len(par.terms) + 2 * len(sx))
    noise_dof = sum(e.noise_dof for e in exps)
    nr = []
    for e, y in zip(sx, fit.outputs):
        spread = float(np.linalg.norm(e.ybar - e.ybar.mean()))
        nr.append(float(np.linalg.norm(e.ybar - y)) / spread if spread > 0 else math.nan)
    sm = s.y**par.mu
    return ModelSummary(
        terms=tuple(terms),
        beta=par.beta / sm,
        gamma=par.gamma / sm,
        mu=par.mu,
        cost=fit.cost,
        dof=dof,
        p_value=adequacy_p(fit.cost, dof, noise_dof),
        nrmse=tuple(nr),
        outputs=tuple(np.asarray(y) * s.y for y in fit.outputs),
    )


def classify(plain_adequate: bool, has_terms: bool, final_adequate: bool, fraction: float) -> Status:
    """The verdict's status from the plain model's test, the final model's and the excess explained."""
    if plain_adequate:
        return "adequate"
    if has_terms and (final_adequate or fraction >= EXPLAINED_FRACTION):
        return "explained"
    if has_terms and fraction >= PARTLY_EXPLAINED_FRACTION:
        return "partly explained"
    return "unexplained"


def _verdict(
    status: Status,
    named: Sequence[NamedTerm],
    partial: Sequence[NamedTerm],
    after: Localisation,
    fraction: float,
) -> str:
    if status == "adequate":
        return "adequate: the plain Wiener-Bouc-Wen model fits at the noise floor"
    where = after.describe() or "spread over the cycle"
    if status == "explained":
        drift = "; the loop drifts from period to period (not modelled)" if after.drift_detected else ""
        return "explained by: " + ", ".join(str(t) for t in named) + drift
    if status == "partly explained":
        return (
            "explained in part by: "
            + ", ".join(str(t) for t in named)
            + f" ({100 * fraction:.0f} % of the excess); unexplained structure remains {where}"
        )
    tail = ""
    if partial:
        tail = (
            f" (tested terms {', '.join(t.label for t in partial)} remove {100 * fraction:.0f} % of the "
            "excess but leave structure the library does not model)"
        )
    return f"unexplained structure remains {where}{tail}"


#: Bracket of the joint refinement of d around the drift-space estimate (relative), and its tolerance.
REFINE_BRACKET = 0.3
REFINE_XTOL = 1e-3


def _refine_degradation(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    fit: AugFit,
    data: Sequence[Any],
    deg: DegradationTest,
    s: Scale,
    substeps: int,
) -> tuple[DegradationTest, AugFit]:
    """d refined on both spaces: the drift cost plus the steady cost of the virgin-strength data refitted.

    The drift-space estimate is first order; the averaged periods carry d too (through the strength each
    experiment has reached, design.md 10.6), so the value is refined by a bounded scalar search of
    ``C_drift(d) + C_steady(d)`` within ``REFINE_BRACKET`` of it, and its standard error taken from the
    curvature of that cost (``var = 2 / C''``). The tests stay those of the drift space.
    """
    from scipy.optimize import minimize_scalar  # type: ignore[import-untyped]

    from .drift import _sums

    sums = [_sums(dd) for dd in data]
    fits: dict[float, AugFit] = {}

    def cost(dv: float) -> float:
        _, fs = corrected(exps, sx, fit, dv, s.y, substeps)
        f = fit_from(fs, fit.params, substeps, max_iter=50)
        if f is None:
            return math.inf
        fits[dv] = f
        return f.cost + sum(c0 - 2.0 * dv * nm + dv * dv * dn for c0, nm, dn in sums)

    d0 = deg.d
    res = minimize_scalar(
        cost,
        bounds=((1 - REFINE_BRACKET) * d0, (1 + REFINE_BRACKET) * d0),
        method="bounded",
        options={"xatol": REFINE_XTOL * d0},
    )
    dv = float(res.x)
    if not math.isfinite(float(res.fun)) or dv not in fits:
        return deg, fit
    h = 0.02 * dv
    curv = (cost(dv + h) - 2.0 * float(res.fun) + cost(dv - h)) / (h * h)
    se = math.sqrt(2.0 / curv) if curv > 0 else deg.standard_error * s.y**2
    return replace(deg, d=dv, value=dv / s.y**2, standard_error=se / s.y**2), fits[dv]


def _degradation_stage(
    exps: Sequence[DiagExperiment],
    sx: Sequence[AugExperiment],
    plain: AugFit,
    s: Scale,
    substeps: int,
    alpha: float,
    family: int,
    held_out_test: bool,
) -> Optional[tuple[Optional[DegradationTest], list[DiagExperiment], list[AugExperiment], AugFit]]:
    """The degradation candidate (design.md 10.6): its test, and the data and start the steady selection
    then runs on (the test is None when it cannot be formed); None without a block record.

    Tested on the plain model's Jacobian, Bonferroni over all ``family`` candidates of the first step as if
    it were one of them. When it is named, the averaged periods are brought back to the virgin strength and
    re-estimated at each loop's own strength, twice (the first pass moves the fit from the plain model's
    average strength to the virgin one, the second settles it), then d is refined on both costs.
    """
    data = drift_data(exps, sx, plain, s.y, substeps)
    if not data:
        return None
    deg = degradation_test(data, s.y, alpha, family=family)
    if deg is None or not (deg.named if held_out_test else deg.passed):
        return deg, list(exps), list(sx), plain
    fit, fexps, fsx = plain, list(exps), list(sx)
    for _ in range(CORRECTION_PASSES):
        fexps, fsx = corrected(exps, sx, fit, deg.d, s.y, substeps)
        fit = best_of([fit_from(fsx, fit.params, substeps)]) or fit
        data = drift_data(exps, sx, fit, s.y, substeps, strengths(len(exps), data, deg.d))
        retest = degradation_test(data, s.y, alpha, family=family)
        if retest is None:
            break
        deg = retest
    if not (deg.named if held_out_test else deg.passed):
        # The refined test no longer names it: the steady selection on the data as they are.
        return deg, list(exps), list(sx), plain
    if deg.d > 0:
        deg, fit = _refine_degradation(exps, sx, fit, data, deg, s, substeps)
        fexps, fsx = corrected(exps, sx, fit, deg.d, s.y, substeps)
    return deg, fexps, fsx, fit


def diagnose(
    experiments: Any,
    *,
    candidates: Optional[Sequence[str]] = None,
    alpha: float = ALPHA,
    held_out_test: bool = True,
    y_unit: str = "",
    u_unit: str = "",
    progress: Progress = None,
) -> Diagnosis:
    """Diagnose what the Wiener-Bouc-Wen model leaves out of sine experiments.

    Parameters
    ----------
    experiments : Recording, Measurement, AveragedPeriod or a sequence of them
        The experiments, fitted jointly (shared physics, one |G|, phi per experiment). The output's DC is
        kept, so an offset can be named; the period-by-period record (Recordings, Measurements) feeds the
        drift test and a noise floor that drift does not inflate.
    candidates : sequence of str, optional
        Term names to try (default: the whole library, :data:`ALL_CANDIDATES`: the steady-loop terms of
        :data:`bouc_wen_id.augmented.TERM_NAMES` and ``"degradation"``, which is fitted from the
        period-by-period record and skipped, with the reason in ``Diagnosis.notes``, without one).
    alpha : float
        Family-wise false-alarm level of each step (Bonferroni over the candidates) and of the adequacy gate.
    held_out_test : bool
        Require a held-out improvement before naming a term (leave-one-experiment-out).
    y_unit, u_unit : str
        Units of the output and the input, for the reported term values.
    progress : bool or callable, optional
        Report the stages: True on stderr (a bar on a terminal, else a line per stage), a callable
        ``progress(stage, done, total)`` receives each report; quiet by default.

    Returns
    -------
    Diagnosis
        Verdict first; every named term with its estimate and standard error in physical units.

    Raises
    ------
    InvalidParameterError
        Unknown candidate names or alpha outside (0, 1).
    InsufficientDataError
        Too few periods for a noise floor.
    SearchAtBoundError
        When not even the plain model can be fitted.
    """
    t0 = time.perf_counter()
    report = reporter(progress)
    cands = _check_candidates(candidates)
    if not (0.0 < float(alpha) < 1.0):
        raise InvalidParameterError(f"alpha = {alpha!r} must lie in (0, 1)")
    report("preparing the averaged periods", 0, 1)
    exps = prepare(experiments)
    skipped: dict[str, str] = {}
    if Distortion.kind in cands and not any(e.distorted for e in exps):
        # The term scales the inputs' own harmonics: with pure sines it is the plain model (design.md 9.5).
        cands = tuple(c for c in cands if c != Distortion.kind)
        skipped[Distortion.kind] = (
            "not tested: every input is a pure sine (no harmonic above its noise floor), so the measured "
            "waveform adds nothing to the model"
        )
    s = scale_of(exps)
    sx = scaled(exps, s)
    substeps = substeps_for([e.ybar.size for e in sx])
    noise_dof = sum(e.noise_dof for e in exps)

    def p_of(fit: AugFit) -> float:
        dof = sum(e.ybar.size for e in sx) - (3 + len(fit.params.terms) + 2 * len(sx))
        return adequacy_p(fit.cost, dof, noise_dof)

    def adequate(fit: AugFit) -> bool:
        p = p_of(fit)
        return bool(math.isfinite(p) and p >= alpha)

    def gate(fit: AugFit) -> bool:
        p = p_of(fit)
        return bool(math.isfinite(p) and p >= 0.5 * alpha)

    report("fitting the plain model", 0, 1)
    plain = fit_plain(exps, sx, s, substeps)
    # The distortion term's waveforms through G at their own frequencies, as the plain fit sees G.
    if Distortion.kind in cands:
        report("carrying the input's harmonics through G", 0, 1)
        sx = carry_through_g(sx, plain, substeps)
    before = _localise(exps, sx, plain, s)
    cache: FoldCache = {}
    steady = tuple(c for c in cands if c != DEGRADATION)
    # Degradation first, in drift space (design.md 10.6); when it is named, the steady terms are selected on
    # the averaged periods brought back to one strength.
    deg: Optional[DegradationTest] = None
    notes: list[str] = []
    fexps, fsx, start = exps, sx, plain
    if DEGRADATION in cands:
        report("testing degradation (period blocks)", 0, 1)
        stage = _degradation_stage(exps, sx, plain, s, substeps, alpha, len(cands), held_out_test)
        if stage is None:
            notes.append(NO_BLOCKS)
        else:
            deg, fexps, fsx, start = stage
    named_deg = deg is not None and (deg.named if held_out_test else deg.passed)
    # The plain model's gate: the global test at alpha / 2, and when it accepts, the targeted step's
    # candidate tests at the other alpha / 2 (select.py's docstring; design.md 10.3).
    targeted = not named_deg and not before.drift_detected and gate(start)
    final, steps = forward_select(
        fsx,
        start,
        steady,
        adequate,
        substeps,
        alpha=alpha,
        use_held_out=held_out_test,
        cache=cache,
        targeted=targeted,
        on_trial=lambda k, t, i, n: report(f"step {k}: fitting candidate {t}", i, n),
    )
    after = _localise(detrended(fexps, deg, s.y) if deg is not None and named_deg else fexps, fsx, final, s)
    units = (y_unit, u_unit)
    plain_sum = _summary(exps, sx, plain, s, units)
    final_sum = _summary(fexps, fsx, final, s, units)
    if deg is not None and named_deg:
        sym, unit = term_symbol_unit(DEGRADATION, *units)
        deg_term = NamedTerm(DEGRADATION, sym, deg.value, deg.standard_error, unit)
        final_sum = replace(final_sum, terms=(*final_sum.terms, deg_term))
    excess = plain_sum.cost - plain_sum.dof
    fraction = (plain_sum.cost - final_sum.cost) / excess if excess > 0 else 0.0
    if deg is not None and named_deg:
        # Both spaces: the steady excess and the drift excess, and what the model removes of each.
        total = max(excess, 0.0) + max(deg.cost0 - deg.dof0, 0.0)
        fraction = (plain_sum.cost - final_sum.cost + deg.cost0 - deg.cost1) / total if total > 0 else 0.0
    # More than all of the excess is all of it (a model below the noise floor fitted some noise too).
    fraction = min(fraction, 1.0)
    status = classify(
        targeted and not final.params.terms,
        bool(final.params.terms) or named_deg,
        adequate(final),
        fraction,
    )
    named = final_sum.terms if status in ("explained", "partly explained") else ()
    partial = final_sum.terms if status == "unexplained" else ()
    alternatives = tuple(a for st in steps for a in st.alternatives)
    report("held-out check of the final model", 0, 1)
    ho = held_out(fsx, start, final, substeps, cache) if final.params.terms else None
    report("done", 1, 1)
    return Diagnosis(
        status=status,
        verdict=_verdict(status, named, partial, after, fraction),
        named=named,
        partial=partial,
        alternatives=alternatives,
        before=before,
        after=after,
        steps=tuple(steps),
        held_out=ho,
        plain=plain_sum,
        final=final_sum,
        experiments=tuple(exps),
        explained_fraction=float(fraction),
        settings={
            "candidates": list(cands),
            "skipped": skipped,
            "alpha": alpha,
            "held_out_test": held_out_test,
            "scale": {"y": s.y, "u": s.u},
            "substeps": substeps,
        },
        seconds=time.perf_counter() - t0,
        plain_fit=plain,
        final_fit=final,
        degradation=deg,
        notes=tuple(notes),
    )
