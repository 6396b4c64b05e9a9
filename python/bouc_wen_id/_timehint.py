"""Is a time axis in ms (or us) though read as seconds?  The test behind :class:`TimeUnitError`.

Kept apart from :mod:`bouc_wen_id.timeunits` so that the value module :mod:`bouc_wen_id.model` can name
the error (numpy and :mod:`.errors` only)."""

from __future__ import annotations

import math
import re
from typing import Any, Optional

import numpy as np

from .errors import TimeUnitError

__all__ = ["SUSPECTS", "TIME_RTOL", "hint", "repeats_as", "suspect", "time_error"]

#: Relative tolerance on the factor between what a time axis says and what is stated beside it.
TIME_RTOL = 0.03
#: The units an undeclared time column is suspected of, with their factor to seconds.
SUSPECTS = (("ms", 1e-3), ("us", 1e-6))
#: Largest relative misfit of the input and itself one stated period later for "it repeats there".
REPEAT_MAX = 0.1


#: Units of time (as written) and seconds per unit.
TIME_UNITS = {
    "s": 1.0,
    "sec": 1.0,
    "secs": 1.0,
    "second": 1.0,
    "seconds": 1.0,
    "ms": 1e-3,
    "msec": 1e-3,
    "us": 1e-6,
    "\u00b5s": 1e-6,
    "\u03bcs": 1e-6,
    "ns": 1e-9,
    "ks": 1e3,
    "min": 60.0,
    "minute": 60.0,
    "minutes": 60.0,
    "h": 3600.0,
    "hour": 3600.0,
    "hours": 3600.0,
}
_LABEL = re.compile(
    r"^\s*(t|time)\s*(?:[\(\[]\s*([^\)\]]+?)\s*[\)\]]|_([A-Za-z\u00b5\u03bc]+))\s*$", re.IGNORECASE
)


def time_scale(unit: str) -> Optional[float]:
    """Seconds per ``unit`` (``"ms"`` -> 1e-3, ``"min"`` -> 60); None when ``unit`` is not a time."""
    return TIME_UNITS.get(unit.strip())


def label_unit(label: object) -> Optional[str]:
    """The unit of time a column label declares (``"t [ms]"``, ``"Time (us)"``, ``"time_ms"`` -> ``"ms"``),
    or None."""
    m = _LABEL.match(label) if isinstance(label, str) else None
    unit = (m.group(2) or m.group(3)) if m else None
    return unit if unit is not None and time_scale(unit) is not None else None


def suspect(ratio: float) -> Optional[tuple[str, float]]:
    """``("ms", 1e-3)`` when ``ratio`` (what is stated / what a time axis read as seconds gives) is 1000 to
    :data:`TIME_RTOL` (``("us", 1e-6)`` for 10^6); None otherwise."""
    if not (math.isfinite(ratio) and ratio > 0.0):
        return None
    for unit, factor in SUSPECTS:
        if abs(ratio * factor - 1.0) <= TIME_RTOL:
            return unit, factor
    return None


def time_error(where: str, unit: str, factor: float, what: str) -> TimeUnitError:
    """The error that says the time looks like ``unit`` (``factor`` seconds), and how to fix it."""
    at = f"{where}: " if where else ""
    return TimeUnitError(
        f"{at}the time looks like {unit}, not seconds: {what}, {1.0 / factor:.0f}x apart. The library reads "
        f"time in seconds: divide the time column by {1.0 / factor:.0f}, or name its unit in the column name "
        f"('t [{unit}]', 'time_{unit}') and it is converted"
    )


def _misfit(u: Any, lag: float) -> float:
    """``rms(u(k + lag) - u(k)) / (sqrt 2 rms(u - mean))`` (linear interpolation for a fractional lag): 0
    for an input that repeats after ``lag`` samples, about 1 for one unrelated to itself there."""
    n = u.size
    if not 2.0 <= lag <= n - 2:
        return math.inf
    k = np.arange(n - math.ceil(lag), dtype=np.float64)
    d = np.interp(k + lag, np.arange(n, dtype=np.float64), u) - u[: k.size]
    spread = float(np.mean((u - u.mean()) ** 2))
    return math.sqrt(float(np.mean(d**2)) / (2.0 * spread)) if spread > 0.0 else math.inf


def repeats_as(t: Any, u: Any, stated: float) -> Optional[tuple[str, float]]:
    """``("ms", 1e-3)`` when the input repeats at the stated omega (rad/s) once ``t`` is read in ms (and not
    at half or a third of that period: an input of that period, not of a shorter one); ``("us", 1e-6)``
    likewise; None otherwise."""
    tt, uu = np.asarray(t, dtype=np.float64), np.asarray(u, dtype=np.float64)
    if tt.size < 8 or uu.size != tt.size or not (math.isfinite(stated) and stated > 0.0):
        return None
    dt = float((tt[-1] - tt[0]) / (tt.size - 1))
    if not (math.isfinite(dt) and dt > 0.0):
        return None
    for unit, factor in SUSPECTS:
        lag = 2.0 * math.pi / stated / (dt * factor)
        if _misfit(uu, lag) < REPEAT_MAX and min(_misfit(uu, lag / 2), _misfit(uu, lag / 3)) >= REPEAT_MAX:
            return unit, factor
    return None


def hint(err: BaseException, t: Any, u: Any, stated: float, where: str = "") -> BaseException:
    """``err`` (a stated omega the data do not match) as a :class:`TimeUnitError` when the input repeats at
    ``stated`` with ``t`` read in ms (us); ``err`` itself otherwise."""
    found = repeats_as(t, u, float(stated))
    if found is None:
        return err
    unit, factor = found
    what = (
        f"the input repeats at the stated frequency {stated:.6g} rad/s only with t read in {unit} (at "
        f"{stated * factor:.6g} rad/s on t read as seconds)"
    )
    return time_error(where, unit, factor, f"{what}; before: {err}")
