"""A degrading loop's own centre, predicted, and the output zero's drift tested on what is left (session 30).

An asymmetric loop's centre (its DC) depends on its strength: as the loop degrades its centre moves over the
record, nearly in a straight line, and the zero-drift test (``zero_drift.py``) reads it as a drifting zero
beside a trending loop. Session 29 took that line out with the DC unused and said "a drifting zero or a
degrading loop's centre, not told apart": an asymmetric degrading specimen with a fixed zero lost its
asymmetry (the DC, where it shows, spent) and, at asymmetry 0.4, was reported "not settled".

Here the two are told apart. The fitted model of a diagnosis that named a drift term (its steady model at the
virgin strength, the asymmetry and play kept, and the fitted ``delta_nu`` or ``delta_eta``) is simulated by
the library's simulator (``drift._period_means``, the core's RK4) from rest through each experiment's settling
periods and recorded periods, driven by the fitted latent ``x = A cos(theta - phi)``; each recorded period's
mean is the loop's own centre there. The straight line through those means (per sample on a recording, per
second on a lab measurement) is taken off the record, and the zero-drift test runs on what is left: only a
remaining drift is a drifting zero. :func:`resolved` decides with the diagnosis made under the drift's
removal (``beside``) and, when that one names no drift term or leaves nothing, the diagnosis of the records
as they are (run only then), and of the records less the remaining line alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, Optional

import numpy as np

from . import zero_drift
from .drift import _HYSTERESIS_TERMS, DRIFT_TERMS, SIM_SUBSTEPS, recorded_periods, simulated_periods
from .result import Diagnosis

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class CentreCheck:
    """The predicted centre trend of each item (per sample on a recording, per second on a lab measurement)
    and the zero-drift test on the records less it (None: no drift left)."""

    slopes: tuple[float, ...]
    change: float  # the predicted centre's largest change over a record (units of y)
    remaining: Optional[zero_drift.Drift]
    #: the model that predicted the centre passed its adequacy test (the diagnosis "explained"); else it
    #: fits only in part: the zero is said fixed with that qualification (review of session 30), and a line
    #: left beyond it is not called the zero's drift (session 43)
    fits: bool = True

    def text(self) -> str:
        """The clause for the verdict."""
        if self.remaining is None:
            but = "" if self.fits else ", though the model that predicted it fits the records only in part"
            return (
                "; the period means trend in a straight line as the degrading loop's own centre does (the "
                f"fitted model simulated: up to {self.change:.3g} over a record; what is left does not "
                "drift): the output's zero is taken as fixed: the degrading loop's predicted centre accounts "
                f"for the period means' trend{but}"
            )
        r = self.remaining
        if not self.fits:
            # The rest is measured against a model that fails its adequacy test: its line may be that
            # model's misfit, not the zero's (session 42, eps42: said of a loop neither model fitted).
            return (
                "; the period means trend in a straight line while the loop trends (taken out, the DC not "
                f"used): the loop's centre moves from period to period (the fitted model simulated: up to "
                f"{self.change:.3g} over a record; the rest still trends, p = {r.p_value:.2g}); the fitted "
                "model does not fit well enough to say whether the zero drifts beyond it; an output offset "
                "or each experiment's own DC cannot be told from it"
            )
        return (
            "; the period means trend in a straight line while the loop trends, beyond the degrading loop's "
            f"own centre (the fitted model simulated, up to {self.change:.3g} over a record, taken off: the "
            f"rest still drifts, p = {r.p_value:.2g}, up to {r.largest:.3g}): the output's zero drifts "
            "(taken out, the DC not used); an output offset or each experiment's own DC cannot be told from "
            "it"
        )


def _named_drift(d: Diagnosis) -> bool:
    deg = d.degradation
    return deg is not None and deg.d > 0 and any(t.term in DRIFT_TERMS for t in d.named)


def predicted_slopes(items: Sequence[Any], d: Diagnosis) -> Optional[tuple[list[float], float]]:
    """Each item's predicted centre trend from ``d``'s fitted model and drift term (module docstring), and
    the largest change over a record; None when ``d`` names no drift term, its fit is no cascade's, or the
    items do not map one to one on its experiments (a lab measurement of several stretches)."""
    from ..augmented import AugFit
    from ..measurement import Measurement
    from ..model import Recording

    fit = d.final_fit
    if not _named_drift(d) or not isinstance(fit, AugFit) or len(items) != len(d.experiments):
        return None
    par, deg = fit.params, d.degradation
    sy, su = float(d.settings["scale"]["y"]), float(d.settings["scale"]["u"])
    hysteresis = (float(par.beta), float(par.gamma), float(par.mu))
    terms = tuple((t, float(v)) for t, v in zip(par.terms, par.values) if t in _HYSTERESIS_TERMS)
    sub = max(int(d.settings.get("substeps", SIM_SUBSTEPS)), SIM_SUBSTEPS)
    slopes, change = [], 0.0
    for i, (rec, e) in enumerate(zip(items, d.experiments)):
        if not isinstance(rec, (Recording, Measurement)) or not math.isfinite(e.lead_periods):
            return None
        n, p = recorded_periods(e), int(e.ybar.size)
        if n < 3:
            slopes.append(0.0)
            continue
        plan = (float(e.frequency), max(int(round(e.lead_periods)), 0), n, p, sub)
        amp = float(e.amplitude) / su * float(par.gains[i])
        phi = float(np.mod(par.phases[i], TWO_PI))
        means = _period_means(hysteresis, terms, amp, phi, plan, deg.term, float(deg.d)) * sy
        k = np.arange(n, dtype=np.float64) - (n - 1) / 2.0
        per_period = float(k @ (means - means.mean())) / float(k @ k)
        change = max(change, abs(per_period) * n)
        if isinstance(rec, Recording):
            slopes.append(per_period / int(rec.samples_per_period))
        else:
            slopes.append(per_period * float(e.frequency) / TWO_PI)
    return slopes, change


def _period_means(
    hysteresis: tuple[float, float, float],
    terms: tuple[tuple[str, float], ...],
    amp: float,
    phi: float,
    plan: tuple[float, int, int, int, int],
    term: str,
    dv: float,
) -> Any:
    """Each recorded period's mean of w (scaled units), from the simulation drift.py's correction runs."""
    return simulated_periods(hysteresis, terms, amp, phi, plan, term, dv).mean(axis=1)


def less_trend(items: Sequence[Any], slopes: Sequence[float]) -> list[Any]:
    """The items less their predicted centre lines (new objects; the user's are not modified)."""
    from ..measurement import Measurement
    from ..model import Recording

    out: list[Any] = []
    for rec, b in zip(items, slopes):
        if isinstance(rec, Recording):
            y = zero_drift.detrended(rec, b)
            out.append(replace(rec, y=y))
        elif isinstance(rec, Measurement):
            t = np.asarray(rec.t, dtype=np.float64)
            y = np.asarray(rec.y, dtype=np.float64) - b * (t - float(np.mean(t)))
            out.append(
                Measurement(
                    rec.t, rec.u, y, nominal_frequency=rec.nominal_frequency, units=rec.units,
                    channels=rec.channels, name=rec.name, metadata=dict(rec.metadata),
                )
            )  # fmt: skip
        else:
            out.append(rec)
    return out


def check(items: Sequence[Any], d: Diagnosis, level: float) -> Optional[CentreCheck]:
    """The zero-drift test on ``items`` less the centre trend ``d``'s fitted model predicts (None when it
    cannot be predicted: :func:`predicted_slopes`)."""
    got = predicted_slopes(items, d)
    if got is None:
        return None
    slopes, change = got
    remaining = zero_drift.detect(less_trend(items, slopes), level)
    return CentreCheck(tuple(slopes), change, remaining, d.status == "explained")


def resolved(
    items: Sequence[Any],
    level: float,
    wander: zero_drift.Drift,
    beside: Diagnosis,
    run: Callable[[Sequence[Any]], Diagnosis],
) -> Diagnosis:
    """The diagnosis to report when the zero-drift test fired beside a trending loop (``wander``, taken out
    with each period's mean for ``beside``); ``run(records)`` diagnoses records with nothing taken out.

    * the records as they are (``run(items)``): when its model's centre trend leaves no drift, it is
      reported (the zero fixed, the DC used: an asymmetry and an offset can be named);
    * else, when ``beside`` names a drift term: ``beside``, saying whether its model's centre trend
      explains the line or the zero drifts beyond it (only when that model passed its adequacy test; else
      that the loop's centre moves and the model does not fit well enough to say: :meth:`CentreCheck.text`);
    * else, when the records' own model leaves a drift and fails its adequacy test: ``beside``, saying the
      loop's centre moves and that model does not fit well enough to tell whether the zero drifts beyond it;
    * else, when the records' own model leaves a drift: that remaining line alone is taken out of the
      records (each period's mean kept, so the loop's own centre and its trend stay in the DC) and they are
      diagnosed again; reported when a drift term is named there, else ``beside`` saying the zero drifts;
    * else ``beside`` as it was (the two not told apart).
    """
    first = check(items, beside, level)
    # The records as they are come first even when ``beside``'s model leaves a drift: with the DC not
    # used, its asymmetry is read from the loop's shape alone and may predict too small a centre trend
    # (an asymmetric degrading loop with a fixed zero was then said to drift).
    other = run(items)
    second = check(items, other, level)
    if second is not None and second.remaining is None:
        return replace(other, verdict=other.verdict + second.text(), notes=(*other.notes, _note(second)))
    if first is not None:
        return _said(beside, wander, first)
    if second is None or second.remaining is None:
        return beside
    if not second.fits:
        # The remaining line is measured against a model that fails its adequacy test: not taken for the
        # zero's (it may be that model's misfit), said so on ``beside``.
        return _said(beside, wander, second)
    zero = second.remaining
    third = run(less_trend(items, zero.slopes))
    if not _named_drift(third):
        return _said(beside, wander, second)
    text = (
        "; the output's zero drifts beyond the degrading loop's own centre (the fitted model simulated, up "
        f"to {second.change:.3g} over a record, taken off the period means: the rest drifts, p = "
        f"{zero.p_value:.2g}, up to {zero.largest:.3g}): that line alone was taken out, each period's mean "
        "kept (the loop's centre and its trend are in the DC)"
    )
    return replace(third, verdict=third.verdict + text, notes=(*third.notes, _note(second)))


def _said(d: Diagnosis, wander: zero_drift.Drift, got: CentreCheck) -> Diagnosis:
    """``d`` with the undecided clause replaced by what ``got`` tells."""
    verdict = d.verdict.replace(wander.clause(), got.text())
    return replace(d, verdict=verdict, notes=(*d.notes, _note(got)))


def _note(got: CentreCheck) -> str:
    slopes = ", ".join(f"{b:.3g}" for b in got.slopes)
    left = "no drift left" if got.remaining is None else f"a drift left (p = {got.remaining.p_value:.2g})"
    return (
        "the degrading loop's own centre trend, predicted by the fitted model (simulated over each record; "
        f"slopes {slopes} per sample or per second), taken off the period means before the zero-drift test: "
        f"{left}"
    )


__all__ = ["CentreCheck", "check", "predicted_slopes", "less_trend", "resolved"]
