"""The header of an experiment (the CSV ``# key: value`` lines, the NPZ/MAT ``meta``, the TDMS/HDF5
``bouc_wen_id`` property) and the experiment it describes: a Recording or a Measurement."""

from __future__ import annotations

import json
import math
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any, Literal, Optional

import numpy as np

from .. import timeunits
from ..errors import BoucWenIdError, FileFormatError, InvalidParameterError
from ..measurement import RESERVED_KEYS, Measurement, check_metadata_key, check_sample_rate
from ..model import Recording, WienerPlant
from ..validation import check_time_axis
from ._common import FloatArray, Item, _array, _scalar_rate

FORMAT = "bouc_wen_id.recording"
MEASUREMENT_FORMAT = "bouc_wen_id.measurement"
VERSION = 1
#: Header keys of the recording format (every other key is metadata).
_RESERVED = {"format", "version", "amplitude", "frequency", "settle_periods", "plant", "sample_rate"}
#: Header keys whose values must be valid JSON (free-form keys fall back to the raw text).
_STRICT = (RESERVED_KEYS | _RESERVED) - {"name", "format"}
#: Relative disagreement allowed between a time column's rate and a stated sample rate.
_RATE_RTOL = 0.01


def _meta_str(v: Any) -> str:
    """Metadata values are strings; JSON values that are not are kept as their JSON text."""
    return v if isinstance(v, str) else json.dumps(v)


def _header(item: Item) -> dict[str, Any]:
    """The header of one experiment, as written to every format."""
    if isinstance(item, Recording):
        head: dict[str, Any] = {
            "format": FORMAT,
            "version": VERSION,
            "amplitude": item.amplitude,
            "frequency": item.frequency,
            "settle_periods": item.settle_periods,
        }
        if item.plant is not None:
            head["plant"] = item.plant.to_dict()
        for k, v in item.metadata.items():
            if k not in _RESERVED:
                head[k] = str(v)
        return head
    if isinstance(item, Measurement):
        head = {"format": MEASUREMENT_FORMAT, "version": VERSION, "name": item.name}
        if item.nominal_frequency is not None:
            head["nominal_frequency"] = item.nominal_frequency
        head["units"] = dict(item.units)
        if item.channels:
            head["channels"] = dict(item.channels)
        head.update(item.metadata)
        return head
    raise InvalidParameterError(f"expected Recording or Measurement objects, got {type(item).__name__}")


def _number(head: Mapping[str, Any], key: str, where: str) -> Optional[float]:
    """A JSON number (null: absent)."""
    v = head.get(key)
    if v is None:
        return None
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise FileFormatError(f"{where}: header {key!r} must be a number, got {json.dumps(v)[:80]}")
    try:
        return float(v)
    except OverflowError as exc:
        raise FileFormatError(f"{where}: header {key!r} is out of range ({exc})") from exc


def _str_dict(head: Mapping[str, Any], key: str, where: str) -> Optional[dict[str, str]]:
    v = head.get(key)
    if v is None:
        return None
    if not isinstance(v, dict) or not all(isinstance(x, str) for x in v.values()):
        raise FileFormatError(
            f'{where}: header {key!r} must be a JSON object of strings, e.g. {{"u": "mm", "y": "N"}}; '
            f"got {json.dumps(v)[:80]}"
        )
    return dict(v)


def _kind(head: Mapping[str, Any], where: str) -> Literal["recording", "measurement"]:
    fmt = head.get("format")
    version = head.get("version", VERSION)
    if (
        isinstance(version, bool)
        or not isinstance(version, (int, float))
        or (isinstance(version, float) and not version.is_integer())
    ):
        raise FileFormatError(f"{where}: header 'version' must be an integer, got {json.dumps(version)[:80]}")
    if version > VERSION:
        raise FileFormatError(f"{where}: version {version} is newer than this library reads ({VERSION})")
    if fmt == FORMAT:
        return "recording"
    if fmt == MEASUREMENT_FORMAT:
        return "measurement"
    if fmt is not None:
        raise FileFormatError(f"{where}: format {fmt!r} is neither {FORMAT!r} nor {MEASUREMENT_FORMAT!r}")
    has = [k for k in ("amplitude", "frequency") if k in head]
    if len(has) == 1:
        missing = "frequency" if has[0] == "amplitude" else "amplitude"
        raise FileFormatError(
            f"{where}: the header has {has[0]!r} but no {missing!r}; a recording states both (the known "
            "input U cos(omega t), omega in rad/s); for lab data without them use 'nominal_frequency'"
        )
    return "recording" if has else "measurement"


@contextmanager
def _in_file(where: str) -> Iterator[None]:
    """Name the file in the library's data errors (same class, the file prefixed to the message)."""
    try:
        yield
    except FileFormatError:
        raise
    except BoucWenIdError as exc:
        if str(exc).startswith(where):
            raise
        new = type(exc)(f"{where}: {exc}")
        new.__dict__.update(exc.__dict__)
        raise new from exc


def _build(
    head: Mapping[str, Any],
    arrays: Mapping[str, FloatArray],
    where: str,
    *,
    default_name: str,
    sample_rate: Optional[float] = None,
    sources: Optional[Mapping[str, str]] = None,
) -> Item:
    """One experiment from its header and arrays (``sources``: the original names of renamed columns)."""
    if not isinstance(head, Mapping):
        raise FileFormatError(f"{where}: the header must be a JSON object, got {type(head).__name__}")
    kind = _kind(head, where)
    for key in ("u", "y"):
        if key not in arrays:
            have = ", ".join(sorted(arrays)) or "none"
            raise FileFormatError(
                f"{where}: no {key!r} data (found: {have}); name the columns t,u,y or map yours with "
                "columns={'u': ..., 'y': ...}"
            )
    lengths = {k: int(v.size) for k, v in arrays.items()}
    if len(set(lengths.values())) != 1:
        raise FileFormatError(f"{where}: the signals have unequal lengths {lengths}")
    n = lengths["u"]
    if n == 0:
        raise FileFormatError(f"{where}: the file holds no samples")
    stated = _number(head, "sample_rate", where)
    with _in_file(where):
        rate = None if stated is None else check_sample_rate(stated, where)
        if sample_rate is not None and rate is not None and abs(sample_rate - rate) > 1e-9 * rate:
            raise FileFormatError(
                f"{where}: the header's sample_rate {rate:g} Hz disagrees with sample_rate={sample_rate:g}"
            )
        rate = sample_rate if rate is None else rate
        if "t" in arrays:
            t, head = timeunits.declared(head, arrays["t"], where)
            if rate is not None and n >= 2:
                dt = check_time_axis(t)
                if abs(1.0 / dt - rate) > _RATE_RTOL * rate:
                    timeunits.check_rate(where, rate, dt)
                    raise FileFormatError(
                        f"{where}: the t column is sampled at {1.0 / dt:.6g} Hz, not at the stated sample "
                        f"rate {rate:.6g} Hz"
                    )
        elif rate is not None:
            with np.errstate(over="ignore"):  # a rate so low that t overflows is a NonFiniteError
                t = np.arange(n) / rate
        else:
            raise FileFormatError(
                f"{where}: no time column 't' and no sample rate; add a t column, a '# sample_rate: <Hz>' "
                "header line, or pass sample_rate="
            )
        if kind == "recording":
            return _build_recording(head, arrays, t, where)
        return _build_measurement(head, arrays, t, where, default_name, sources or {})


def _build_recording(
    head: Mapping[str, Any], arrays: Mapping[str, FloatArray], t: FloatArray, where: str
) -> Recording:
    amplitude = _number(head, "amplitude", where)
    frequency = _number(head, "frequency", where)
    for key, v in (("amplitude", amplitude), ("frequency", frequency)):
        if v is None:
            raise FileFormatError(f"{where}: the header has no {key!r} (the known input U cos(omega t))")
    settle = head.get("settle_periods", 0)
    if isinstance(settle, bool) or not isinstance(settle, (int, float)) or not math.isfinite(settle):
        raise FileFormatError(
            f"{where}: header 'settle_periods' must be a whole number, got {json.dumps(settle)[:80]}"
        )
    plant = head.get("plant")
    plant_obj = None
    if plant is not None:
        try:
            plant_obj = WienerPlant.from_dict(plant)
        except BoucWenIdError:
            raise
        except (KeyError, TypeError, ValueError, AttributeError, OverflowError) as exc:
            raise FileFormatError(
                f"{where}: header 'plant' is not a WienerPlant.to_dict() object ({type(exc).__name__}: {exc})"
            ) from exc
    assert amplitude is not None and frequency is not None
    return Recording(
        t=t,
        u=arrays["u"],
        y=arrays["y"],
        amplitude=amplitude,
        frequency=frequency,
        settle_periods=settle,  # type: ignore[arg-type]  # Recording checks that it is a whole number
        x=arrays.get("x"),
        w=arrays.get("w"),
        plant=plant_obj,
        metadata={k: _meta_str(v) for k, v in head.items() if k not in _RESERVED},
    )


def _build_measurement(
    head: Mapping[str, Any],
    arrays: Mapping[str, FloatArray],
    t: FloatArray,
    where: str,
    default_name: str,
    sources: Mapping[str, str],
) -> Measurement:
    nominal = _number(head, "nominal_frequency", where)
    hz = _number(head, "nominal_frequency_hz", where)
    if hz is not None:
        from_hz = 2.0 * math.pi * hz
        if nominal is not None and not abs(nominal - from_hz) <= 1e-9 * abs(nominal):
            raise FileFormatError(
                f"{where}: nominal_frequency {nominal:.12g} rad/s and nominal_frequency_hz {hz:.12g} Hz "
                "disagree"
            )
        nominal = from_hz if nominal is None else nominal
    units = _str_dict(head, "units", where)
    channels = _str_dict(head, "channels", where)
    if channels is None:
        channels = {k: v for k, v in sources.items() if k in ("t", "u", "y")}
    name = head["name"] if "name" in head else default_name
    return Measurement(
        t,
        arrays["u"],
        arrays["y"],
        nominal_frequency=nominal,
        units=units,
        channels=channels,
        name=_meta_str(name),
        metadata={k: _meta_str(v) for k, v in head.items() if k not in RESERVED_KEYS},
    )


def _check_header_keys(head: Mapping[str, Any]) -> None:
    for k in head:
        check_metadata_key(k)


def _read_single(
    contents: Mapping[str, Any],
    names: Sequence[str],
    picked: Mapping[str, int],
    head: Mapping[str, Any],
    where: str,
    stem: str,
    rate: Optional[float],
) -> Item:
    arrays = {role: _array(where, names[j], contents[names[j]]) for role, j in picked.items()}
    sources = {role: names[j] for role, j in picked.items() if names[j] != role}
    if "t" not in arrays and rate is None:
        for key in ("sample_rate", "fs"):
            if key in contents and key not in {names[j] for j in picked.values()}:
                rate = _scalar_rate(where, key, contents[key])
                break
    return _build(head, arrays, where, default_name=stem, sample_rate=rate, sources=sources)
