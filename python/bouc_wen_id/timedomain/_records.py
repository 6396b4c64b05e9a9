"""Time-domain records ``(t, u, y)`` of any waveform, and the checks every time-domain fit runs on them.

A :class:`TimeRecord` is a frozen copy: the arrays handed in are copied and made read-only, so nothing the
user passes is modified and the record cannot change behind a fit's back.  Every bad input ends in a named
error (all :class:`~bouc_wen_id.errors.BoucWenIdError`):

* :class:`~bouc_wen_id.errors.NonFiniteError`: NaN or infinity in ``t``, ``u`` or ``y``;
* :class:`~bouc_wen_id.errors.TimeAxisError`: a time axis that is not strictly increasing (non-causal:
  a sample before its predecessor) or not uniformly sampled;
* :class:`~bouc_wen_id.errors.InvalidParameterError`: unequal lengths, complex or non-1-D data;
* :class:`~bouc_wen_id.errors.InsufficientDataError`: a record shorter than a model's memory
  (:func:`check_memory`), or under :data:`MIN_SAMPLES` samples.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InsufficientDataError, InvalidParameterError
from ..model import Recording
from ..validation import TIME_JITTER_RTOL, check_time_axis, frozen_array

__all__ = ["TimeRecord", "as_time_records", "check_memory", "settling_lead_in", "MIN_SAMPLES"]

FloatArray = NDArray[np.float64]

#: Fewest samples of a record: below this no model with a state can be told from its initial transient.
MIN_SAMPLES = 8


@dataclass(frozen=True, eq=False, init=False)
class TimeRecord:
    """One measured record: time ``t`` (s, uniform, strictly increasing), input ``u`` and output ``y``.

    Parameters
    ----------
    t, u, y : array_like
        1-D, real, finite, equal lengths (>= :data:`MIN_SAMPLES`).  Copied and frozen.
    name : str
        A label for reports (e.g. the file it came from).
    rtol : float
        Largest deviation of a time step from the median step, relative to it (lab data jitter).

    Raises
    ------
    NonFiniteError, TimeAxisError, InvalidParameterError, InsufficientDataError
        See the module docstring.
    """

    t: FloatArray
    u: FloatArray
    y: FloatArray
    name: str
    dt: float

    def __init__(
        self, t: ArrayLike, u: ArrayLike, y: ArrayLike, name: str = "", *, rtol: float = TIME_JITTER_RTOL
    ) -> None:
        arrays = {n: frozen_array(n, v) for n, v in (("t", t), ("u", u), ("y", y))}
        sizes = {n: a.size for n, a in arrays.items()}
        if len(set(sizes.values())) != 1:
            raise InvalidParameterError(f"t, u and y must have equal lengths, got {sizes}")
        if sizes["t"] < MIN_SAMPLES:
            raise InsufficientDataError(
                f"a time record needs at least {MIN_SAMPLES} samples, got {sizes['t']}"
            )
        check_time_axis(arrays["t"], rtol=rtol)
        for n, a in arrays.items():
            object.__setattr__(self, n, a)
        object.__setattr__(self, "name", str(name))
        # The mean step: the simulators run on a uniform grid from t[0].
        object.__setattr__(self, "dt", float((arrays["t"][-1] - arrays["t"][0]) / (sizes["t"] - 1)))

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` (s)."""
        return float(self.t[-1] - self.t[0])

    def __setstate__(self, state: Mapping[str, Any]) -> None:
        for name, value in state.items():
            if isinstance(value, np.ndarray):
                value = np.array(value, dtype=value.dtype, copy=True)
                value.setflags(write=False)
            object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        label = f"{self.name!r}, " if self.name else ""
        return f"TimeRecord({label}{len(self)} samples, dt={self.dt:.6g} s)"


RecordLike = Union[TimeRecord, Recording, tuple[ArrayLike, ArrayLike, ArrayLike]]


def as_time_records(records: Union[RecordLike, Sequence[RecordLike]]) -> list[TimeRecord]:
    """One record or a sequence of them as a list of :class:`TimeRecord`.

    Accepts a :class:`TimeRecord`, a sine :class:`~bouc_wen_id.model.Recording` (its ``t, u, y``) or a
    tuple ``(t, u, y)``; a sequence of those.

    Raises
    ------
    InvalidParameterError
        An empty sequence, or an item of another type.
    """
    if isinstance(records, (TimeRecord, Recording)):
        return [_one(records, 0)]
    if isinstance(records, tuple) and len(records) == 3 and not _is_record_like(records[0]):
        return [_one(records, 0)]
    if not isinstance(records, Sequence) or isinstance(records, (str, bytes)):
        raise InvalidParameterError(
            f"records must be a TimeRecord, a Recording, a (t, u, y) tuple or a sequence of them, "
            f"got {type(records).__name__}"
        )
    out = [_one(r, i) for i, r in enumerate(records)]
    if not out:
        raise InvalidParameterError("records is empty: give at least one (t, u, y) record")
    return out


def _is_record_like(item: object) -> bool:
    return isinstance(item, (TimeRecord, Recording)) or (isinstance(item, tuple) and len(item) == 3)


def _one(item: object, i: int) -> TimeRecord:
    if isinstance(item, TimeRecord):
        return item
    if isinstance(item, Recording):
        return TimeRecord(item.t, item.u, item.y, name=item.metadata.get("name", f"record {i}"))
    if isinstance(item, tuple) and len(item) == 3:
        return TimeRecord(item[0], item[1], item[2], name=f"record {i}")
    raise InvalidParameterError(
        f"record {i} must be a TimeRecord, a Recording or a (t, u, y) tuple, got {type(item).__name__}"
    )


def check_memory(record: TimeRecord, memory: float, what: str = "the model", *, factor: float = 1.0) -> None:
    """Refuse a record shorter than ``factor`` times a model's memory ``memory`` (s).

    The memory is the time over which the model's output still depends on its past (e.g. the delay plus a
    few time constants of G): a record that does not outlast it holds only the initial transient.

    Raises
    ------
    InsufficientDataError
        ``record.duration < factor * memory``.
    """
    need = factor * float(memory)
    if not record.duration >= need:
        label = f" {record.name!r}" if record.name else ""
        raise InsufficientDataError(
            f"the record{label} lasts {record.duration:.6g} s, shorter than {what}'s memory of {need:.6g} s: "
            "it holds only the initial transient; record longer"
        )


def lead_in_samples(record: TimeRecord, lead_in: Optional[float]) -> int:
    """Samples of ``record`` in the first ``lead_in`` seconds (0 when None)."""
    if lead_in is None or lead_in <= 0.0:
        return 0
    return int(np.searchsorted(record.t - record.t[0], float(lead_in), side="left"))


def settling_lead_in(recordings: Sequence[Any]) -> Optional[float]:
    """The shortest declared settling (s) among the sine recordings, None when there is none."""
    times = [
        r.settle_periods * 2.0 * math.pi / r.frequency
        for r in recordings
        if isinstance(r, Recording) and r.settle_periods > 0
    ]
    return min(times) if times else None
