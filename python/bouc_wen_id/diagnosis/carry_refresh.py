"""The drive's harmonics carried through a G seen beside a device term, when the plain model's G failed.

The ``distortion`` term carries each input's harmonics through G at their own frequencies
(:func:`.fitting.carry_through_g`), with G read from the gains and phases of the plain model plus the
term itself, once, before the selection. A device term that model leaves out biases those gains and
phases: in saturation the gains are weakly pinned, so a dashpot on u beside a resonant G moved the
carrying G's pole pair from 6 to 5.84 rad/s and its delay from 0.03 to 0.014 s (review 35's cu_h3: viscous
on u, c = 0.01, a 3 % third harmonic, ``36 / (s^2 + 1.2 s + 36)`` with a 0.03 s delay). At the harmonic
that falls on the peak (6 rad/s, the 2 rad/s experiment's third) that is enough for every set holding the
drive's term to fail its law, and the verdict was "unexplained" (final chi2/dof 68.5).

So when a diagnosis's final model fails its adequacy test and it holds the drive's term beside device
terms, or some step fitted the drive's term beside a device term (the pair step's sets, pairs.py), the
harmonics are carried once more, through the G of the plain model plus those device terms (the final
model's, else the lowest-cost set's), and the whole diagnosis is run again on them. The second diagnosis
replaces the first only when its final model fits better by the adequacy test
(a lower normal score of its chi-square, the order of the p-values that does not underflow at p = 0),
and the verdict says it was carried so (the settings' ``carry_beside``): nothing changes where the first
carry served,
and a set of experiments whose misfit is not the drive's keeps its first verdict. (A two-pole G without
delay, below saturation, viscous on u: the first carry's G from the drive's term alone left the pair's
law failing, "unexplained" at final p = 5e-26; beside the viscous damping the carrying G is the true one
within 1 % and the pair is named, c = 0.00973 +- 0.00058 for 0.01, at final p = 0.043, "in part".)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any, Optional

from ..augmented import AugExperiment, AugFit
from ..terms import TERMS, Distortion
from .fitting import carry_through_g, fit_with
from .limits_void import DEFAULT_ALPHA


def carried(
    sx: Sequence[AugExperiment], plain: AugFit, substeps: int, beside: Sequence[str] = ()
) -> list[AugExperiment]:
    """The waveforms carried through G as :func:`.fitting.carry_through_g` does, seen by the plain model plus
    the terms ``beside``, added one by one (module docstring); a term that does not fit is left out."""
    base = plain
    for term in beside:
        f = fit_with(sx, base, term, substeps)
        base = f if f is not None else base
    return carry_through_g(sx, base, substeps)


def beside_terms(d: Any) -> tuple[str, ...]:
    """The device terms beside which to carry the harmonics again: those of ``d``'s final model when it holds
    the drive's term (a step named it alone, a later one the device term: review 35's drive through a
    resonance with a 3 % second harmonic had the viscous damping named at step 2, and the offset and
    asymmetry that stood in for the misfit of the first carry at steps 3-4), else the device term of the
    lowest-cost set fitted with the drive's term by a pair step (:func:`beside_term`); () for none."""
    final = getattr(getattr(d, "final_fit", None), "params", None)
    terms = tuple(getattr(final, "terms", ()))
    if Distortion.kind in terms:
        own = tuple(t for t in terms if t != Distortion.kind and not TERMS[t].part_of)
        if own:
            return own
    term = beside_term(d)
    return () if term is None else (term,)


def beside_term(d: Any) -> Optional[str]:
    """The device term of the lowest-cost set fitted with the drive's term in ``d``'s steps (pair step's
    sets of two), or None."""
    best: Optional[tuple[float, str]] = None
    for st in getattr(d, "steps", ()):
        for p in getattr(st, "pairs", ()):
            if Distortion.kind not in p.terms or len(p.terms) != 2 or p.fit is None:
                continue
            if not math.isfinite(p.cost):
                continue
            other = next(t for t in p.terms if t != Distortion.kind)
            if best is None or p.cost < best[0]:
                best = (p.cost, other)
    return None if best is None else best[1]


def _fails(d: Any) -> bool:
    alpha = float(getattr(d, "settings", {}).get("alpha", DEFAULT_ALPHA))
    p = float(d.final.p_value)
    return bool(math.isfinite(p) and p < alpha)


def again(d: Any, cands: Sequence[str], rerun: Callable[[tuple[str, ...]], Any]) -> Any:
    """``d``, or the diagnosis ``rerun(terms)`` gives with the harmonics carried beside ``terms``
    (:func:`beside_terms`) when ``d``'s final model fails its adequacy test and that one's fits better by it
    (module docstring)."""
    if Distortion.kind not in cands or not _fails(d):
        return d
    terms = beside_terms(d)
    if not terms:
        return d
    second = rerun(terms)
    if second is None or not math.isfinite(float(second.final.p_value)):
        return d
    if not _z(second) < _z(d):
        return d
    labels = " and ".join(TERMS[t].place_label() if t in TERMS else t for t in terms)
    said = (
        f"; the input's harmonics are carried through G as fitted beside {labels} (a second carry: through "
        f"the plain model's G the final model's chi2/dof was {_per_dof(d):.3g}, through this G "
        f"{_per_dof(second):.3g})"
    )
    settings = {**second.settings, "carry_beside": list(terms)}
    return replace(second, verdict=second.verdict + said, settings=settings)


def _per_dof(d: Any) -> float:
    return float(d.final.cost) / max(int(d.final.dof), 1)


def _z(d: Any) -> float:
    """The final model's adequacy statistic as a normal score, ``(chi2 - dof) / sqrt(2 dof)``: the order of
    the p-values where they are finite, and an order still where both underflow to 0 (review rv36m F3: at
    p = 0 for both a second carry that fits far better could not be kept, nor a worse one refused by fit)."""
    dof = max(int(d.final.dof), 1)
    return (float(d.final.cost) - dof) / math.sqrt(2.0 * dof)
