"""Raw lab data: :class:`Measurement`, a sampled input and output without a known exact U and omega.

A :class:`~bouc_wen_id.model.Recording` states the input ``u = U cos(omega t)`` exactly and needs a whole
number of samples per period.  Lab data rarely allow that: the excitation runs off its nominal frequency
(clock mismatch between generator and DAQ), the samples per period are not a whole number, the channels
come in raw DAQ units, the record holds ramps and idle stretches.  A :class:`Measurement` holds such data
as they are, with what is known about them (a nominal frequency as a hint, units, original channel names,
provenance), for the signal analysis to estimate the sine and pick the steady periods.

:func:`clipping_check` refuses channels whose extremes are flat (a sensor or DAQ out of range), telling
a clip from the legitimate repeats of quantised data near a peak.
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Hashable, Mapping
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from . import _optional
from .errors import (
    ClippingError,
    InvalidParameterError,
    NonFiniteError,
    UnitWarning,
)
from .model import Recording, _refreeze
from .validation import check_time_axis

__all__ = ["Measurement", "clipping_check", "RESERVED_KEYS"]

FloatArray = NDArray[np.float64]

#: Header keys of the file formats; metadata may not use them (see :mod:`bouc_wen_id.io`).
RESERVED_KEYS = frozenset(
    {
        "format",
        "version",
        "name",
        "nominal_frequency",
        "nominal_frequency_hz",
        "units",
        "channels",
        "sample_rate",
        "amplitude",
        "frequency",
        "settle_periods",
        "plant",
    }
)
#: ``DataFrame.attrs`` key of what :meth:`Measurement.to_dataframe` keeps beside the columns.
FRAME_ATTR = "bouc_wen_id"
#: Signals a measurement carries; ``units`` and ``channels`` are keyed by these names.
SIGNALS = ("t", "u", "y")

#: A channel is clipped at an extreme when more than this fraction of its samples sit on it ...
CLIP_MIN_FRACTION = 0.01
#: ... in at least this many runs ...
CLIP_MIN_RUNS = 3
#: ... each at least this many samples long ...
CLIP_MIN_RUN = 3
#: ... and longer than this multiple of the dwell a quantised sine has within one step of its peak.
CLIP_DWELL_FACTOR = 2.0
#: "On the extreme" means within this relative distance of it.
CLIP_RTOL = 1e-12
#: A flat run entered or left by a step smaller than this (relative) is an asymptotic approach, not a cut.
CLIP_APPROACH_RTOL = 1e-9


def _frozen(name: str, values: ArrayLike) -> FloatArray:
    try:
        raw = np.asarray(values)
        if raw.dtype.kind == "c":
            raise TypeError(f"complex dtype {raw.dtype}")
        arr = np.array(raw, dtype=np.float64, copy=True)
    except (TypeError, ValueError) as exc:
        raise InvalidParameterError(f"{name} must be an array of real numbers ({exc})") from exc
    if arr.ndim != 1:
        raise InvalidParameterError(f"{name} must be 1-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.flatnonzero(~np.isfinite(arr))[0])
        raise NonFiniteError(f"{name} holds a non-finite value ({arr[bad]}) at index {bad}; clean or drop it")
    arr.setflags(write=False)
    return arr


def _str_map(what: str, mapping: Optional[Mapping[str, str]], keys: tuple[str, ...]) -> dict[str, str]:
    out: dict[str, str] = {}
    for k, v in (mapping or {}).items():
        if k not in keys:
            raise InvalidParameterError(f"{what} are keyed by {', '.join(keys)}; got {k!r}")
        if not isinstance(v, str):
            raise InvalidParameterError(f"{what}[{k!r}] must be a string, got {type(v).__name__}")
        out[k] = v
    return out


def check_metadata_key(key: object) -> str:
    """A metadata key that a ``# key: value`` header line can carry: printable, no ':', stripped."""
    if not isinstance(key, str) or not key or key != key.strip() or ":" in key or not key.isprintable():
        raise InvalidParameterError(
            f"metadata key {key!r} must be a non-empty printable string without ':' or surrounding spaces"
        )
    return key


def _runs(mask: NDArray[np.bool_]) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Starts and lengths of the runs of True in ``mask``."""
    edges = np.diff(np.concatenate(([0], mask.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    return starts, np.flatnonzero(edges == -1) - starts


def _samples_per_period(x: FloatArray) -> float:
    """Median spacing of the upward crossings of the mid level, with a hysteresis of a quarter of the
    half-range so that noise does not count as crossings (the median ignores idle stretches and pauses);
    the record length when there are fewer than two."""
    top, bottom = float(np.max(x)), float(np.min(x))
    mid, band = 0.5 * (top + bottom), 0.25 * (top - bottom)
    high, low = x > mid + band, x < mid - band
    events = np.flatnonzero(high | low)
    ups = events[np.flatnonzero(np.diff(high[events].astype(np.int8)) == 1) + 1]
    if ups.size >= 2:
        return float(np.median(np.diff(ups)))
    return float(x.size)


def clipping_check(x: ArrayLike, name: str = "x") -> None:
    """Raise :class:`ClippingError` when the channel ``x`` has flat tops at its global maximum or minimum.

    A sensor or DAQ driven out of range holds its rail value for a stretch of every period.  An extreme
    counts as clipped when all of these hold:

    * more than 1 % of the samples sit on it (within 1e-12 of the channel's scale);
    * in at least 3 runs of at least 3 consecutive samples;
    * at least 3 of these runs are longer than twice (plus one sample) the dwell that a sine of the
      channel's half-range needs to cross one quantisation step below its peak,
      ``P / pi * arccos(1 - q / A)`` samples (``P`` samples per period from the mid-level crossings,
      ``q`` the channel's quantisation step, the smallest gap between its distinct values): quantised
      data legitimately repeat their top level for that long;
    * each of these runs is entered and left by a step of more than 1e-9 of the channel's scale (a clip
      cuts the signal at a finite slope, a step of at least one quantisation level; a channel settling
      asymptotically onto a plateau, e.g. a noise-free simulated saturation, is not clipped).

    A constant channel is not judged (it has no extremes to compare); other checks refuse it.  A heavy clip
    of a coarsely and coherently sampled sine (e.g. 32 samples per period, a handful of distinct values)
    can pass: there the sampling alone explains flat stretches of that length.
    """
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim != 1:
        raise InvalidParameterError(f"{name} must be 1-D, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise NonFiniteError(f"{name} holds a non-finite value; clean or drop it first")
    if arr.size < CLIP_MIN_RUNS * CLIP_MIN_RUN:
        return
    top, bottom = float(np.max(arr)), float(np.min(arr))
    if top == bottom:
        return
    # Work in units of the largest magnitude: nothing overflows, whatever the channel's scale.
    scale = max(abs(top), abs(bottom))
    unit = arr / scale
    hi, lo = top / scale, bottom / scale
    gaps = np.diff(np.unique(unit))
    gaps = gaps[gaps > 1e-9]
    q = float(np.min(gaps)) if gaps.size else 0.0
    half_range = 0.5 * (hi - lo)
    period = _samples_per_period(unit)
    dwell = period / math.pi * math.acos(max(1.0 - q / half_range, -1.0))
    longest_allowed = max(CLIP_MIN_RUN - 1, CLIP_DWELL_FACTOR * (dwell + 1.0))
    for extreme, scaled_extreme, side in ((top, hi, "maximum"), (bottom, lo, "minimum")):
        on = np.abs(unit - scaled_extreme) <= CLIP_RTOL
        count = int(np.count_nonzero(on))
        if count <= CLIP_MIN_FRACTION * arr.size:
            continue
        starts, lengths = _runs(on)
        long_runs = 0
        for s, n in zip(starts.tolist(), lengths.tolist()):
            if n < CLIP_MIN_RUN or n <= longest_allowed:
                continue
            # The jump into and out of the run (a run at an end of the record has one side only).
            sides = [unit[s - 1]] if s > 0 else []
            sides += [unit[s + n]] if s + n < arr.size else []
            if sides and min(abs(scaled_extreme - v) for v in sides) < CLIP_APPROACH_RTOL:
                continue
            long_runs += 1
        if long_runs >= CLIP_MIN_RUNS:
            longest = int(lengths.max())
            raise ClippingError(
                f"{name} looks clipped at its {side} {extreme:.6g}: {count} samples ({count / arr.size:.1%}) "
                f"sit on it in {long_runs} flat runs up to {longest} samples long, where a sine of this "
                f"range and quantisation (step {q * scale:.3g}, {period:.1f} samples per period) dwells "
                f"about {dwell:.1f} samples at its peak. Check the sensor range and the DAQ gain, or drop "
                "the clipped part"
            )


@dataclass(frozen=True, eq=False, init=False)
class Measurement:
    """One lab record: time, input and output samples, with what is known about them.

    Parameters
    ----------
    t : array_like
        Sample times in seconds, strictly increasing and uniform to 1 % (:class:`TimeAxisError`).
    u, y : array_like
        Input (the excitation, e.g. a displacement) and output (the response, e.g. a force), in any units.
        ``t``, ``u`` and ``y`` are copied, made read-only, and must have equal lengths
        (:class:`InvalidParameterError`) and be finite (:class:`NonFiniteError`).
    nominal_frequency : float, optional
        The excitation's nominal angular frequency in rad/s: a hint for the signal analysis, not a
        truth (the actual frequency is estimated from the data).
    units : mapping, optional
        Units of ``"t"``, ``"u"`` and ``"y"``, e.g. ``{"u": "mm", "y": "N"}``; ``t`` is always in
        seconds (``"t": "s"`` is filled in).
    channels : mapping, optional
        The original channel names of ``"u"`` and ``"y"`` (and ``"t"``), e.g. ``{"u": "CHANNEL1"}``.
    name : str
        A label for reports.
    metadata : mapping, optional
        Free-form strings (provenance, operator, ...).  Keys must fit a ``# key: value`` header line and
        may not be one of the file formats' own keys (:data:`RESERVED_KEYS`).
    """

    t: FloatArray
    u: FloatArray
    y: FloatArray
    nominal_frequency: Optional[float]
    units: Mapping[str, str]
    channels: Mapping[str, str]
    name: str
    metadata: Mapping[str, str]

    def __setstate__(self, state: Mapping[str, object]) -> None:
        # Unpickled arrays come back writeable: freeze them again.
        _refreeze(self, state)

    def __init__(
        self,
        t: ArrayLike,
        u: ArrayLike,
        y: ArrayLike,
        *,
        nominal_frequency: Optional[float] = None,
        units: Optional[Mapping[str, str]] = None,
        channels: Optional[Mapping[str, str]] = None,
        name: str = "",
        metadata: Optional[Mapping[str, str]] = None,
    ) -> None:
        arrays = {k: _frozen(k, v) for k, v in (("t", t), ("u", u), ("y", y))}
        lengths = {k: int(v.size) for k, v in arrays.items()}
        if len(set(lengths.values())) != 1:
            raise InvalidParameterError(f"t, u and y must have equal lengths, got {lengths}")
        check_time_axis(arrays["t"])
        nominal: Optional[float] = None
        if nominal_frequency is not None:
            if isinstance(nominal_frequency, bool):
                raise InvalidParameterError("nominal_frequency must be a number (rad/s), not a bool")
            try:
                nominal = float(nominal_frequency)
            except (TypeError, ValueError, OverflowError) as exc:
                raise InvalidParameterError(f"nominal_frequency must be a number (rad/s): {exc}") from exc
            if not math.isfinite(nominal):
                raise NonFiniteError(f"nominal_frequency = {nominal} is not finite")
            if nominal <= 0:
                raise InvalidParameterError(f"nominal_frequency = {nominal} rad/s must be > 0")
        unit_map = {"t": "s", **_str_map("units", units, SIGNALS)}
        if unit_map["t"] != "s":
            raise InvalidParameterError(
                f"t is in seconds; units['t'] = {unit_map['t']!r}: convert the time axis to seconds"
            )
        if not isinstance(name, str):
            raise InvalidParameterError(f"name must be a string, got {type(name).__name__}")
        meta: dict[str, str] = {}
        for k, v in (metadata or {}).items():
            check_metadata_key(k)
            if k in RESERVED_KEYS:
                raise InvalidParameterError(
                    f"metadata key {k!r} is reserved for the file header; use the Measurement field or "
                    "another key"
                )
            meta[k] = v if isinstance(v, str) else str(v)
        for k, arr in arrays.items():
            object.__setattr__(self, k, arr)
        object.__setattr__(self, "nominal_frequency", nominal)
        object.__setattr__(self, "units", unit_map)
        object.__setattr__(self, "channels", _str_map("channels", channels, SIGNALS))
        object.__setattr__(self, "name", name)
        object.__setattr__(self, "metadata", meta)

    @classmethod
    def from_rate(
        cls,
        sample_rate: float,
        u: ArrayLike,
        y: ArrayLike,
        *,
        nominal_frequency: Optional[float] = None,
        units: Optional[Mapping[str, str]] = None,
        channels: Optional[Mapping[str, str]] = None,
        name: str = "",
        metadata: Optional[Mapping[str, str]] = None,
    ) -> Measurement:
        """A measurement sampled at ``sample_rate`` Hz from t = 0: ``t = k / sample_rate``."""
        rate = check_sample_rate(sample_rate)
        uu = _frozen("u", u)
        with np.errstate(over="ignore"):  # a rate so low that t overflows is a NonFiniteError
            t = np.arange(uu.size) / rate
        return cls(
            t,
            uu,
            y,
            nominal_frequency=nominal_frequency,
            units=units,
            channels=channels,
            name=name,
            metadata=metadata,
        )

    def __len__(self) -> int:
        return int(self.t.size)

    @property
    def dt(self) -> float:
        """Median sampling step (s)."""
        return float(np.median(np.diff(self.t)))

    @property
    def sample_rate(self) -> float:
        """Sampling rate (Hz): the inverse of the median step."""
        return 1.0 / self.dt

    @property
    def duration(self) -> float:
        """``t[-1] - t[0]`` (s)."""
        return float(self.t[-1] - self.t[0])

    def check(self) -> None:
        """Run :func:`clipping_check` on ``u`` and ``y`` (raises :class:`ClippingError`)."""
        for name, x in (("u", self.u), ("y", self.y)):
            label = name if name not in self.channels else f"{name} ({self.channels[name]})"
            clipping_check(x, f"{self.name + ': ' if self.name else ''}{label}")

    def segment(self, start: Optional[float] = None, stop: Optional[float] = None) -> Measurement:
        """The samples with ``start <= t < stop`` (seconds; None for open ends), as a new measurement."""
        lo = 0 if start is None else int(np.searchsorted(self.t, start, side="left"))
        hi = self.t.size if stop is None else int(np.searchsorted(self.t, stop, side="left"))
        return self._replace(self.t[lo:hi], self.u[lo:hi], self.y[lo:hi])

    def scaled(
        self, u: float = 1.0, y: float = 1.0, *, units: Optional[Mapping[str, str]] = None
    ) -> Measurement:
        """Raw channel values to physical ones: ``u * u_scale``, ``y * y_scale``, with the new units.

        E.g. ``m.scaled(u=10.0, y=980.665, units={"u": "mm", "y": "N"})`` for a DAQ's volts.
        """
        new_units = {**self.units, **(units or {})}
        with np.errstate(over="ignore", invalid="ignore"):  # overflow is a NonFiniteError
            su, sy = self.u * float(u), self.y * float(y)
        return self._replace(self.t, su, sy, units=new_units)

    def _replace(
        self, t: FloatArray, u: FloatArray, y: FloatArray, units: Optional[Mapping[str, str]] = None
    ) -> Measurement:
        return Measurement(
            t,
            u,
            y,
            nominal_frequency=self.nominal_frequency,
            units=self.units if units is None else units,
            channels=self.channels,
            name=self.name,
            metadata=self.metadata,
        )

    def to_recording(self, amplitude: float, frequency: float, settle_periods: int = 0) -> Recording:
        """This measurement as a :class:`Recording` with the known ``u = amplitude cos(frequency t)``.

        For data whose U and omega (rad/s) are known exactly; the Recording's own checks apply (a time
        grid uniform to 1e-5 of a step, and, when identified, a whole number of samples per period and
        an input matching ``U cos(omega t)``).  The name, units, channels and nominal frequency go into the
        recording's metadata (the dicts as JSON strings).
        """
        meta: dict[str, str] = {}
        if self.name:
            meta["name"] = self.name
        meta["units"] = json.dumps(dict(self.units))
        if self.channels:
            meta["channels"] = json.dumps(dict(self.channels))
        if self.nominal_frequency is not None:
            meta["nominal_frequency"] = repr(self.nominal_frequency)
        meta.update(self.metadata)
        return Recording(
            self.t, self.u, self.y, amplitude, frequency, settle_periods=settle_periods, metadata=meta
        )

    @classmethod
    def from_dataframe(
        cls,
        df: Any,
        *,
        input: Hashable = "u",
        output: Hashable = "y",
        time: Optional[Hashable] = None,
        sample_rate: Optional[float] = None,
        units: Optional[Mapping[str, str]] = None,
        nominal_frequency: Optional[float] = None,
        name: Optional[str] = None,
        metadata: Optional[Mapping[str, str]] = None,
    ) -> Measurement:
        """A measurement from a :class:`pandas.DataFrame` (needs pandas: the ``pandas`` extra).

        Parameters
        ----------
        df : pandas.DataFrame
            One row per sample.  It is read, never modified.
        input, output : column label
            The columns holding u (the excitation) and y (the response); their labels become
            :attr:`channels`.
        time : column label, optional
            A column of times: seconds (numbers), ``datetime64`` or ``timedelta64`` (both made seconds from
            the first row).  Without it the index is the time axis: a ``DatetimeIndex`` or
            ``TimedeltaIndex`` (seconds from the first row), or a numeric index in seconds; a plain
            ``RangeIndex`` of row numbers is refused unless ``sample_rate`` (Hz) gives
            ``t = k / sample_rate``.
        units : mapping, optional
            Units keyed ``"u"``/``"y"``; by default taken from ``df.attrs["units"]`` when that maps the
            chosen column labels to strings.
        nominal_frequency, name, metadata
            As for :class:`Measurement`; by default from ``df.attrs["bouc_wen_id"]`` (what
            :meth:`to_dataframe` writes), else none.

        Raises
        ------
        InvalidParameterError
            Not a DataFrame, a missing or duplicated column, a non-numeric column, no time axis.
        NonFiniteError
            NaN/inf (or NaT) in a used column or the time axis.
        TimeAxisError
            Times that do not increase uniformly (to 1 %).
        """
        pd = _optional.require("pandas", "Measurement.from_dataframe")
        if not isinstance(df, pd.DataFrame):
            raise InvalidParameterError(f"df must be a pandas DataFrame, got {type(df).__name__}")
        saved: Mapping[str, Any] = df.attrs.get(FRAME_ATTR) or {}
        if not isinstance(saved, Mapping):
            saved = {}
        u = _frame_column(pd, df, input, "u")
        y = _frame_column(pd, df, output, "y")
        channels = {"u": str(input), "y": str(output)}
        t = _frame_time_axis(pd, df, time, sample_rate, (input, output))
        if time is not None:
            channels["t"] = str(time)
        if units is None:
            units = _frame_units(df, input, output)
        if nominal_frequency is None and isinstance(saved.get("nominal_frequency"), (int, float)):
            nominal_frequency = saved["nominal_frequency"]
        if name is None:
            name = saved["name"] if isinstance(saved.get("name"), str) else ""
        if metadata is None and isinstance(saved.get("metadata"), Mapping):
            metadata = saved["metadata"]
        if (input, output) == ("u", "y") and isinstance(saved.get("channels"), Mapping):
            channels = dict(saved["channels"])  # the frame came from to_dataframe: the original names
        return cls(
            t,
            u,
            y,
            nominal_frequency=nominal_frequency,
            units=units,
            channels=channels,
            name=name,
            metadata=metadata,
        )

    def to_dataframe(self) -> Any:
        """This measurement as a :class:`pandas.DataFrame` (needs pandas: the ``pandas`` extra).

        Columns ``u`` and ``y`` (copies, writeable), indexed by the times in seconds (index name ``t``);
        ``df.attrs["units"]`` maps ``u``/``y`` to their units and ``df.attrs["bouc_wen_id"]`` holds the
        name, nominal frequency, original channel names and metadata, so that
        :meth:`from_dataframe` reads it back as it was.
        """
        pd = _optional.require("pandas", "Measurement.to_dataframe")
        df = pd.DataFrame(
            {"u": np.array(self.u), "y": np.array(self.y)}, index=pd.Index(np.array(self.t), name="t")
        )
        df.attrs["units"] = {k: v for k, v in self.units.items() if k != "t"}
        df.attrs[FRAME_ATTR] = {
            "name": self.name,
            "nominal_frequency": self.nominal_frequency,
            "channels": dict(self.channels),
            "metadata": dict(self.metadata),
        }
        return df

    def __repr__(self) -> str:
        nominal = "" if self.nominal_frequency is None else f", nominal={self.nominal_frequency:g} rad/s"
        return (
            f"Measurement(name={self.name!r}, n={self.t.size}, rate={self.sample_rate:.6g} Hz, "
            f"duration={self.duration:.6g} s{nominal})"
        )


def check_sample_rate(sample_rate: object, where: str = "") -> float:
    """A sampling rate in Hz: a finite number > 0 (``where``, a file, prefixes the messages; the readers
    of :mod:`bouc_wen_id.io` check a stated rate with it too)."""
    at = f"{where}: " if where else ""
    if isinstance(sample_rate, bool):
        raise InvalidParameterError(f"{at}sample_rate must be a number (Hz), not a bool")
    try:
        rate = float(sample_rate)  # type: ignore[arg-type]
    except (TypeError, ValueError, OverflowError) as exc:
        raise InvalidParameterError(f"{at}sample_rate must be a number (Hz): {exc}") from exc
    if not math.isfinite(rate):
        raise NonFiniteError(f"{at}sample_rate = {rate} is not finite")
    if rate <= 0:
        raise InvalidParameterError(f"{at}sample_rate = {rate} Hz must be > 0")
    return rate


def _row_numbers(pd: Any, index: Any) -> bool:
    """An index of integers: row numbers (a RangeIndex, or what is left of one after filtering rows), which
    would silently read as a 1 Hz time axis."""
    return isinstance(index, pd.RangeIndex) or (
        pd.api.types.is_integer_dtype(index.dtype) and not isinstance(index, pd.MultiIndex)
    )


def _frame_time_axis(
    pd: Any, df: Any, time: Optional[Hashable], sample_rate: Optional[float], used: tuple[Hashable, Hashable]
) -> FloatArray:
    """The seconds of a frame's rows: its ``time`` column, ``k / sample_rate`` for row numbers, or its
    index of times (a plain index of row numbers without ``sample_rate`` is refused, not read as 1 Hz)."""
    if time is not None:
        if time in used:
            raise InvalidParameterError(f"time={time!r} is also the input or output column")
        t = _frame_times(pd, _frame_series(df, time, "t"), f"t (column {time!r})")
        if sample_rate is not None:
            raise InvalidParameterError("give time= or sample_rate=, not both")
        return _declared_seconds(t, time)
    if _row_numbers(pd, df.index) or sample_rate is not None:
        if sample_rate is None:
            raise InvalidParameterError(
                f"the frame's index holds integers (row numbers, a {type(df.index).__name__}), not "
                "times: pass time=<column>, sample_rate=<Hz>, or index the frame by time in seconds "
                "or datetimes (e.g. df.set_index('t'))"
            )
        if not _row_numbers(pd, df.index):
            raise InvalidParameterError(
                f"sample_rate= is for a frame indexed by row numbers; this one has a "
                f"{type(df.index).__name__} of times: drop sample_rate or reset the index"
            )
        return np.arange(len(df)) / check_sample_rate(sample_rate)
    if isinstance(df.index, pd.MultiIndex):
        raise InvalidParameterError("a MultiIndex is not a time axis: pass time=<column>")
    return _declared_seconds(_frame_times(pd, df.index.to_series(), "t (the index)"), df.index.name)


def _declared_seconds(t: FloatArray, label: object) -> FloatArray:
    """``t`` in seconds when its column's label declares another unit of time (``"t [ms]"``, ``"time_ms"``),
    with a :class:`UnitWarning`; as it is otherwise."""
    from ._timehint import label_unit, time_scale

    unit = label_unit(label)
    factor = time_scale(unit) if unit is not None else None
    if unit is None or factor is None or factor == 1.0:
        return t
    warnings.warn(
        f"read the time column {label!r} in {unit} as seconds (x {factor:g})", UnitWarning, stacklevel=4
    )
    return t * factor


def _frame_units(df: Any, input: Hashable, output: Hashable) -> dict[str, str]:
    """The units ``df.attrs["units"]`` states for the chosen columns (label -> unit string)."""
    stated = df.attrs.get("units")
    units: dict[str, str] = {}
    if isinstance(stated, Mapping):
        for role, col in (("u", input), ("y", output)):
            if isinstance(stated.get(col), str):
                units[role] = stated[col]
    return units


def _frame_series(df: Any, label: Hashable, role: str) -> Any:
    """The column ``label`` of ``df`` (one column, present)."""
    if label not in df.columns:
        shown = ", ".join(map(repr, list(df.columns)[:20]))
        raise InvalidParameterError(
            f"no column {label!r} for {role!r}; the frame has {shown or 'no columns'}"
        )
    col = df.loc[:, label]
    if col.ndim != 1:
        raise InvalidParameterError(f"column label {label!r} (for {role!r}) appears more than once")
    return col


def _frame_column(pd: Any, df: Any, label: Hashable, role: str) -> FloatArray:
    """A numeric column as float64 (a copy), missing values as NaN for the finiteness check."""
    col = _frame_series(df, label, role)
    what = f"{role} (column {label!r})"
    if pd.api.types.is_bool_dtype(col.dtype) or not pd.api.types.is_numeric_dtype(col.dtype):
        raise InvalidParameterError(f"{what} holds {col.dtype} values, not real numbers")
    if pd.api.types.is_complex_dtype(col.dtype):
        raise InvalidParameterError(f"{what} holds complex values, not real numbers")
    return _frozen(what, col.to_numpy(dtype=np.float64, na_value=np.nan, copy=True))


def _frame_times(pd: Any, values: Any, what: str) -> FloatArray:
    """Seconds from a numeric, datetime or timedelta series (the latter two from their first entry)."""
    dtype = values.dtype
    if pd.api.types.is_datetime64_any_dtype(dtype) or pd.api.types.is_timedelta64_dtype(dtype):
        if len(values) == 0:
            return _frozen(what, np.empty(0))
        if values.isna().any():
            bad = int(np.flatnonzero(values.isna().to_numpy())[0])
            raise NonFiniteError(f"{what} holds a missing time (NaT) at row {bad}; clean or drop it")
        seconds = (values - values.iloc[0]) / pd.Timedelta(seconds=1)
        return _frozen(what, seconds.to_numpy(dtype=np.float64, copy=True))
    if pd.api.types.is_bool_dtype(dtype) or not pd.api.types.is_numeric_dtype(dtype):
        raise InvalidParameterError(
            f"{what} holds {dtype} values: times must be numbers (s), datetimes or timedeltas"
        )
    return _frozen(what, values.to_numpy(dtype=np.float64, na_value=np.nan, copy=True))
