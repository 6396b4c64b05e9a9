"""A named value that moves under preprocessing is not a finding (issue 18; review 38 finding 1).

The study's stability check (stability.py) re-diagnoses each preprocessing variant, four diagnoses in all.
This check is its cheap half, run inside ``diagnose``: when terms are named, the FINAL model (same terms, no
selection) is refitted from its own fit on each variant of the same records (the steady stretch without
its last third, ``early``; without its first third, ``late``; for Measurements also ``half harmonics``,
stability.VARIANTS), and each named value is compared with the main run's.

The rule. A variant holds a subset of the main run's data (two thirds of each steady stretch, or half the
harmonics of the same averaged period). For nested data and an efficient estimator the covariance of the
two estimates is the main run's variance, so var(diff) = se_var^2 - se_main^2 <= max(se)^2: dividing the
difference by max(se_main, se_var) is conservative whatever the (unknown) covariance is. A value moves when
|diff| > z max(se), z the two-sided normal quantile at alpha / (values x variants) (Bonferroni over every
comparison, alpha the diagnosis's family-wise level). A term the library holds truly keeps its value up to
noise on every variant; a term standing in for physics outside the library (a slow creep read as a series
dashpot) takes whatever value fits the stretch it is shown, so it moves.

A moved value is said in the headline ("unstable under preprocessing (...): the value is not a finding;
physics outside the library likely") and an ``explained`` status becomes ``partly explained`` (verdict head
"explained in part by:"). The comparison is in ``settings["value_stability"]`` (JSON). Not checked (and
said there) when the main run fitted a drift term or freed the experiments' DCs (its records were corrected
before the final fit), when a measured input waveform is named (:data:`WAVEFORM`), or when the items are
AveragedPeriods (no record to cut).
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Optional

from ..terms import Distortion
from .result import Diagnosis, NamedTerm

#: The key of the comparison in ``Diagnosis.settings``.
KEY = "value_stability"

#: The verdict head of an explained diagnosis (run_words._verdict) and its revision.
EXPLAINED_BY = "explained by: "
IN_PART_BY = "explained in part by: "


def _z(alpha: float, m: int) -> float:
    from statistics import NormalDist

    return float(NormalDist().inv_cdf(1.0 - alpha / (2.0 * max(m, 1))))


def _cut_recording(rec: Any, variant: str) -> Any:
    """A Recording as the variant preprocesses it: ``early`` without the last third of its steady periods,
    ``late`` with its first third counted as settling (kept in the record, as variants._segments keeps
    it)."""
    p = int(rec.samples_per_period)
    s = int(rec.settle_periods)
    n = int(rec.whole_periods) - s
    third = n // 3
    if variant == "late":
        return replace(rec, settle_periods=s + third)
    end = (s + n - third) * p
    cut = {k: (None if getattr(rec, k) is None else getattr(rec, k)[:end]) for k in ("t", "u", "y", "x", "w")}
    return replace(rec, **cut)


def variant_items(items: Sequence[Any]) -> dict[str, list[Any]]:
    """{variant: its items} for the items' kind: Measurements get every stability.VARIANTS variant,
    Recordings ``early`` and ``late`` (a recording's averaged period keeps every harmonic); {} otherwise."""
    from ..measurement import Measurement
    from ..model import Recording
    from .variants import VARIANTS
    from .variants import variant_items as cut

    keys = [k for k, _ in VARIANTS[1:]]
    if items and all(isinstance(m, Measurement) for m in items):
        return {v: cut(list(items), v) for v in keys}
    if items and all(isinstance(m, Recording) for m in items):
        return {v: [_cut_recording(r, v) for r in items] for v in ("early", "late")}
    return {}


def _refit(d: Diagnosis, items: list[Any], variant: str, units: tuple[str, str]) -> dict[str, NamedTerm]:
    """The final model refitted from its own fit on one variant's items: {term: value}; {} when it fails."""
    from .data import prepare
    from .fitting import Scale, best_of, fit_from, scaled
    from .run_words import _summary
    from .settling import _noise_floors, _settled

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kept, _ = _settled(items)
        exps, _ = _noise_floors(kept, prepare(kept))
    main = {e.source for e in d.experiments}
    suffix = f" ({variant})"
    exps = [e for e in exps if (e.source[: -len(suffix)] if e.source.endswith(suffix) else e.source) in main]
    if not exps or d.final_fit is None:
        return {}
    sc = d.settings["scale"]
    s = Scale(y=float(sc["y"]), u=float(sc["u"]))
    sx = scaled(exps, s)
    fit = best_of([fit_from(sx, d.final_fit.params, int(d.settings["substeps"]))])
    if fit is None:
        return {}
    return {t.term: t for t in _summary(exps, sx, fit, s, units).terms}


#: The measured input waveform's term: its carry of the input's harmonics trades with the variant's own
#: input harmonics, and on a distorted drive through a resonance (test_distortion_resonant.py,
#: test_drive_shape.py) the refits moved its value (1.01 -> -0.005 and 0.11) and dragged a true dashpot's with
#: it: not checked.
WAVEFORM = Distortion.kind
WAVEFORM_WHY = "a measured input waveform is named: its carry trades with each variant's own input harmonics"


def _skip(d: Diagnosis, why: str) -> Diagnosis:
    return replace(d, settings={**d.settings, KEY: {"checked": False, "why": why}})


def checked(d: Diagnosis, items: Sequence[Any], units: tuple[str, str] = ("", "")) -> Diagnosis:
    """``d`` with its named values compared across preprocessing variants of ``items`` (module docstring)."""
    t0 = time.perf_counter()
    steady = [t for t in d.named if d.final_fit is not None and t.term in d.final_fit.params.terms]
    if not steady:
        return d
    if "common_dc" in d.settings or d.degradation is not None and len(steady) < len(d.named):
        return _skip(d, "the records were corrected before the final fit (a drift or a free DC)")
    if any(t.term == WAVEFORM for t in d.named):
        return _skip(d, WAVEFORM_WHY)
    cuts = variant_items(list(items))
    if not cuts:
        return _skip(d, "no record to cut (averaged periods, or a mix of kinds)")
    from ..errors import BoucWenIdError

    fits: dict[str, dict[str, NamedTerm]] = {}
    for v, its in cuts.items():
        try:
            fits[v] = _refit(d, its, v, units)
        except BoucWenIdError:
            fits[v] = {}
    alpha = float(d.settings.get("alpha", 0.05))
    m = len(steady) * sum(1 for f in fits.values() if f)
    z = _z(alpha, m)
    rows, moved = [], []
    for t in steady:
        for v, f in fits.items():
            o = f.get(t.term)
            if o is None:
                continue
            se = max(t.standard_error, o.standard_error)
            score = abs(o.value - t.value) / se if se > 0 and math.isfinite(se) else math.nan
            out = bool(math.isfinite(score) and score > z)
            rows.append({"term": t.term, "variant": v, "value": o.value, "se": o.standard_error, "z": score})
            if out:
                moved.append((t, v, o))
    info = {
        "checked": True,
        "variants": list(cuts),
        "completed": [v for v, f in fits.items() if f],
        "z_threshold": z,
        "comparisons": rows,
        "unstable": sorted({t.term for t, _, _ in moved}),
        "seconds": time.perf_counter() - t0,
    }
    d = replace(d, settings={**d.settings, KEY: info})
    return _revised(d, moved) if moved else d


def _revised(d: Diagnosis, moved: list[tuple[NamedTerm, str, NamedTerm]]) -> Diagnosis:
    by: dict[str, list[str]] = {}
    heads: dict[str, NamedTerm] = {}
    for t, v, o in moved:
        heads[t.term] = t
        by.setdefault(t.term, []).append(f"{o.value:.3g} with the {_what(v)}")
    said = "; ".join(
        f"{t.label} {t.symbol} unstable under preprocessing ({t.symbol} = {t.value:.3g} as recorded, "
        + ", ".join(by[k])
        + ")"
        for k, t in heads.items()
    )
    clause = f"; {said}: the value is not a finding; physics outside the library likely"
    verdict, status = d.verdict, d.status
    if status == "explained":
        status = "partly explained"
        if verdict.startswith(EXPLAINED_BY):
            verdict = IN_PART_BY + verdict[len(EXPLAINED_BY) :]
    return replace(d, status=status, verdict=verdict + clause)


def _what(variant: str) -> str:
    return {"early": "early two thirds", "late": "late two thirds"}.get(variant, variant)


def seconds(d: Diagnosis) -> Optional[float]:
    """The seconds the check added to ``d`` (None: not run)."""
    info = d.settings.get(KEY, {})
    return info.get("seconds") if isinstance(info, dict) else None


__all__ = ["KEY", "checked", "variant_items", "seconds"]
