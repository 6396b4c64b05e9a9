"""``diagnose``: locate the mismatch, name the physics, model it, prove the fit improves (design.md 10)."""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from typing import Any, Optional

import numpy as np

from ..augmented import TERM_NAMES, AugExperiment, AugFit
from ..errors import InvalidParameterError
from .data import DiagExperiment, prepare
from .fitting import Scale, carry_through_g, fit_plain, physical, scale_of, scaled, substeps_for
from .locate import Localisation, adequacy_p, locate
from .result import Diagnosis, ModelSummary, NamedTerm, Status, term_symbol_unit
from .select import ALPHA, FoldCache, forward_select, held_out

#: The named terms must remove at least this share of the plain model's excess residual for the verdict
#: "explained" when the final model is still rejected.
EXPLAINED_FRACTION = 0.9
#: Between this share and EXPLAINED_FRACTION the verdict is "partly explained" (the terms are named, and the
#: structure left is located); below it "unexplained" (the terms are reported as partial, not named).
PARTLY_EXPLAINED_FRACTION = 0.5


def _check_candidates(candidates: Optional[Sequence[str]]) -> tuple[str, ...]:
    if candidates is None:
        return tuple(TERM_NAMES)
    out = tuple(candidates)
    bad = [c for c in out if c not in TERM_NAMES]
    if bad or len(set(out)) != len(out):
        raise InvalidParameterError(
            f"candidates must be distinct names among {', '.join(TERM_NAMES)}; got {list(out)!r}"
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


def diagnose(
    experiments: Any,
    *,
    candidates: Optional[Sequence[str]] = None,
    alpha: float = ALPHA,
    held_out_test: bool = True,
    y_unit: str = "",
    u_unit: str = "",
) -> Diagnosis:
    """Diagnose what the Wiener-Bouc-Wen model leaves out of sine experiments.

    Parameters
    ----------
    experiments : Recording, Measurement, AveragedPeriod or a sequence of them
        The experiments, fitted jointly (shared physics, one |G|, phi per experiment). The output's DC is
        kept, so an offset can be named; the period-by-period record (Recordings, Measurements) feeds the
        drift test and a noise floor that drift does not inflate.
    candidates : sequence of str, optional
        Term names to try (default: the whole library, :data:`bouc_wen_id.augmented.TERM_NAMES`).
    alpha : float
        Family-wise false-alarm level of each step (Bonferroni over the candidates) and of the adequacy gate.
    held_out_test : bool
        Require a held-out improvement before naming a term (leave-one-experiment-out).
    y_unit, u_unit : str
        Units of the output and the input, for the reported term values.

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
    cands = _check_candidates(candidates)
    if not (0.0 < float(alpha) < 1.0):
        raise InvalidParameterError(f"alpha = {alpha!r} must lie in (0, 1)")
    exps = prepare(experiments)
    skipped: dict[str, str] = {}
    if "distortion" in cands and not any(e.distorted for e in exps):
        # The term scales the inputs' own harmonics: with pure sines it is the plain model (design.md 9.5).
        cands = tuple(c for c in cands if c != "distortion")
        skipped["distortion"] = (
            "not tested: every input is a pure sine (no harmonic above its noise floor), so the measured "
            "waveform adds nothing to the model"
        )
    s = scale_of(exps)
    sx = scaled(exps, s)
    substeps = substeps_for([e.ybar.size for e in sx])
    noise_dof = sum(e.noise_dof for e in exps)

    def adequate(fit: AugFit) -> bool:
        dof = sum(e.ybar.size for e in sx) - (3 + len(fit.params.terms) + 2 * len(sx))
        p = adequacy_p(fit.cost, dof, noise_dof)
        return bool(math.isfinite(p) and p >= alpha)

    plain = fit_plain(experiments, exps, s, substeps)
    # The distortion term's waveforms through G at their own frequencies, as the plain fit sees G.
    if "distortion" in cands:
        sx = carry_through_g(sx, plain, substeps)
    before = _localise(exps, sx, plain, s)
    cache: FoldCache = {}
    final, steps = forward_select(
        sx, plain, cands, adequate, substeps, alpha=alpha, use_held_out=held_out_test, cache=cache
    )
    after = _localise(exps, sx, final, s)
    units = (y_unit, u_unit)
    plain_sum = _summary(exps, sx, plain, s, units)
    final_sum = _summary(exps, sx, final, s, units)
    excess = plain_sum.cost - plain_sum.dof
    fraction = (plain_sum.cost - final_sum.cost) / excess if excess > 0 else 0.0
    status = classify(
        adequate(plain) and not before.drift_detected, bool(final.params.terms), adequate(final), fraction
    )
    named = final_sum.terms if status in ("explained", "partly explained") else ()
    partial = final_sum.terms if status == "unexplained" else ()
    alternatives = tuple(a for st in steps for a in st.alternatives)
    ho = held_out(sx, plain, final, substeps, cache) if final.params.terms else None
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
    )
