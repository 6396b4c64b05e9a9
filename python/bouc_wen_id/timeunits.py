"""Time in seconds: a time column in another unit is converted when it says so, and named when it does not.

Every time axis of the library is in seconds.  A lab file's time column is often in milliseconds; read as
seconds, every frequency comes out 1000x too low and the fit is confidently wrong.  So

* a time column whose name **declares** its unit (``t [ms]``, ``Time (us)``, ``time_ms``: :mod:`.io`) is
  converted to seconds when the unit is a time (``ms``, ``us``, ``ns``, ``min``, ``h``: ``TIME_UNITS``),
  with a :class:`~bouc_wen_id.errors.UnitWarning`; the experiment's metadata records it
  (``units_converted: "t: ms -> s"``) and the notes of ``identify``/``diagnose`` repeat it.  A time column
  in a unit that is not a time (``Time (mm)``) is a :class:`~bouc_wen_id.errors.UnitMismatchError`;
* an **undeclared** time column whose step disagrees with what the file or the user states by a factor of
  1000 (or 10^6) is a :class:`~bouc_wen_id.errors.TimeUnitError` saying "the time looks like ms (us)", not
  a generic mismatch and never a fit: a stated sample rate (``# sample_rate:``, a DAQ's ``Sampling Rate``)
  against the t column's step, a Recording's frequency omega against the frequency its input repeats at on
  the t axis, a Measurement's ``nominal_frequency`` against the frequency of the sine found in it.

What stays undetectable: a time column in ms with nothing stated beside it (no rate, no frequency, no unit);
a plant 1000x slower is then as plausible as the data, and the file is read as seconds.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._timehint import hint, suspect, time_error, time_scale
from .errors import UnitMismatchError, UnitWarning
from .units import MARK

__all__ = ["check_frequency", "check_rate", "declared", "hint", "time_scale"]


def check_rate(where: str, rate: float, dt: float) -> None:
    """Raise :class:`TimeUnitError` when a t column's step ``dt`` is 1000x (10^6x) the stated rate's."""
    found = suspect(rate * dt)
    if found is not None:
        raise time_error(
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
        raise time_error(
            where,
            *hit,
            f"{what} is {stated:.6g} rad/s, the input repeats at {found:.6g} rad/s on the t column read "
            "as seconds",
        )


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
    if not isinstance(units, Mapping):
        return t, dict(head)
    unit = units.get("t")
    if not isinstance(unit, str) or unit.strip() in ("", "s"):
        return t, dict(head)
    factor = time_scale(unit)
    if factor is None:
        raise UnitMismatchError(
            f"{where}: the time column is in {unit.strip()!r}, which is not a unit of time (s, ms, us, ns, "
            "min, h): rename the column's unit or choose another time column with columns={'t': ...}"
        )
    new_units = {**units, "t": "s"}
    if factor == 1.0:  # "sec", "seconds": seconds by another name
        return t, {**head, "units": new_units}
    mark = f"t: {unit.strip()} -> s"
    old = head.get(MARK)
    out = {**head, "units": new_units, MARK: f"{old}; {mark}" if isinstance(old, str) and old else mark}
    warnings.warn(
        f"{where}: read the time column in {unit.strip()} as seconds (x {factor:g})",
        UnitWarning,
        stacklevel=2,
    )
    return np.asarray(t, dtype=np.float64) * factor, out
