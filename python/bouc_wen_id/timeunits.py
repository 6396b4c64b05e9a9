"""Time in seconds: a time column in another unit is converted when it says so, and named when it does not.

Every time axis of the library is in seconds.  A lab file's time column is often in milliseconds; read as
seconds, every frequency comes out 1000x too low and the fit is confidently wrong.  So

* a time column whose name **declares** its unit (``t [ms]``, ``Time (us)``, ``time_ms``: :mod:`.io`) is
  converted to seconds when the unit is a time (``ms``, ``us``, ``ns``, ``min``... any SI prefix of ``s``),
  with a :class:`~bouc_wen_id.errors.UnitWarning`; the experiment's metadata records it
  (``units_converted: "t: ms -> s"``) and the notes of ``identify``/``diagnose`` repeat it.  A unit that is
  not a time (``t [mm]``) is a :class:`~bouc_wen_id.errors.UnitMismatchError`;
* an **undeclared** time column whose step disagrees with what the file or the user states by a factor of
  1000 (or 10^6) is a :class:`~bouc_wen_id.errors.TimeUnitError` saying "the time looks like ms (us)", not
  a generic mismatch and never a fit: a stated sample rate (``# sample_rate:``, a DAQ's ``Sampling Rate``)
  against the t column's step, a Recording's frequency omega against the frequency its input repeats at on
  the t axis, a Measurement's ``nominal_frequency`` against the frequency of the sine found in it.

What stays undetectable: a time column in ms with nothing stated beside it (no rate, no frequency, no unit);
a plant 1000x slower is then as plausible as the data, and the file is read as seconds.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from .errors import TimeUnitError, UnitMismatchError, UnitWarning
from .units import MARK, parse

__all__ = ["SUSPECTS", "TIME_RTOL", "check_frequency", "check_rate", "declared", "suspect", "time_scale"]

#: Relative tolerance on the factor between what a time axis says and what is stated beside it.
TIME_RTOL = 0.03
#: The units an undeclared time column is suspected of, with their factor to seconds.
SUSPECTS = (("ms", 1e-3), ("us", 1e-6))


def time_scale(unit: str) -> Optional[float]:
    """Seconds per ``unit`` (``"ms"`` -> 1e-3, ``"min"`` -> 60); None when ``unit`` is not a time."""
    text = unit.strip()
    if text in ("min", "minute", "minutes"):
        return 60.0
    if text in ("h", "hour", "hours"):
        return 3600.0
    if text in ("seconds", "second", "secs"):
        return 1.0
    found = parse(text)
    return found[1] if found is not None and found[0] == "s" else None


def suspect(ratio: float) -> Optional[tuple[str, float]]:
    """``("ms", 1e-3)`` when ``ratio`` (what is stated / what a time axis read as seconds gives) is 1000 to
    :data:`TIME_RTOL` (``("us", 1e-6)`` for 10^6); None otherwise."""
    if not (math.isfinite(ratio) and ratio > 0.0):
        return None
    for unit, factor in SUSPECTS:
        if abs(ratio * factor - 1.0) <= TIME_RTOL:
            return unit, factor
    return None


def _error(where: str, unit: str, factor: float, what: str) -> TimeUnitError:
    at = f"{where}: " if where else ""
    return TimeUnitError(
        f"{at}the time looks like {unit}, not seconds: {what}, {1.0 / factor:.0f}x apart. The library reads "
        f"time in seconds: divide the time column by {1.0 / factor:.0f}, or name its unit in the column name "
        f"('t [{unit}]', 'time_{unit}') and it is converted"
    )


def check_rate(where: str, rate: float, dt: float) -> None:
    """Raise :class:`TimeUnitError` when a t column's step ``dt`` is 1000x (10^6x) the stated rate's."""
    found = suspect(rate * dt)
    if found is not None:
        raise _error(
            where,
            *found,
            f"the t column steps by {dt:.6g} per sample, the stated sample rate {rate:.6g} Hz needs "
            f"{1.0 / rate:.6g} s",
        )


def check_frequency(where: str, stated: float, found: float, what: str = "the stated frequency") -> None:
    """Raise :class:`TimeUnitError` when ``stated`` (rad/s) is 1000x (10^6x) the frequency ``found`` in the
    data on its time axis read as seconds."""
    hit = suspect(stated / found) if found > 0.0 else None
    if hit is not None:
        raise _error(
            where,
            *hit,
            f"{what} is {stated:.6g} rad/s, the input repeats at {found:.6g} rad/s on the t column read "
            "as seconds",
        )


def data_frequency(t: NDArray[np.float64], u: NDArray[np.float64]) -> float:
    """The frequency (rad/s) of the input's largest spectral peak on the time axis ``t`` (NaN when none)."""
    from .signal._sine import dft_peak

    try:
        return dft_peak(np.asarray(u, dtype=np.float64), float((t[-1] - t[0]) / (t.size - 1)), None)
    except (ValueError, ZeroDivisionError, IndexError):
        return math.nan


def hint(err: BaseException, t: Any, u: Any, stated: float) -> BaseException:
    """``err`` (a mismatch of a stated omega and the data) as a :class:`TimeUnitError` when the input
    repeats 1000x (10^6x) slower than ``stated`` on ``t``; ``err`` itself otherwise."""
    try:
        tt, uu = np.asarray(t, dtype=np.float64), np.asarray(u, dtype=np.float64)
        check_frequency("", float(stated), data_frequency(tt, uu))
    except TimeUnitError as better:
        return TimeUnitError(f"{better} (before: {err})")
    return err


def declared(
    head: Mapping[str, Any], t: NDArray[np.float64], where: str
) -> tuple[NDArray[np.float64], dict[str, Any]]:
    """The time axis in seconds and the header saying so, when the header's ``units`` (from the column
    names, or the header line) give ``t`` another unit; ``(t, head)`` unchanged otherwise.

    Raises
    ------
    UnitMismatchError
        The t column's unit is not a time (``t [mm]``).
    """
    units = head.get("units")
    unit = units.get("t") if isinstance(units, Mapping) else None
    if not isinstance(unit, str) or unit.strip() in ("", "s"):
        return t, dict(head)
    factor = time_scale(unit)
    if factor is None:
        raise UnitMismatchError(
            f"{where}: the time column is in {unit.strip()!r}, which is not a unit of time (s, ms, us, ns, "
            "min, h): rename the column's unit or choose another time column with columns={'t': ...}"
        )
    new_units = {**units, "t": "s"}
    mark = f"t: {unit.strip()} -> s"
    old = head.get(MARK)
    out = {**head, "units": new_units, MARK: f"{old}; {mark}" if isinstance(old, str) and old else mark}
    warnings.warn(
        f"{where}: read the time column in {unit.strip()} as seconds (x {factor:g})",
        UnitWarning,
        stacklevel=2,
    )
    return np.asarray(t, dtype=np.float64) * factor, out


def note_of(item: Any, label: str) -> Optional[str]:
    """The note of a time axis converted on reading (``"t: ms -> s"`` in the metadata), or None."""
    meta = getattr(item, "metadata", {})
    text = meta.get(MARK, "") if isinstance(meta, Mapping) else ""
    for part in str(text).split(";"):
        q, _, rest = part.partition(":")
        src, _, dst = rest.partition("->")
        if q.strip() == "t" and src.strip():
            scale = time_scale(src.strip())
            return f"read the time column of {label} in {src.strip()} as seconds (x {scale:g})"
    return None
