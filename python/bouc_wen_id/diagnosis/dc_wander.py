"""A smooth wander of the output's zero alone: taken out as a wandering baseline is (session 46, wander46).

The wander test (``baseline.py``) asks the period means to stay rough over the last half of the periods (a
settling transient has died out there, a wander goes on); the zero-drift test (``zero_drift.py``) asks them
to follow a line that does not slow. A baseline that wanders by a fraction of a cycle over each record
(review 45's design C: white noise plus 3 sines of 0.2-1 cycle, RMS one noise sd) does neither: it is far
rougher than a quadratic over the whole record, but smooth over the last half, and it bends, so the
decay test reads it as slowing. Left in, 10 of 30 such nulls were "unexplained" at p = 0 (the drift test
or the DC's structure; studies/cseed46, studies/wander46).

:func:`detect` (on the recordings of :data:`zero_drift.MIN_PERIODS` periods or more after settling) calls
the zero wandering when, pooled over those recordings,

* the period means are correlated from period to period (``baseline``'s lag-1 correlation, at least
  ``WANDER_CORRELATION``: white noise and noise correlated over about a period fall short);
* they are rough about each recording's best settling transient: a level plus an exponential
  approach, its time constant fitted (from half a period to ten records; a line is its slow limit), the
  chi-square against the white noise at :data:`SETTLE_ALPHA`. A loop centre still settling, monotone
  toward its steady value (the designs bench's low-amplitude null, a centre that decays over a few
  periods) fits such a curve to the noise and is left to the settling test as before. Roughness about a
  quadratic (``baseline``'s first test) is not asked: a wander of a fraction of a cycle is often near one
  over the record, and it is still no transient;
* the loop itself does not trend (the fundamental's amplitude, ``zero_drift``'s loop test, p at least
  ``DRIFT_ALPHA``): a degradation moves the loop's shape and is left to the drift tests as before.

Then the wander is taken out (``baseline.removed``): in each recording whose period means sit on a smooth
curve within the noise, that curve, its ramp within each period included, and no random walk's leak on the
noise floor (``wander_curve.py``, session 47); in the others each period's mean with the walk's leak, as
before. The verdict says the zero wanders (and that an output offset cannot be tested, when no
common centre stands out: ``dc_untested.py``).
"""

from __future__ import annotations

import math
from typing import Any, Optional

import numpy as np

from ..model import Recording
from . import wander_curve
from .baseline import WANDER_CORRELATION, Wander, _statistics
from .data import common_centre
from .zero_drift import DRIFT_ALPHA, _recording, _rows

#: Level of the pooled chi-square of the period means about each recording's best settling transient.
SETTLE_ALPHA = 1e-3
#: Time constants (in periods) tried for the settling transient, over the record's own length times these.
_TAUS = np.geomspace(0.05, 10.0, 60)


def settle_rough(dc: np.ndarray, weight: float) -> tuple[float, int]:
    """The period means' chi-square about their best settling transient ``a + b exp(-k / tau)`` (``tau``
    from :data:`_TAUS` times the record's periods, or a line, the slow limit), ``weight`` = P / sigma^2;
    its dof ``n - 3`` (a level, a size and a time constant)."""
    n = dc.size
    k = np.arange(n, dtype=np.float64)
    bases = [np.column_stack([np.ones(n), k - k.mean()])]
    bases += [np.column_stack([np.ones(n), np.exp(-k / (tau * n))]) for tau in _TAUS]
    bases += [np.column_stack([np.ones(n), np.exp(-k / 0.5)])]  # half a period: a jump after the first
    best = math.inf
    for a in bases:
        res = dc - a @ np.linalg.lstsq(a, dc, rcond=None)[0]
        best = min(best, float(res @ res))
    return best * weight, n - 3


def _statistics_dc(items: Any) -> Optional[tuple[float, int, float, float]]:
    """The settling-transient chi-square, its dof and p, and the fundamental's pooled trend p, over the
    Recordings of ``zero_drift.MIN_PERIODS`` periods or more after settling; None when there are none."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    chi2, dof, loop, m = 0.0, 0, 0.0, 0
    for rec in seq:
        if not isinstance(rec, Recording):
            continue
        got = _rows(rec)
        if got is None:
            continue
        rows, p, _ = got
        nums = _recording(rows, p)
        if isinstance(nums, str):  # its periods repeat exactly: nothing to test
            continue
        x2, d2 = settle_rough(rows.mean(axis=1), p / nums[4])
        chi2, dof, loop, m = chi2 + x2, dof + d2, loop + nums[2], m + 1
    if m == 0 or dof <= 0:
        return None
    return chi2, dof, float(chdtrc(dof, chi2)), float(chdtrc(m, loop))


def detect(items: Any, level: float) -> Optional[Wander]:
    """The DC-only wander (module docstring) as a ``baseline.Wander`` (its note says which test took it),
    or None. ``level`` is the common centre's t-test level."""
    st = _statistics(items)
    if st is None:
        return None
    chi2, dof, pval, r, pl, centres = st
    if not r >= WANDER_CORRELATION:
        return None
    dc = _statistics_dc(items)
    if dc is None:
        return None
    sx2, sdof, sp, loop_p = dc
    if not (sp < SETTLE_ALPHA and loop_p >= DRIFT_ALPHA):
        return None
    c, se, cp, kept = common_centre(centres, level)
    seq = list(items) if isinstance(items, (list, tuple)) else [items]
    curves = tuple(wander_curve.degree(rec) if isinstance(rec, Recording) else None for rec in seq)
    numbers = (sx2, sdof, sp, loop_p)
    return Wander(r, pl, chi2, dof, pval, c if kept else 0.0, se, cp, kept, level, numbers, curves)


__all__ = ["detect", "settle_rough", "SETTLE_ALPHA"]
