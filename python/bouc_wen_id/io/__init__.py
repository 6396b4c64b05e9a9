"""Reading and writing experiments: :class:`Recording` (U, omega known) and :class:`Measurement` (lab data).

Three file formats, each holding either kind, documented in the README:

* **CSV** (``.csv``), one experiment per file: ``# key: value`` header lines whose values are JSON, then a
  line of column names and one row per sample.  Columns are found by name (``t``, ``u``, ``y``; ``x``, ``w``
  for simulated recordings; any order, other columns ignored) or through ``columns={"u": "disp_mm", ...}``
  (names, or 0-based indices for a file without a line of names).  Without a ``t`` column the time axis is
  ``t = k / sample_rate`` from a ``# sample_rate: <Hz>`` header line or the ``sample_rate=`` argument.
* **NPZ** (``.npz``), a bundle: arrays ``t_<i>``, ``u_<i>``, ``y_<i>`` (``x_<i>``, ``w_<i>``) and ``meta``, a
  JSON string holding the list of per-experiment headers (the CSV header as a JSON object).  A plain
  archive with arrays ``u``, ``y`` (``t``, or a scalar ``fs``/``sample_rate``) and an optional ``meta`` JSON
  object reads as one experiment.
* **TDMS** (``.tdms``, NI, extra ``tdms``) and **HDF5** (``.h5``, ``.hdf5``, extra ``hdf5``): one
  experiment per group holding the ``u`` and ``y`` channels (datasets), found by name or through
  ``columns`` (see :func:`read_tdms`, :func:`read_hdf5`); the sampling rate from the channels' attributes
  (``wf_increment``, ``sample_rate``, ...), a ``t`` channel or ``sample_rate=``.
* **MAT** (``.mat``, MATLAB v5/v7 via :func:`scipy.io.loadmat`): variables ``t``, ``u``, ``y`` (or a scalar
  ``fs``/``sample_rate`` instead of ``t``) and ``meta``, a JSON string; or a bundle, a variable
  ``experiments`` holding a struct array (or a cell array of structs) with the same fields.

The header decides the kind: ``format: "bouc_wen_id.recording"``, or ``amplitude`` and ``frequency`` without
a format, make a :class:`Recording`; ``format: "bouc_wen_id.measurement"``, or neither key, a
:class:`Measurement`.  Every malformed file raises :class:`FileFormatError` naming the file and the fault;
data problems inside a well-formed file keep their own names (``NonFiniteError``, ``TimeAxisError``, ...)
with the file name prefixed to the message.

Results are written as JSON (``IdentificationResult.to_json``).
"""

from __future__ import annotations

import io as _stdio
import json
import math
import os
import re
import struct
import zlib
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial
from pathlib import Path
from typing import Any, Literal, Optional, Union

import numpy as np
from numpy.typing import NDArray

from .. import _optional
from .. import budget as _budget
from ..errors import BoucWenIdError, FileFormatError, InvalidParameterError, NonFiniteError
from ..measurement import RESERVED_KEYS, Measurement, check_metadata_key
from ..model import Recording, WienerPlant
from ..validation import check_time_axis

__all__ = [
    "Item",
    "load",
    "save",
    "load_recordings",
    "save_recordings",
    "read_csv",
    "write_csv",
    "read_npz",
    "write_npz",
    "read_mat",
    "write_mat",
    "read_tdms",
    "write_tdms",
    "read_hdf5",
    "write_hdf5",
    "FORMAT",
    "MEASUREMENT_FORMAT",
    "VERSION",
    "SUFFIXES",
]

PathLike = Union[str, "os.PathLike[str]"]
#: What the loaders return: a recording (U and omega known) or a raw lab measurement.
Item = Union[Recording, Measurement]
#: ``columns=``: signal name (``t``, ``u``, ``y``, ``x``, ``w``) -> column name, or 0-based column index.
ColumnMap = Mapping[str, Union[str, int]]
FloatArray = NDArray[np.float64]

FORMAT = "bouc_wen_id.recording"
MEASUREMENT_FORMAT = "bouc_wen_id.measurement"
VERSION = 1
#: File suffixes the loaders read (case-insensitive); folders are scanned for these.
SUFFIXES = (".csv", ".npz", ".mat", ".tdms", ".h5", ".hdf5")
#: Header keys of the recording format (every other key is metadata).
_RESERVED = {"format", "version", "amplitude", "frequency", "settle_periods", "plant", "sample_rate"}
#: Signals a file can hold, in column order.
_ROLES = ("t", "u", "y", "x", "w")
#: Header keys whose values must be valid JSON (free-form keys fall back to the raw text).
_STRICT = (RESERVED_KEYS | _RESERVED) - {"name", "format"}
#: Relative disagreement allowed between a time column's rate and a stated sample rate.
_RATE_RTOL = 0.01


# --------------------------------------------------------------------------------------------------
# Headers
# --------------------------------------------------------------------------------------------------


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


def _rate_value(value: Any, where: str = "") -> float:
    at = f"{where}: " if where else ""
    try:
        rate = float(value)
    except OverflowError as exc:
        raise InvalidParameterError(f"{at}sample_rate = {value} Hz is out of range") from exc
    if not math.isfinite(rate):
        raise NonFiniteError(f"{at}sample_rate = {rate} is not finite")
    if rate <= 0:
        raise InvalidParameterError(f"{at}sample_rate = {rate} Hz must be > 0")
    return rate


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
        rate = None if stated is None else _rate_value(stated, where)
        if sample_rate is not None and rate is not None and abs(sample_rate - rate) > 1e-9 * rate:
            raise FileFormatError(
                f"{where}: the header's sample_rate {rate:g} Hz disagrees with sample_rate={sample_rate:g}"
            )
        rate = sample_rate if rate is None else rate
        if "t" in arrays:
            t = arrays["t"]
            if rate is not None and n >= 2:
                dt = check_time_axis(t)
                if abs(1.0 / dt - rate) > _RATE_RTOL * rate:
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


# --------------------------------------------------------------------------------------------------
# Arguments
# --------------------------------------------------------------------------------------------------


def _check_columns(columns: Optional[ColumnMap]) -> dict[str, Union[str, int]]:
    out: dict[str, Union[str, int]] = {}
    for role, col in (columns or {}).items():
        if role not in _ROLES:
            raise InvalidParameterError(f"columns keys are signal names {', '.join(_ROLES)}; got {role!r}")
        if isinstance(col, bool) or not isinstance(col, (str, int)) or (isinstance(col, int) and col < 0):
            raise InvalidParameterError(
                f"columns[{role!r}] must be a column name or a 0-based column index, got {col!r}"
            )
        out[role] = col
    return out


def _check_rate(sample_rate: Optional[float]) -> Optional[float]:
    if sample_rate is None:
        return None
    if isinstance(sample_rate, bool) or not isinstance(sample_rate, (int, float, np.integer, np.floating)):
        raise InvalidParameterError(f"sample_rate must be a number (Hz), got {sample_rate!r}")
    return _rate_value(sample_rate)


def _pick(
    names: Sequence[str], columns: Mapping[str, Union[str, int]], where: str, what: str = "column"
) -> dict[str, int]:
    """Role -> index into ``names`` for every role present (mapped, or found under its own name)."""
    picked: dict[str, int] = {}
    for role in _ROLES:
        col = columns.get(role, role)
        if isinstance(col, int) and what != "column":
            raise FileFormatError(
                f"{where}: columns[{role!r}] = {col}: column indices apply to CSV files; name the {what}"
            )
        if isinstance(col, int):
            if col >= len(names):
                raise FileFormatError(
                    f"{where}: columns[{role!r}] = {col} but the file has {len(names)} {what}s"
                )
            picked[role] = col
        elif col in names:
            picked[role] = names.index(col)
        elif role in columns:
            raise FileFormatError(
                f"{where}: no {what} {col!r} (for {role!r}); the file has {', '.join(map(repr, names))}"
            )
    seen: dict[int, str] = {}
    for role, i in picked.items():
        if i in seen:
            raise InvalidParameterError(f"{where}: {seen[i]!r} and {role!r} both read {what} {names[i]!r}")
        seen[i] = role
    return picked


def _array(where: str, key: str, value: Any) -> FloatArray:
    """A numeric vector from a container (NPZ entry, MAT variable): 1-D, or a row or column."""
    arr = np.asarray(value)
    if arr.dtype.kind not in "fiu":
        raise FileFormatError(f"{where}: {key!r} holds {arr.dtype} values, not real numbers")
    if arr.ndim == 2 and 1 in arr.shape:
        arr = arr.reshape(-1)
    elif arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != 1:
        raise FileFormatError(f"{where}: {key!r} must be a vector, got shape {arr.shape}")
    return np.asarray(arr, dtype=np.float64)


def _scalar_rate(where: str, key: str, value: Any) -> float:
    arr = _array(where, key, value)
    if arr.size != 1:
        raise FileFormatError(f"{where}: {key!r} must be one number (the sample rate in Hz), got {arr.size}")
    return _rate_value(arr[0], where)


def _parse_json(text: str, where: str, what: str) -> Any:
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise FileFormatError(f"{where}: {what} is not valid JSON ({exc})") from exc


# --------------------------------------------------------------------------------------------------
# CSV
# --------------------------------------------------------------------------------------------------


def _check_header_keys(head: Mapping[str, Any]) -> None:
    for k in head:
        check_metadata_key(k)


def write_csv(path: PathLike, item: Item, *, sample_rate: Optional[float] = None) -> None:
    """Write one recording or measurement as CSV: ``# key: value`` header lines, then columns.

    ``t,u,y`` (``x,w`` too for a simulated recording), with 17 significant digits (exact for doubles).
    With ``sample_rate`` (Hz) the ``t`` column is left out and a ``# sample_rate:`` header line written
    instead; the time axis must then be ``t = k / sample_rate``.
    """
    head = _header(item)
    _check_header_keys(head)
    cols = ["t", "u", "y"]
    if isinstance(item, Recording):
        cols += [c for c in ("x", "w") if getattr(item, c) is not None]
    if sample_rate is not None:
        rate = _check_rate(sample_rate)
        assert rate is not None
        with np.errstate(over="ignore", invalid="ignore"):
            expected = np.arange(item.t.size) / rate
            off = float(np.max(np.abs(item.t - expected)))
        if not off <= 1e-9 / rate:
            raise InvalidParameterError(
                f"the time axis is not t = k / {rate:g}: write it with its t column (sample_rate=None)"
            )
        head["sample_rate"] = rate
        cols = cols[1:]
    data = np.column_stack([getattr(item, c) for c in cols])
    with open(path, "w", encoding="utf-8", newline="\n") as fh:
        for k, v in head.items():
            fh.write(f"# {k}: {json.dumps(v)}\n")
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, data, delimiter=",", fmt="%.17g")


#: Memory a parsed CSV takes per byte of text (the text, its lines, the parsed table): the file size cap
#: is ``max_bytes / CSV_MEMORY_FACTOR``.
CSV_MEMORY_FACTOR = 8


def _regular_file(path: Path, what: str, memory_factor: int = 1) -> int:
    """The size of ``path`` after checking it is a regular file within the byte budget.

    A FIFO would block forever and a device (``/dev/zero`` behind a ``.csv`` symlink) never ends: only
    regular files are read, and only up to ``max_bytes / memory_factor`` bytes.
    """
    import stat

    try:
        st = os.stat(path)  # follows symlinks: the target is what would be read
    except OSError as exc:
        raise FileFormatError(f"{path}: cannot be read ({exc})") from exc
    if not stat.S_ISREG(st.st_mode):
        kind = (
            "a FIFO"
            if stat.S_ISFIFO(st.st_mode)
            else "a device"
            if stat.S_ISCHR(st.st_mode) or stat.S_ISBLK(st.st_mode)
            else "a folder"
            if stat.S_ISDIR(st.st_mode)
            else "not a regular file"
        )
        raise FileFormatError(f"{path}: is {kind}, not a regular {what} file; only regular files are read")
    limit = _budget.get_budget().max_bytes // memory_factor
    if st.st_size > limit:
        _budget.check_bytes(
            f"reading {path} ({st.st_size} bytes, about {memory_factor}x that in memory)",
            st.st_size * memory_factor,
        )
    return int(st.st_size)


def _read_text(path: Path) -> str:
    size = _regular_file(path, "CSV", CSV_MEMORY_FACTOR)
    try:
        with open(path, "rb") as fh:
            # Never more than the size checked: a file that grows while read is cut at its checked size.
            raw = fh.read(size)
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{path}: not a UTF-8 text file ({exc})") from exc
    except OSError as exc:
        raise FileFormatError(f"{path}: cannot be read ({exc})") from exc


def _split(line: str, delimiter: Optional[str]) -> list[str]:
    return [c.strip() for c in (line.split(delimiter) if delimiter else line.split())]


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _diagnose(rows: Sequence[tuple[int, str]], delimiter: Optional[str], width: int, where: str) -> str:
    """Where a block of data rows that numpy refused goes wrong, by file line."""
    for lineno, line in rows:
        cells = _split(line, delimiter)
        if len(cells) != width:
            return f"{where}: line {lineno} has {len(cells)} fields, the first data row {width} (ragged rows)"
        for j, cell in enumerate(cells):
            if not _is_number(cell) or "_" in cell:
                return f"{where}: line {lineno}, field {j + 1}: {cell[:40]!r} is not a number"
    return f"{where}: the data rows are not numeric CSV"


def read_csv(
    path: PathLike, *, columns: Optional[ColumnMap] = None, sample_rate: Optional[float] = None
) -> Item:
    """Read one experiment from a CSV file (a :class:`Recording` or a :class:`Measurement`, by its header).

    Parameters
    ----------
    path : path
        The file.
    columns : mapping, optional
        Signal name (``"t"``, ``"u"``, ``"y"``, ``"x"``, ``"w"``) -> column name, or 0-based column index
        (needed when the file has no line of column names).  Unmapped signals are looked up under their
        own names; other columns are ignored.
    sample_rate : float, optional
        Sampling rate (Hz) of a file without a ``t`` column (``t = k / sample_rate``).  Also accepted from
        a ``# sample_rate:`` header line; a ``t`` column must agree with it to 1 %.
    """
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    p = Path(path)
    where = str(p)
    lines = [line.rstrip("\r") for line in _read_text(p).split("\n")]
    _budget.check_samples(f"{where}: the CSV rows", len(lines))
    if not any(line.strip() for line in lines):
        raise FileFormatError(f"{where}: the file is empty")
    head: dict[str, Any] = {}
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        line = lines[i]
        i += 1
        if not line.strip():
            continue
        key, sep, value = line[1:].partition(":")
        key = key.strip()
        if not sep or not key:
            raise FileFormatError(f"{where}: header line {i} {line.strip()[:60]!r} is not '# key: value'")
        if key in head:
            raise FileFormatError(f"{where}: header key {key!r} appears twice (line {i})")
        try:
            head[key] = json.loads(value)
        except (ValueError, RecursionError) as exc:
            if key in _STRICT:
                raise FileFormatError(
                    f"{where}: header line {i}: the value of {key!r} is not valid JSON ({exc})"
                ) from exc
            head[key] = value.strip()
    if i == len(lines):
        raise FileFormatError(f"{where}: no column names and no data after the header")
    first = lines[i]
    delimiter = next((d for d in (",", ";", "\t") if d in first), None)
    cells = _split(first, delimiter)
    if all(_is_number(c) for c in cells):
        names: Optional[list[str]] = None
        start = i
    else:
        names = [c.strip("\"'").strip() for c in cells]
        start = i + 1
        for j, nm in enumerate(names):
            if not nm:
                raise FileFormatError(f"{where}: column {j + 1} of the column-name line {i + 1} has no name")
        dup = sorted({nm for nm in names if names.count(nm) > 1})
        if dup:
            raise FileFormatError(f"{where}: column names {dup} appear more than once")
    rows = [
        (k + 1, lines[k])
        for k in range(start, len(lines))
        if lines[k].strip() and not lines[k].startswith("#")
    ]
    if not rows:
        raise FileFormatError(f"{where}: no data rows after the column names")
    width = len(_split(rows[0][1], delimiter))
    try:
        data = np.loadtxt([r for _, r in rows], delimiter=delimiter, ndmin=2, dtype=np.float64, comments=None)
    except (ValueError, TypeError, OverflowError) as exc:
        raise FileFormatError(_diagnose(rows, delimiter, width, where) + f" ({exc})") from exc
    if names is None:
        if not any(isinstance(c, int) for c in cols.values()):
            raise FileFormatError(
                f"{where}: the file has no line of column names; name them (e.g. 't,u,y') or pass "
                "columns={'u': <index>, 'y': <index>} with 0-based column indices"
            )
        names = [f"column {j}" for j in range(data.shape[1])]
    if data.shape[1] != len(names):
        raise FileFormatError(f"{where}: {len(names)} column names but {data.shape[1]} columns of data")
    picked = _pick(names, cols, where)
    arrays = {role: np.ascontiguousarray(data[:, j]) for role, j in picked.items()}
    sources = {role: names[j] for role, j in picked.items() if names[j] != role}
    return _build(head, arrays, where, default_name=p.stem, sample_rate=rate, sources=sources)


# --------------------------------------------------------------------------------------------------
# NPZ
# --------------------------------------------------------------------------------------------------


def write_npz(path: PathLike, items: Sequence[Item]) -> None:
    """Write several experiments (recordings and measurements, mixed) into one compressed NPZ bundle."""
    if not items:
        raise InvalidParameterError("nothing to write: no experiments")
    arrays: dict[str, np.ndarray] = {}
    meta = []
    for i, item in enumerate(items):
        meta.append(_header(item))
        for c in _ROLES:
            v = getattr(item, c, None)
            if v is not None:
                arrays[f"{c}_{i}"] = np.asarray(v)
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez_compressed(path, **arrays)  # type: ignore[arg-type]


_INDEXED = re.compile(r"^([a-z]+)_(\d+)$")


def read_npz(
    path: PathLike, *, columns: Optional[ColumnMap] = None, sample_rate: Optional[float] = None
) -> list[Item]:
    """Read every experiment of an NPZ file: a bundle written by :func:`write_npz`, or a plain archive
    with arrays ``u``, ``y`` and ``t`` (or a scalar ``fs``/``sample_rate``), renamed by ``columns``."""
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    p = Path(path)
    where = str(p)
    _regular_file(p, "NPZ")
    try:
        # Our own handle: numpy leaks the one it opens when the archive is corrupt.
        with open(p, "rb") as fh:
            z = np.load(fh, allow_pickle=False)
            if not isinstance(z, np.lib.npyio.NpzFile):
                raise FileFormatError(f"{where}: holds a single .npy array, not an NPZ archive")
            with z:
                _guard_npz(z, where)
                contents = {k: z[k] for k in z.files}
    except BoucWenIdError:
        raise
    except Exception as exc:  # noqa: BLE001 - any decoder failure of an untrusted file is a format error
        raise FileFormatError(f"{where}: not a readable NPZ archive ({type(exc).__name__}: {exc})") from exc
    if "meta" in contents:
        meta_arr = contents["meta"]
        if meta_arr.dtype.kind != "U" or meta_arr.size != 1:
            raise FileFormatError(
                f"{where}: 'meta' must be one JSON string, got {meta_arr.dtype} {meta_arr.shape}"
            )
        meta = _parse_json(str(meta_arr.reshape(())), where, "'meta'")
    else:
        meta = None
    if isinstance(meta, list):
        return _read_bundle(contents, meta, where, p.stem, rate)
    if meta is not None and not isinstance(meta, dict):
        raise FileFormatError(
            f"{where}: 'meta' must hold a JSON list (bundle) or object, not {type(meta).__name__}"
        )
    names = [k for k in contents if k != "meta"]
    picked = _pick(names, cols, where, what="array")
    if "u" not in picked or "y" not in picked:
        raise FileFormatError(
            f"{where}: no 'meta' entry (not a bouc_wen_id bundle) and no arrays 'u' and 'y' "
            f"(arrays: {', '.join(sorted(names)) or 'none'})"
        )
    return [_read_single(contents, names, picked, meta or {}, where, p.stem, rate)]


def _guard_npz(z: Any, where: str) -> None:
    """Refuse an archive whose arrays would inflate beyond ``max_bytes``, before inflating any.

    Both what the zip directory declares (the inflater stops there) and what each ``.npy`` header
    declares (numpy allocates that before reading) are summed.
    """
    declared = 0
    allocated = 0
    for info in z.zip.infolist():
        declared += info.file_size
        if not info.filename.endswith(".npy"):
            continue
        with z.zip.open(info) as member:
            version = np.lib.format.read_magic(member)
            if version == (1, 0):
                shape, _, dtype = np.lib.format.read_array_header_1_0(member)
            else:
                shape, _, dtype = np.lib.format.read_array_header_2_0(member)
        count = math.prod(int(n) for n in shape)
        _budget.check_samples(f"{where}: array {info.filename[:-4]!r}", count)
        allocated += count * int(dtype.itemsize)
    _budget.check_bytes(f"{where}: the arrays of the NPZ archive", max(declared, allocated))


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


def _read_bundle(
    contents: Mapping[str, Any], meta: list[Any], where: str, stem: str, rate: Optional[float]
) -> list[Item]:
    if not meta:
        raise FileFormatError(f"{where}: the bundle's 'meta' lists no experiments")
    for key in contents:
        m = _INDEXED.match(key)
        if m and m.group(1) in _ROLES and int(m.group(2)) >= len(meta):
            raise FileFormatError(f"{where}: array {key!r} has no entry in 'meta' ({len(meta)} experiments)")
    out: list[Item] = []
    for i, head in enumerate(meta):
        at = f"{where}[{i}]"
        arrays = {c: _array(at, f"{c}_{i}", contents[f"{c}_{i}"]) for c in _ROLES if f"{c}_{i}" in contents}
        out.append(_build(head, arrays, at, default_name=f"{stem}[{i}]", sample_rate=rate))
    return out


# --------------------------------------------------------------------------------------------------
# MAT
# --------------------------------------------------------------------------------------------------


def _scipy_io() -> Any:
    """scipy.io, imported on first use (it is slow to import and only the MAT format needs it)."""
    import scipy.io  # type: ignore[import-untyped]

    return scipy.io


def _mat_fields(item: Item) -> dict[str, Any]:
    fields: dict[str, Any] = {
        c: np.asarray(getattr(item, c)) for c in _ROLES if getattr(item, c, None) is not None
    }
    fields["meta"] = json.dumps(_header(item))
    return fields


def write_mat(path: PathLike, items: Sequence[Item], *, bundle: Optional[bool] = None) -> None:
    """Write experiments to a MATLAB (v5, compressed) file.

    One experiment (unless ``bundle=True``): variables ``t``, ``u``, ``y`` (``x``, ``w``) and ``meta``, its
    header as a JSON string.  Several (or ``bundle=True``): a variable ``experiments``, a 1 x n struct array
    with those fields (a cell array of structs when the experiments' fields differ).
    """
    savemat = _scipy_io().savemat

    items = list(items)
    if not items:
        raise InvalidParameterError("nothing to write: no experiments")
    fields = [_mat_fields(item) for item in items]
    if len(items) == 1 and not bundle:
        variables: dict[str, Any] = fields[0]
    else:
        keys = list(fields[0])
        if all(list(f) == keys for f in fields):
            arr = np.zeros((1, len(fields)), dtype=[(k, object) for k in keys])
            for i, f in enumerate(fields):
                for k in keys:
                    arr[0, i][k] = f[k]
        else:
            arr = np.empty((1, len(fields)), dtype=object)
            for i, f in enumerate(fields):
                arr[0, i] = f
        variables = {"experiments": arr}
    savemat(path, variables, do_compression=True, oned_as="column")


#: Data-type codes scipy's MAT v5 reader has a dtype for; any other code on a numeric or char element makes
#: it dereference a NULL or wild pointer (a segfault: scipy/scipy#25349, unfixed in scipy 1.17).
_MAT_DTYPE_CODES = frozenset({1, 2, 3, 4, 5, 6, 7, 9, 12, 13, 16, 17, 18})
_MAT_MATRIX, _MAT_COMPRESSED = 14, 15
_MAT_CELL, _MAT_STRUCT, _MAT_CHAR = 1, 2, 4
_MAT_NUMERIC_CLASSES = range(6, 16)
#: Largest nesting of cells and structs read, and largest inflated size of one compressed variable.
_MAT_MAX_DEPTH = 32
_MAT_MAX_INFLATED = 1 << 31


class _Mat5Walk:
    """Walks one MAT v5 variable the way scipy's reader will read it, refusing what would crash it.

    scipy reads the elements of a matrix sequentially by class (it does not honour the byte counts of
    nested matrices), so the walk follows the same order: a matrix tag, the array-flags element, the
    dimensions, the name, then per class the numeric parts, the char data, the cells or the struct's
    field names and fields.  Only the classes this library reads (numeric, char, cell, struct) are
    allowed in the variables it loads.
    """

    def __init__(self, buf: bytes, order: str, where: str) -> None:
        self.buf, self.order, self.where, self.pos = buf, order, where, 0

    def fail(self, what: str) -> FileFormatError:
        return FileFormatError(f"{self.where}: not a readable MAT file ({what})")

    def pair(self) -> tuple[int, int]:
        if self.pos + 8 > len(self.buf):
            raise self.fail("truncated")
        a, b = struct.unpack_from(self.order + "II", self.buf, self.pos)
        self.pos += 8
        return int(a), int(b)

    def element(self) -> tuple[int, bytes]:
        """One data element (full or small format): its type code and data."""
        start = self.pos
        word, count = self.pair()
        if word >> 16:  # small data element: the data sit in the tag
            if word >> 16 > 4:
                raise self.fail("bad small data element")
            return word & 0xFFFF, self.buf[start + 4 : start + 4 + (word >> 16)]
        if self.pos + count > len(self.buf):
            raise self.fail("truncated element")
        data = self.buf[self.pos : self.pos + count]
        self.pos += count + (-count % 8)
        return word, data

    def int32s(self, limit: int) -> list[int]:
        code, data = self.element()
        if code not in (5, 6) or len(data) > limit:
            raise self.fail("bad dimensions")
        return list(struct.unpack_from(f"{self.order}{len(data) // 4}i", data))

    def header(self) -> tuple[int, bool, list[int], str]:
        """After a matrix tag: array flags, dimensions and name (class, complex, dims, name)."""
        self.pair()  # the array-flags tag, not checked by scipy
        flags, _ = self.pair()
        mclass, is_complex = flags & 0xFF, bool(flags >> 11 & 1)
        dims = [] if mclass == 17 else self.int32s(128)
        code, name = self.element()
        if code not in (1, 16) or len(dims) > 32:
            raise self.fail("bad array name or dimensions")
        return mclass, is_complex, dims, name.decode("latin1")

    def matrix(self, depth: int) -> None:
        """A nested matrix (a cell or a struct field)."""
        code, count = self.pair()
        if code != _MAT_MATRIX:
            raise self.fail(f"element type {code} where a matrix is expected")
        if count:
            mclass, is_complex, dims, _ = self.header()
            self.array(mclass, is_complex, dims, depth + 1)

    def count(self, dims: list[int], per_item: int) -> int:
        n = 1
        for d in dims:
            if d < 0:
                raise self.fail("negative dimension")
            n *= d
        # Every cell or field is a matrix of at least 8 bytes; a struct without fields reads nothing per
        # element, but scipy still loops over them.
        if n * per_item * 8 > len(self.buf) - self.pos or (per_item == 0 and n > 10**6):
            raise self.fail("more elements than the data can hold")
        return n

    def array(self, mclass: int, is_complex: bool, dims: list[int], depth: int) -> None:
        if depth > _MAT_MAX_DEPTH:
            raise self.fail("cells or structs nested too deep")
        if len(dims) < 2:  # MATLAB arrays have 2 or more; scipy's char conversion crashes on 0
            raise self.fail(f"an array with {len(dims)} dimensions")
        if mclass in _MAT_NUMERIC_CLASSES or mclass == _MAT_CHAR:
            for _ in range(2 if is_complex and mclass != _MAT_CHAR else 1):
                code, data = self.element()
                # scipy looks the code up even for no data, except in char arrays.
                if (data or mclass != _MAT_CHAR) and code not in _MAT_DTYPE_CODES:
                    raise self.fail(f"unknown data type code {code}")
        elif mclass == _MAT_CELL:
            for _ in range(self.count(dims, 1)):
                self.matrix(depth)
        elif mclass == _MAT_STRUCT:
            (length,) = self.int32s(4) or [0]
            code, names = self.element()
            if code not in (1, 16) or length <= 0:
                raise self.fail("bad struct field names")
            fields = len(names) // length
            for _ in range(self.count(dims, fields) * fields):
                self.matrix(depth)
        else:
            raise self.fail(f"MATLAB class {mclass} (objects, sparse, function handles) is not supported")


def _guard_mat5(data: bytes, wanted: set[str], where: str) -> None:
    """Refuse a MAT v5 file whose variables in ``wanted`` would crash scipy's reader; leave every other
    fault (and v4 and v7.3 files) to scipy, which raises on them."""
    if len(data) < 128 or 0 in data[:4]:
        return
    version = data[124:128]
    if version[int(version[2] == ord("I"))] != 1:
        return
    order = "<" if data[126:128] == b"IM" else ">"
    pos = 128
    inflated_total = 0
    while pos < len(data):
        top = _Mat5Walk(data, order, where)
        top.pos = pos
        code, count = top.pair()
        if count == 0:
            return  # scipy refuses it
        pos = top.pos + count
        if code == _MAT_COMPRESSED:
            inflater = zlib.decompressobj()
            try:
                limit = min(_MAT_MAX_INFLATED, _budget.get_budget().max_bytes - inflated_total)
                inflated = inflater.decompress(data[top.pos : pos], max(limit, 0) + 1)
            except zlib.error as exc:
                raise top.fail(f"corrupt compressed variable: {exc}") from exc
            if inflater.unconsumed_tail or len(inflated) > limit:
                if limit < _MAT_MAX_INFLATED:
                    _budget.check_bytes(
                        f"{where}: the compressed variables of the MAT file", inflated_total + len(inflated)
                    )
                raise top.fail("a compressed variable inflates beyond 2 GiB")
            inflated_total += len(inflated)
            # At least one byte per element (8 for the float64 signals): an upper bound of the samples.
            _budget.check_samples(f"{where}: a compressed variable of the MAT file", len(inflated) // 8)
            walk = _Mat5Walk(inflated, order, where)
            code, count = walk.pair()
        else:
            walk = top
        if code != _MAT_MATRIX:
            return  # scipy refuses it
        if count == 0:
            continue
        mclass, is_complex, dims, name = walk.header()
        if name in wanted:
            walk.array(mclass, is_complex, dims, 0)


def _mat_meta(value: Any, where: str) -> dict[str, Any]:
    if isinstance(value, np.ndarray) and value.size == 0:
        return {}
    if not isinstance(value, str):
        raise FileFormatError(f"{where}: 'meta' must be a JSON string (a char row vector)")
    head = _parse_json(value, where, "'meta'")
    if not isinstance(head, dict):
        raise FileFormatError(f"{where}: 'meta' must hold a JSON object, not {type(head).__name__}")
    return head


def read_mat(
    path: PathLike, *, columns: Optional[ColumnMap] = None, sample_rate: Optional[float] = None
) -> list[Item]:
    """Read the experiments of a MATLAB v5/v7 file: one (variables ``u``, ``y``, ``t`` or ``fs``/
    ``sample_rate``, ``meta``; renamed by ``columns``) or a bundle (``experiments``: struct array or cell
    array of structs with those fields)."""
    loadmat = _scipy_io().loadmat

    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    p = Path(path)
    where = str(p)
    wanted = {"t", "u", "y", "x", "w", "fs", "sample_rate", "meta", "experiments"}
    wanted |= {c for c in cols.values() if isinstance(c, str)}
    _regular_file(p, "MAT")
    try:
        data = p.read_bytes()
    except OSError as exc:
        raise FileFormatError(f"{where}: cannot be read ({exc})") from exc
    _guard_mat5(data, wanted, where)
    try:
        raw = loadmat(_stdio.BytesIO(data), simplify_cells=True, variable_names=sorted(wanted))
    except NotImplementedError as exc:
        raise FileFormatError(
            f"{where}: MATLAB v7.3 (HDF5) files are not supported; save with -v7 ({exc})"
        ) from exc
    except Exception as exc:  # noqa: BLE001 - any decoder failure of an untrusted file is a format error
        raise FileFormatError(f"{where}: not a readable MAT file ({type(exc).__name__}: {exc})") from exc
    variables = {k: v for k, v in raw.items() if not k.startswith("__")}
    if "experiments" in variables:
        exps = variables["experiments"]
        if isinstance(exps, dict):
            exps = [exps]
        elif isinstance(exps, np.ndarray) and exps.dtype == object:
            exps = exps.ravel().tolist()
        if not isinstance(exps, (list, tuple)) or not exps:
            raise FileFormatError(
                f"{where}: 'experiments' must be a non-empty struct array or cell array of structs"
            )
        out: list[Item] = []
        for i, exp in enumerate(exps):
            at = f"{where}[{i}]"
            if not isinstance(exp, dict):
                raise FileFormatError(f"{at}: experiment {i} is a {type(exp).__name__}, not a struct")
            out.append(_read_mat_struct(exp, {}, at, f"{p.stem}[{i}]", rate))
        return out
    if "u" not in variables and "u" not in cols:
        raise FileFormatError(
            f"{where}: no variables 'u' and 'y' and no 'experiments' struct array "
            f"(variables: {', '.join(sorted(variables)) or 'none'})"
        )
    return [_read_mat_struct(variables, cols, where, p.stem, rate)]


def _read_mat_struct(
    fields: Mapping[str, Any],
    cols: Mapping[str, Union[str, int]],
    where: str,
    stem: str,
    rate: Optional[float],
) -> Item:
    head = _mat_meta(fields["meta"], where) if "meta" in fields else {}
    names = [k for k in fields if k != "meta"]
    picked = _pick(names, cols, where, what="variable")
    # Empty fields of a struct array stand for absent signals (e.g. x, w of one recording among several).
    present = {
        role: j
        for role, j in picked.items()
        if not (isinstance(fields[names[j]], np.ndarray) and fields[names[j]].size == 0)
    }
    return _read_single(fields, names, present, head, where, stem, rate)


# --------------------------------------------------------------------------------------------------
# Lab containers: NI TDMS and HDF5 (optional extras ``tdms`` and ``hdf5``, imported on first use)
# --------------------------------------------------------------------------------------------------

#: Group property (TDMS) or attribute (HDF5) holding an experiment's header as JSON (what :func:`write_tdms`
#: and :func:`write_hdf5` write); a group without it is read as lab data.
HEADER_KEY = "bouc_wen_id"
#: Channel, group or file attributes that state the sampling rate in Hz ...
RATE_ATTRS = ("sample_rate", "sampling_rate", "fs")
#: ... or the sampling step in s (``wf_increment``: the step of an NI waveform channel).
STEP_ATTRS = ("wf_increment", "dt")
#: Channel attributes holding the channel's unit (``unit_string``: NI's).
UNIT_ATTRS = ("unit_string", "units", "unit")
#: Lab group properties that may set a header key (the others among RESERVED_KEYS would change the kind
#: of experiment or clash with what the file states elsewhere, so they are left out).
_LAB_HEADER_KEYS = ("nominal_frequency", "nominal_frequency_hz")
#: HDF5 groups nested deeper than this are not searched (hard links can make cycles).
_HDF5_MAX_DEPTH = 8
#: Relative disagreement allowed between two stated sampling rates (they are copies of one number).
_STATED_RTOL = 1e-9


@dataclass(frozen=True)
class _Channel:
    """One channel of a lab container, read only when needed."""

    name: str
    #: ``group/channel`` (TDMS) or the dataset's path without its leading ``/`` (HDF5).
    path: str
    size: int
    props: Mapping[str, Any]
    read: Callable[[], Any]


@dataclass(frozen=True)
class _Group:
    """A TDMS group or an HDF5 group (``path`` '' for the HDF5 root) and its channels by name."""

    path: str
    props: Mapping[str, Any]
    channels: Mapping[str, _Channel]


def _plain(value: Any) -> Any:
    """A property value as a Python scalar (bytes decoded, one-element arrays unwrapped); None if it is
    not a string, number or time stamp."""
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(())[()]  # a numpy scalar (datetime64 kept as such)
    if isinstance(value, np.generic) and value.dtype.kind != "M":
        value = value.item()
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.datetime64):
        return str(value)
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        return value
    return None


def _stated_rate(props: Mapping[str, Any], where: str, what: str) -> Optional[float]:
    """The sampling rate (Hz) that ``props`` state, if any."""
    for keys, is_step in ((RATE_ATTRS, False), (STEP_ATTRS, True)):
        for key in keys:
            if key not in props:
                continue
            v = _plain(props[key])
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise FileFormatError(
                    f"{where}: {what} attribute {key!r} = {props[key] if v is None else v!r} is not a "
                    "positive "
                    f"{'step (s)' if is_step else 'rate (Hz)'}"
                )
            return 1.0 / float(v) if is_step else float(v)
    return None


def _file_rate(
    picked: Mapping[str, _Channel], chain: Sequence[tuple[str, Mapping[str, Any]]], where: str
) -> Optional[float]:
    """The rate the channels state (they must agree), else the first their group or the file states."""
    rates = {}
    for role, ch in picked.items():
        if role != "t":
            r = _stated_rate(ch.props, where, f"{ch.path!r}:")
            if r is not None:
                rates[ch.path] = r
    if rates:
        lo, hi = min(rates.values()), max(rates.values())
        if hi - lo > _STATED_RTOL * hi:
            shown = ", ".join(f"{k} {v:.9g} Hz" for k, v in rates.items())
            raise FileFormatError(f"{where}: the channels are sampled at different rates ({shown})")
        return hi
    for what, props in chain:
        r = _stated_rate(props, where, what)
        if r is not None:
            return r
    return None


def _group_header(group: _Group, picked: Mapping[str, _Channel], where: str) -> dict[str, Any]:
    """The header this library wrote (HEADER_KEY), or one made of a lab group's properties and units."""
    if HEADER_KEY in group.props:
        text = _plain(group.props[HEADER_KEY])
        if not isinstance(text, str):
            raise FileFormatError(f"{where}: property {HEADER_KEY!r} must be a JSON string")
        head = _parse_json(text, where, f"property {HEADER_KEY!r}")
        if not isinstance(head, dict):
            raise FileFormatError(
                f"{where}: property {HEADER_KEY!r} must hold a JSON object, not {type(head).__name__}"
            )
        return head
    head = {}
    for key, raw in group.props.items():
        value = _plain(raw)
        if value is None or (key in RESERVED_KEYS and key not in _LAB_HEADER_KEYS):
            continue
        if key in STEP_ATTRS or key in RATE_ATTRS:
            continue
        try:
            check_metadata_key(key)
        except InvalidParameterError:
            continue  # a property name no header line can carry: not kept
        head[key] = value
    units = {}
    for role in ("u", "y"):
        ch = picked.get(role)
        unit = next((_plain(ch.props[k]) for k in UNIT_ATTRS if ch and k in ch.props), None)
        if isinstance(unit, str) and unit:
            units[role] = unit
    if units:
        head["units"] = units
    start = picked["u"].props.get("wf_start_time") if "u" in picked else None
    if start is not None and _plain(start) is not None and "start_time" not in head:
        head["start_time"] = str(_plain(start))
    return head


def _container_item(
    group: _Group,
    picked: Mapping[str, _Channel],
    chain: Sequence[tuple[str, Mapping[str, Any]]],
    where: str,
    default_name: str,
    rate: Optional[float],
    what: str,
) -> Item:
    """One experiment from the channels ``picked`` (role -> channel), sizes checked before reading."""
    for ch in picked.values():
        _budget.check_samples(f"{where}: {what} {ch.path!r}", ch.size)
    _budget.check_bytes(f"{where}: the signals", 8 * sum(ch.size for ch in picked.values()))
    arrays = {}
    for role, ch in picked.items():
        try:
            raw = ch.read()
        except BoucWenIdError:
            raise
        except Exception as exc:  # noqa: BLE001 - any decoder failure of an untrusted file is a format error
            raise FileFormatError(
                f"{where}: {what} {ch.path!r} cannot be read ({type(exc).__name__}: {exc})"
            ) from exc
        arrays[role] = _array(where, ch.path, raw)
    head = _group_header(group, picked, where)
    stated = _file_rate(picked, [(f"group {group.path!r}:", group.props), *chain], where)
    if stated is not None and head.get("sample_rate") is None:
        head["sample_rate"] = stated
    if "t" not in arrays and head.get("sample_rate") is None and rate is None:
        raise FileFormatError(
            f"{where}: no sample rate: no time {what} 't' and no attribute "
            f"{', '.join(map(repr, RATE_ATTRS + STEP_ATTRS))} on the channels, their group or the file; "
            f"map a time {what} with columns={{'t': ...}} or pass sample_rate= (Hz)"
        )
    sources = {role: ch.name for role, ch in picked.items() if ch.name != role}
    return _build(head, arrays, where, default_name=default_name, sample_rate=rate, sources=sources)


def _container_items(
    groups: Sequence[_Group],
    root: Mapping[str, Any],
    cols: Mapping[str, Union[str, int]],
    where: str,
    stem: str,
    rate: Optional[float],
    what: str,
) -> list[Item]:
    """The experiments of a TDMS or HDF5 file: one per group holding the ``u`` and ``y`` channels (their
    own names or those ``cols`` maps), or the one that ``cols`` pins with ``group/channel`` paths."""
    for role, col in cols.items():
        if isinstance(col, int):
            raise FileFormatError(
                f"{where}: columns[{role!r}] = {col}: column indices apply to CSV files; name the {what} "
                f"(or 'group/{what}')"
            )
    listing = "; ".join(
        f"{g.path or '/'}: {', '.join(map(repr, g.channels)) or 'no ' + what + 's'}" for g in groups
    )
    chain = [("the file's", root)]
    by_path = {ch.path: (g, ch) for g in groups for ch in g.channels.values()}
    # A "/" pins a group, unless the whole name is a channel's (e.g. a channel called "Force/kN").
    names_anywhere = {name for g in groups for name in g.channels}
    pinned = {
        role: str(col).strip("/")
        for role, col in cols.items()
        if "/" in str(col) and str(col) not in names_anywhere
    }
    if pinned:
        chosen = {}
        for role, path in pinned.items():
            if path not in by_path:
                raise FileFormatError(f"{where}: no {what} {path!r} (for {role!r}); the file has {listing}")
            chosen[role] = by_path[path]
        home = (chosen["u"] if "u" in chosen else next(iter(chosen.values())))[0]
        at = f"{where}, group {home.path!r}" if home.path else where
        rest = {role: col for role, col in cols.items() if role not in pinned}
        names = list(home.channels)
        picked = {role: home.channels[names[j]] for role, j in _pick(names, rest, at, what).items()}
        picked = {r: c for r, c in picked.items() if c.path not in pinned.values()}
        picked.update({role: ch for role, (_, ch) in chosen.items()})
        return [_container_item(home, picked, chain, at, home.path.split("/")[-1] or stem, rate, what)]
    out: list[Item] = []
    for g in groups:
        names = list(g.channels)
        if not any(cols.get(role, role) in g.channels for role in ("u", "y")):
            continue  # a group of other channels (settings, temperatures, ...)
        at = f"{where}, group {g.path!r}" if g.path else where
        for role in ("u", "y"):
            if cols.get(role, role) not in g.channels:
                raise FileFormatError(
                    f"{at}: no {what} {cols.get(role, role)!r} (for {role!r}); the group has "
                    f"{', '.join(map(repr, names))}; map yours with columns={{{role!r}: ...}}"
                )
        picked = {role: g.channels[names[j]] for role, j in _pick(names, cols, at, what).items()}
        out.append(_container_item(g, picked, chain, at, g.path.split("/")[-1] or stem, rate, what))
    if not out:
        u, y = cols.get("u", "u"), cols.get("y", "y")
        raise FileFormatError(
            f"{where}: no group holds the {what}s {u!r} (u) and {y!r} (y); the file has "
            f"{listing or 'nothing'}; "
            f"map yours with columns={{'u': ..., 'y': ...}} ({what} names, or 'group/{what}' paths)"
        )
    return out


class _LogRecords:
    """Collects the warnings a library logs (npTDMS reports truncated files only through its logger)."""

    def __init__(self, name: str) -> None:
        import logging

        self.messages: list[str] = []
        records = self.messages

        class Handler(logging.Handler):
            def emit(self, record: logging.LogRecord) -> None:
                records.append(record.getMessage())

        self._logger = logging.getLogger(name)
        self._handler = Handler(logging.WARNING)

    def __enter__(self) -> list[str]:
        self._logger.addHandler(self._handler)
        return self.messages

    def __exit__(self, *exc: object) -> None:
        self._logger.removeHandler(self._handler)


def read_tdms(
    path: PathLike, *, columns: Optional[ColumnMap] = None, sample_rate: Optional[float] = None
) -> list[Item]:
    """Read the experiments of an NI TDMS file (needs the ``tdms`` extra: npTDMS).

    Every group holding the channels ``u`` and ``y`` (their own names, or those ``columns`` maps, e.g.
    ``{"u": "Displacement", "y": "Force"}``) is one experiment, named after the group; groups holding
    neither are skipped.  A ``"group/channel"`` path in ``columns`` reads that one experiment.  The time
    axis is the ``t`` channel when there is one, else ``t = k / rate`` with the rate from the channels'
    ``wf_increment`` (NI waveforms; ``dt``, ``sample_rate``, ``sampling_rate`` or ``fs`` also read, on the
    channels, their group or the file) or ``sample_rate=``.  Units come from the channels'
    ``unit_string``; ``wf_start_time`` and the group's scalar properties go into the metadata.  A group
    written by :func:`write_tdms` carries its header (property ``bouc_wen_id``) and reads back as written.
    """
    nptdms = _optional.require("nptdms", "reading .tdms files")
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    p = Path(path)
    where = str(p)
    _regular_file(p, "TDMS")
    with _LogRecords("nptdms") as logged, open(p, "rb") as fh:
        try:
            tdms = nptdms.TdmsFile.open(fh)
        except Exception as exc:  # noqa: BLE001 - any decoder failure of an untrusted file is a format error
            raise FileFormatError(f"{where}: not a readable TDMS file ({type(exc).__name__}: {exc})") from exc

        def truncated() -> FileFormatError:
            return FileFormatError(f"{where}: the TDMS file is truncated or corrupt (npTDMS: {logged[0]})")

        with tdms:
            if logged:
                raise truncated()
            groups = [
                _Group(
                    g.name,
                    dict(g.properties),
                    {
                        c.name: _Channel(
                            c.name, f"{g.name}/{c.name}", len(c), dict(c.properties), partial(_read_all, c)
                        )
                        for c in g.channels()
                    },
                )
                for g in tdms.groups()
            ]
            try:
                items = _container_items(groups, dict(tdms.properties), cols, where, p.stem, rate, "channel")
            except BoucWenIdError as exc:
                if logged:
                    raise truncated() from exc
                raise
            if logged:
                raise truncated()
    return items


def _read_all(channel: Any) -> Any:
    return channel[:]


def write_tdms(path: PathLike, items: Sequence[Item]) -> None:
    """Write experiments to an NI TDMS file (needs the ``tdms`` extra): one group ``exp_<i>`` each, with
    float64 channels ``t``, ``u``, ``y`` (``x``, ``w``), their ``wf_increment`` and ``unit_string``, and
    the header as the group property ``bouc_wen_id`` (JSON)."""
    nptdms = _optional.require("nptdms", "writing .tdms files")
    seq = _items(items)
    objects: list[Any] = [nptdms.RootObject({})]
    for i, item in enumerate(seq):
        group = f"exp_{i:03d}"
        objects.append(nptdms.GroupObject(group, {HEADER_KEY: json.dumps(_header(item))}))
        units = item.units if isinstance(item, Measurement) else {}
        step = float(np.median(np.diff(item.t))) if item.t.size > 1 else None
        for role in _ROLES:
            data = getattr(item, role, None)
            if data is None:
                continue
            props: dict[str, Any] = {}
            if role == "t":
                props["unit_string"] = "s"
            else:
                if step is not None:
                    props["wf_increment"] = step
                    props["wf_start_offset"] = float(item.t[0])
                if role in units:
                    props["unit_string"] = units[role]
            objects.append(nptdms.ChannelObject(group, role, np.asarray(data, dtype=np.float64), props))
    with nptdms.TdmsWriter(str(path)) as writer:
        writer.write_segment(objects)


def _hdf5_groups(h5py: Any, root: Any, where: str) -> list[_Group]:
    """The root and every group below it (hard links only, to a bounded depth), with their datasets."""
    out: list[_Group] = []

    def visit(group: Any, prefix: str, depth: int) -> None:
        channels: dict[str, _Channel] = {}
        subgroups = []
        for name in group:
            link = group.get(name, getlink=True)
            if not isinstance(link, h5py.HardLink):
                continue  # soft and external links could point anywhere (another file)
            obj = group[name]
            if isinstance(obj, h5py.Dataset):
                size = int(obj.size) if obj.shape is not None else 0
                channels[name] = _Channel(
                    name, prefix + name, size, dict(obj.attrs), _hdf5_reader(obj, where)
                )
            elif isinstance(obj, h5py.Group) and depth < _HDF5_MAX_DEPTH:
                subgroups.append((obj, prefix + name + "/"))
        out.append(_Group(prefix.rstrip("/"), dict(group.attrs), channels))
        for obj, sub in subgroups:
            visit(obj, sub, depth + 1)

    visit(root, "", 0)
    return out


def _hdf5_reader(dataset: Any, where: str) -> Callable[[], Any]:
    def read() -> Any:
        if dataset.dtype.kind not in "fiu":  # refuse before reading strings or compound records
            raise FileFormatError(
                f"{where}: dataset {dataset.name.lstrip('/')!r} holds {dataset.dtype} values, not real "
                "numbers"
            )
        return dataset[()]

    return read


def read_hdf5(
    path: PathLike, *, columns: Optional[ColumnMap] = None, sample_rate: Optional[float] = None
) -> list[Item]:
    """Read the experiments of an HDF5 file (needs the ``hdf5`` extra: h5py).

    Every group (the root included) holding the datasets ``u`` and ``y`` (their own names, or those
    ``columns`` maps) is one experiment, named after the group; a ``"group/dataset"`` path in ``columns``
    reads that one experiment.  The time axis is the ``t`` dataset when there is one, else
    ``t = k / rate`` with the rate from an attribute of the datasets, their group or the file:
    ``sample_rate``, ``sampling_rate`` or ``fs`` (Hz), ``dt`` or ``wf_increment`` (s); or from
    ``sample_rate=``.  Units come from the datasets' ``units`` (or ``unit``, ``unit_string``) attribute and
    the group's scalar attributes go into the metadata.  Datasets must be numeric vectors (or 1-row/column
    matrices); soft and external links are not followed.  A group written by :func:`write_hdf5` carries
    its header (attribute ``bouc_wen_id``) and reads back as written.
    """
    h5py = _optional.require("h5py", "reading .h5/.hdf5 files")
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    p = Path(path)
    where = str(p)
    _regular_file(p, "HDF5")
    try:
        h5 = h5py.File(p, "r", locking=False)
    except Exception as exc:  # noqa: BLE001 - any decoder failure of an untrusted file is a format error
        raise FileFormatError(f"{where}: not a readable HDF5 file ({type(exc).__name__}: {exc})") from exc
    with h5:
        try:
            groups = _hdf5_groups(h5py, h5, where)
        except BoucWenIdError:
            raise
        except Exception as exc:  # noqa: BLE001
            raise FileFormatError(f"{where}: a corrupt HDF5 file ({type(exc).__name__}: {exc})") from exc
        root = groups[0].props
        return _container_items(groups, root, cols, where, p.stem, rate, "dataset")


def write_hdf5(path: PathLike, items: Sequence[Item]) -> None:
    """Write experiments to an HDF5 file (needs the ``hdf5`` extra): one group ``exp_<i>`` each, with
    float64 datasets ``t``, ``u``, ``y`` (``x``, ``w``), a ``units`` attribute on each, and the header as
    the group attribute ``bouc_wen_id`` (JSON)."""
    h5py = _optional.require("h5py", "writing .h5/.hdf5 files")
    seq = _items(items)
    with h5py.File(path, "w") as h5:
        for i, item in enumerate(seq):
            group = h5.create_group(f"exp_{i:03d}")
            group.attrs[HEADER_KEY] = json.dumps(_header(item))
            units = item.units if isinstance(item, Measurement) else {"t": "s"}
            for role in _ROLES:
                data = getattr(item, role, None)
                if data is None:
                    continue
                ds = group.create_dataset(role, data=np.asarray(data, dtype=np.float64))
                if role in units:
                    ds.attrs["units"] = units[role]


def _items(items: Sequence[Item]) -> list[Item]:
    seq = list(items)
    if not seq:
        raise InvalidParameterError("nothing to write: no experiments")
    for item in seq:
        if not isinstance(item, (Recording, Measurement)):
            raise InvalidParameterError(
                f"expected Recording or Measurement objects, got {type(item).__name__}"
            )
    return seq


# --------------------------------------------------------------------------------------------------
# Files and folders
# --------------------------------------------------------------------------------------------------


def _read_file(p: Path, cols: Optional[ColumnMap], rate: Optional[float]) -> list[Item]:
    suffix = p.suffix.lower()
    if suffix == ".csv":
        return [read_csv(p, columns=cols, sample_rate=rate)]
    if suffix == ".npz":
        return read_npz(p, columns=cols, sample_rate=rate)
    if suffix == ".mat":
        return read_mat(p, columns=cols, sample_rate=rate)
    if suffix == ".tdms":
        return read_tdms(p, columns=cols, sample_rate=rate)
    if suffix in (".h5", ".hdf5"):
        return read_hdf5(p, columns=cols, sample_rate=rate)
    raise FileFormatError(
        f"{p}: unknown recording format {p.suffix!r} (expected .csv, .npz, .mat, .tdms, .h5 or .hdf5)"
    )


def _files(paths: PathLike | Iterable[PathLike]) -> list[Path]:
    items = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    out: list[Path] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            files = sorted(
                f
                for f in p.iterdir()
                if f.is_file() and f.suffix.lower() in SUFFIXES and not f.name.startswith(".")
            )
            if not files:
                raise FileFormatError(
                    f"{p}: the folder holds no .csv or .npz recordings (nor .mat, .tdms, .h5 or .hdf5 files)"
                )
            out.extend(files)
        elif not p.exists():
            raise FileFormatError(f"{p}: no such file or folder")
        else:
            out.append(p)
    return out


def load(
    paths: PathLike | Iterable[PathLike],
    *,
    columns: Optional[ColumnMap] = None,
    sample_rate: Optional[float] = None,
) -> list[Item]:
    """Load experiments from files (``.csv``, ``.npz``, ``.mat``; ``.tdms``, ``.h5``, ``.hdf5`` with the
    ``tdms``/``hdf5`` extras) and folders of such files (sorted by name).

    Each experiment is a :class:`Recording` when its header states the input's ``amplitude`` and
    ``frequency`` (or ``format: "bouc_wen_id.recording"``), a :class:`Measurement` otherwise.
    ``columns`` and ``sample_rate`` apply to every file (see :func:`read_csv`; in TDMS and HDF5 files
    ``columns`` names channels or datasets, or pins ``"group/channel"`` paths: see :func:`read_tdms`).

    Raises
    ------
    FileFormatError
        A missing file, an unknown suffix, or a malformed file (named, with what is wrong).
    """
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    out: list[Item] = []
    for f in _files(paths):
        out.extend(_read_file(f, cols, rate))
    return out


def load_recordings(
    paths: PathLike | Iterable[PathLike],
    *,
    columns: Optional[ColumnMap] = None,
    sample_rate: Optional[float] = None,
) -> list[Recording]:
    """Load recordings (experiments with known U and omega) as :func:`load` does; refuse measurements."""
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    out: list[Recording] = []
    for f in _files(paths):
        for item in _read_file(f, cols, rate):
            if not isinstance(item, Recording):
                raise FileFormatError(
                    f"{f}: holds a measurement (no 'amplitude' and 'frequency' in its header), not a "
                    "recording; read lab data with bouc_wen_id.io.load"
                )
            out.append(item)
    return out


def save(
    path: PathLike,
    items: Item | Sequence[Item],
    *,
    fmt: Literal["csv", "npz", "mat"] = "csv",
) -> list[Path]:
    """Save experiments; return the files written.

    ``*.npz``: one bundle.  ``*.mat``: one MAT file (one experiment as plain variables, several as a
    struct array).  ``*.tdms``, ``*.h5``, ``*.hdf5``: one file, a group per experiment (needs the ``tdms``
    or ``hdf5`` extra).  ``*.csv``: one experiment.  Anything else is a folder (created if needed) of
    ``exp_000.<fmt>``, ``exp_001.<fmt>``, ... (``fmt``: ``"csv"``, ``"npz"`` or ``"mat"``).
    """
    seq: list[Item] = [items] if isinstance(items, (Recording, Measurement)) else list(items)
    if not seq:
        raise InvalidParameterError("nothing to save: no experiments")
    for item in seq:
        if not isinstance(item, (Recording, Measurement)):
            raise InvalidParameterError(
                f"expected Recording or Measurement objects, got {type(item).__name__}"
            )
    if fmt not in ("csv", "npz", "mat"):
        raise InvalidParameterError(f"fmt must be 'csv', 'npz' or 'mat', got {fmt!r}")
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".npz":
        write_npz(p, seq)
        return [p]
    if suffix == ".mat":
        write_mat(p, seq)
        return [p]
    if suffix == ".tdms":
        write_tdms(p, seq)
        return [p]
    if suffix in (".h5", ".hdf5"):
        write_hdf5(p, seq)
        return [p]
    if suffix == ".csv":
        if len(seq) != 1:
            raise InvalidParameterError(
                f"a .csv file holds one experiment, got {len(seq)}: save to a folder, .npz or .mat"
            )
        write_csv(p, seq[0])
        return [p]
    p.mkdir(parents=True, exist_ok=True)
    written = []
    for i, item in enumerate(seq):
        f = p / f"exp_{i:03d}.{fmt}"
        if fmt == "csv":
            write_csv(f, item)
        elif fmt == "npz":
            write_npz(f, [item])
        else:
            write_mat(f, [item])
        written.append(f)
    return written


def save_recordings(path: PathLike, recordings: Sequence[Recording]) -> list[Path]:
    """Save recordings: ``*.npz`` gives one bundle, ``*.mat`` one MAT file, anything else a folder of
    ``exp_<i>.csv`` files (see :func:`save`)."""
    return save(path, list(recordings))
