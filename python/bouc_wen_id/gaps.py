"""A record with dropped samples or a pause, cut into uniformly sampled pieces (review 35 ``null_drop``).

Every analysis needs a constant step (:func:`.validation.check_time_axis`); a DAQ that drops a few samples,
or pauses, leaves a record none of them takes. Its pieces between the gaps are uniformly sampled, and
``diagnose`` and ``identify`` take them as :class:`~bouc_wen_id.measurement.Measurement` s: the pieces of
one experiment at one nominal frequency (review 35's ``split35.py``: null_drop's records cut at a dropped
sample, "adequate"). A :class:`~bouc_wen_id.model.Recording` cannot take them: each piece would need its own
settle periods; a Measurement's steady segments are found from its data.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike

from .errors import GapWarning, InsufficientDataError, InvalidParameterError
from .measurement import Measurement, _frozen
from .validation import TIME_JITTER_RTOL, TIME_ROUNDING_RTOL, check_time_axis

__all__ = ["MIN_PERIODS", "split_at_gaps"]

#: The fewest nominal periods a piece keeps (the steady-segment analysis needs 2 steady ones, and a piece's
#: first period may read as transient).
MIN_PERIODS = 4.0


def _fields(record: Any) -> tuple[Any, Any, Any, dict[str, Any]]:
    """``(t, u, y, keywords)`` of an object with ``t``, ``u`` and ``y`` (a Measurement, a Recording, ...)."""
    if not all(hasattr(record, k) for k in ("t", "u", "y")):
        raise InvalidParameterError(
            f"split_at_gaps takes t, u and y, or one record with t, u and y; got {type(record).__name__}"
        )
    kw: dict[str, Any] = {}
    nominal = getattr(record, "nominal_frequency", None) or getattr(record, "frequency", None)
    if nominal is not None:
        kw["nominal_frequency"] = nominal
    for k in ("units", "channels", "name", "metadata"):
        v = getattr(record, k, None)
        if v:
            kw[k] = dict(v) if isinstance(v, Mapping) else v
    return record.t, record.u, record.y, kw


def _arguments(t: Any, u: Any, y: Any, keywords: dict[str, Any]) -> tuple[Any, Any, Any, dict[str, Any]]:
    """``(t, u, y, keywords given)``: from the arrays, or from one record (what is given here first)."""
    given = {k: v for k, v in keywords.items() if v}
    if u is None and y is None:
        t, u, y, kw = _fields(t)
        return t, u, y, {**kw, **given}
    if u is None or y is None:
        raise InvalidParameterError("split_at_gaps needs t, u and y (or one record holding them)")
    return t, u, y, given


def split_at_gaps(
    t: Any,
    u: Optional[ArrayLike] = None,
    y: Optional[ArrayLike] = None,
    *,
    nominal_frequency: Optional[float] = None,
    units: Optional[Mapping[str, str]] = None,
    channels: Optional[Mapping[str, str]] = None,
    name: str = "",
    metadata: Optional[Mapping[str, str]] = None,
    rtol: float = TIME_JITTER_RTOL,
    min_periods: float = MIN_PERIODS,
) -> list[Measurement]:
    """Cut a record at its gaps (dropped samples, pauses) into uniformly sampled Measurements.

    A gap is a step longer than the record's median step by more than ``rtol`` of it; the record is cut
    there, each piece keeps its own samples and times (nothing is interpolated), and each becomes a
    :class:`~bouc_wen_id.measurement.Measurement` with the record's nominal frequency, units, channels and
    metadata, named ``"<name> piece k of n"`` with the samples it holds in ``metadata["piece"]``. Give the
    pieces of all experiments to :func:`~bouc_wen_id.diagnose` or :func:`~bouc_wen_id.identify` as one
    list: each piece must hold enough steady periods on its own (diagnose says which does not). A record
    without a gap comes back as one piece. The arrays given are copied, never modified.

    Parameters
    ----------
    t, u, y : array_like
        Sample times (s, strictly increasing) and the input and output samples; or ``t`` alone: an object
        with ``t``, ``u`` and ``y`` (and, when it has them, ``nominal_frequency`` or ``frequency``,
        ``units``, ``channels``, ``name``, ``metadata``, used when not given here).
    nominal_frequency, units, channels, name, metadata
        As for :class:`~bouc_wen_id.measurement.Measurement`, given to every piece.
    rtol : float
        A step longer than ``(1 + rtol)`` times the median step is a gap.
    min_periods : float
        With a nominal frequency, a piece shorter than this many of its periods is left out with a
        :class:`~bouc_wen_id.errors.GapWarning` naming its samples: a piece too short for the steady-period
        analysis stopped diagnose on the whole set (review 35: 3 dropped samples left a 1-period piece).
        0 keeps every piece.

    Raises
    ------
    TimeAxisError
        ``t`` not strictly increasing, or a step shorter than the median beyond ``rtol`` (a jittering or
        resampled axis, not a gap: resample it), or a piece whose own steps jitter.
    InsufficientDataError
        Every piece shorter than ``min_periods``.
    InvalidParameterError
        Lengths differ, or no ``u`` and ``y`` and ``t`` is no record; a piece of a single sample between two
        gaps (it cannot be a Measurement: drop those samples).
    """
    keywords = {"nominal_frequency": nominal_frequency, "units": units, "channels": channels}
    t, u, y, given = _arguments(t, u, y, {**keywords, "name": name, "metadata": metadata})
    if not (isinstance(rtol, (int, float)) and math.isfinite(rtol) and rtol > 0):
        raise InvalidParameterError(f"rtol = {rtol!r} must be a finite number > 0")
    tt, uu, yy = _frozen("t", t), _frozen("u", u), _frozen("y", y)
    if not tt.size == uu.size == yy.size:
        raise InvalidParameterError(
            f"t, u and y must have equal lengths, got {tt.size}, {uu.size}, {yy.size}"
        )
    check_time_axis(tt, gap_factor=1.0 + rtol, rtol=rtol)  # increasing; no step short of the median
    steps = np.diff(tt)
    dt = float(np.median(steps))
    tol = rtol * dt + TIME_ROUNDING_RTOL * max(abs(float(tt[0])), abs(float(tt[-1])))
    cuts = [0, *(int(i) + 1 for i in np.flatnonzero(steps > dt + tol)), tt.size]
    n = len(cuts) - 1
    base = str(given.pop("name", ""))
    meta = dict(given.pop("metadata", {}) or {})
    if not (isinstance(min_periods, (int, float)) and math.isfinite(min_periods) and min_periods >= 0):
        raise InvalidParameterError(f"min_periods = {min_periods!r} must be a finite number >= 0")
    omega = float(given.get("nominal_frequency") or 0.0)
    shortest = 2.0 * math.pi * min_periods / omega if omega > 0 else 0.0
    pieces, short = [], []
    for k, (a, b) in enumerate(zip(cuts[:-1], cuts[1:]), 1):
        if b - a >= 2 and (b - a) * dt < shortest:
            short.append(f"{a}..{b - 1} ({(b - a) * dt * omega / (2.0 * math.pi):.2g} periods)")
            continue
        if b - a < 2:
            raise InvalidParameterError(
                f"sample {a} (t = {tt[a]:.9g} s) lies alone between two gaps: a piece needs 2 samples or "
                "more; drop it from the record"
            )
        label = base if n == 1 else f"{base + ' ' if base else ''}piece {k} of {n}"
        info = {**meta, "piece": f"{k} of {n}: samples {a}..{b - 1}"} if n > 1 else meta
        pieces.append(Measurement(tt[a:b], uu[a:b], yy[a:b], name=label, metadata=info, **given))
    if short:
        said = f"{len(short)} of {n} pieces of {base or 'the record'} left out, shorter than {min_periods:g} "
        said += f"periods: samples {', '.join(short)}"
        if not pieces:
            raise InsufficientDataError(said + "; nothing is left: record longer stretches without gaps")
        warnings.warn(said + " (min_periods=0 keeps them)", GapWarning, stacklevel=2)
    return pieces
