"""Delimited text as a lab's software writes it: the lines before the columns, the column layout, the rows.

A DAQ export (e.g. ``Sampling Rate:  1000`` ... then ``Sample Number, Date/Time, CHANNEL0, CHANNEL1,
Events``) starts with ``Key: value`` lines that are neither this library's ``# key: value`` header nor the
column names.  They are found as the lines before the line of names that precedes the first row of numbers,
or skipped with ``skiprows=``; a stated sampling rate or interval among them sets the time axis, a stated
sample count is checked against the rows, the rest is kept as metadata.  Text columns (a date, an event
log) are allowed beside the numeric ones and are read only when a signal is mapped to them; an ``Events``
column that marks ``DAQ Pause`` / ``DAQ Resume`` splits the file into one experiment per acquisition block.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Optional, Union

from .._timehint import time_scale
from ..errors import FileFormatError, InvalidParameterError
from ..measurement import RESERVED_KEYS, check_metadata_key
from ._header import _RESERVED

#: Preamble keys (lower case, single spaces) stating the sampling rate in Hz ...
_PREAMBLE_RATE_KEYS = ("sampling rate", "sample rate", "sampling frequency", "sample_rate", "fs")
#: ... or the sampling interval in s.
_PREAMBLE_STEP_KEYS = ("sampling interval", "sample interval", "sampling period", "dt")
#: Preamble keys stating how many rows of samples follow.
_PREAMBLE_COUNT_KEYS = ("sample count", "number of samples")
#: Units a stated rate (Hz) or interval (s) may carry after its number, as factors to Hz or s; any other
#: unit is refused rather than read as if it were Hz or s ("1 ms" is not 1 s).
_RATE_UNITS = {"": 1.0, "hz": 1.0, "1/s": 1.0, "s/s": 1.0, "sps": 1.0, "khz": 1e3, "ks/s": 1e3, "mhz": 1e6}
_STEP_UNITS = {"": 1.0, "s": 1.0, "sec": 1.0, "seconds": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "ns": 1e-9}
#: Relative disagreement allowed between a stated rate and a stated interval (copies of one number).
_PREAMBLE_RTOL = 1e-6
#: Column names (lower case, units removed) read as a signal when no column has the signal's own name.
_ROLE_WORDS = {
    "t": ("time",),
    "u": ("displacement", "disp", "position", "stroke", "input"),
    "y": ("force", "load", "output"),
}
#: Names of a text column whose cells mark the acquisition's pauses (one experiment per block).
_EVENT_COLUMNS = ("events", "event", "markers", "marker")
_UNIT = re.compile(r"^(.*?)\s*[\(\[]([^\)\]]+)[\)\]]\s*$")
#: A unit written as the name's last ``_``-part (``force_N``, ``disp_mm``, ``time_s``): read only when that
#: part is a unit symbol, an SI prefix and a unit (case as written: ``mN`` is not ``MN``) or an imperial one,
#: so that ``u_raw`` or ``force_2`` stay names (review 32: lab names like ``force_N`` carried no unit).
_SUFFIX = re.compile(r"^(.+?)_([A-Za-zµ]+)$")
_SI_UNITS = ("s", "m", "g", "N", "Pa", "V", "A", "W", "J", "Hz", "rad", "K")
_SI_PREFIXES = ("", "p", "n", "u", "µ", "m", "c", "k", "M", "G")
_SUFFIX_UNITS = frozenset(p + u for u in _SI_UNITS for p in _SI_PREFIXES) | {
    "deg",
    "in",
    "ft",
    "lb",
    "lbf",
    "kip",
    "psi",
}


def check_skiprows(skiprows: Optional[int]) -> Optional[int]:
    if skiprows is None:
        return None
    if isinstance(skiprows, bool) or not isinstance(skiprows, int) or skiprows < 0:
        raise InvalidParameterError(f"skiprows must be a whole number >= 0 (lines to skip), got {skiprows!r}")
    return skiprows


def split(line: str, delimiter: Optional[str]) -> list[str]:
    return [c.strip() for c in (line.split(delimiter) if delimiter else line.split())]


def is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def delimiter_of(line: str) -> Optional[str]:
    return next((d for d in (",", ";", "\t") if d in line), None)


def _looks_like_data(line: str, delimiter: Optional[str]) -> bool:
    """A row of samples: most of its fields are numbers (a ``Key: 7`` line has one number in two)."""
    cells = [c for c in split(line, delimiter) if c]
    numbers = sum(is_number(c) for c in cells)
    return numbers >= 1 and 2 * numbers > len(cells)


def holds_numbers(path: Path, limit: int = 1 << 16) -> bool:
    """Whether a text file's first ``limit`` bytes hold a row of numbers (notes in a data folder do not)."""
    try:
        with open(path, "rb") as fh:
            raw = fh.read(limit)
    except OSError:
        return True  # let the reader name the fault
    lines = raw.decode("utf-8", "replace").splitlines()
    if len(raw) == limit:
        lines = lines[:-1]  # cut in the middle
    return any(
        line.strip() and not line.startswith("#") and _looks_like_data(line, delimiter_of(line))
        for line in lines
    )


def _key_value(line: str) -> Optional[tuple[str, str]]:
    """``Key: value``, ``Key = value`` or ``Key<TAB>value``; None for any other line."""
    for sep in (":", "=", "\t"):
        key, found, value = line.partition(sep)
        if found and key.strip() and not is_number(key.strip()):
            return key.strip(), value.strip()
    return None


@dataclass
class Preamble:
    """What the lines before the columns state: a sampling rate (Hz), a sample count, other keys."""

    rate: Optional[float]
    count: Optional[int]
    metadata: dict[str, str]


def find_preamble(
    lines: Sequence[str], start: int, skiprows: Optional[int], where: str
) -> tuple[list[tuple[int, str]], int]:
    """The preamble lines (file line number, text) from ``start`` and where the columns begin.

    With ``skiprows`` those lines (counted from the top of the file) are the preamble, whatever they hold.
    Otherwise the preamble is what lies between ``start`` and the line of column names that precedes the
    first row of numbers; each of its lines must then read as ``Key: value``.
    """
    if skiprows is not None:
        if skiprows >= len(lines):
            raise FileFormatError(f"{where}: skiprows={skiprows} skips all {len(lines)} lines of the file")
        return [(k + 1, lines[k]) for k in range(skiprows) if lines[k].strip()], skiprows
    tail = next((line for line in reversed(lines) if line.strip() and not line.startswith("#")), "")
    delimiter = delimiter_of(tail)
    first_data = next(
        (k for k in range(start, len(lines)) if lines[k].strip() and _looks_like_data(lines[k], delimiter)),
        len(lines),
    )
    if first_data == len(lines):
        return [], start  # no row of numbers: the reader says so
    names_at = next((k for k in range(first_data - 1, start - 1, -1) if lines[k].strip()), start)
    width = len(split(lines[first_data], delimiter))
    if _key_value(lines[names_at]) and len(split(lines[names_at], delimiter)) != width:
        names_at = first_data  # 'Key: value' right above the rows: no line of names
    preamble = [(k + 1, lines[k]) for k in range(start, names_at) if lines[k].strip()]
    for lineno, line in preamble:
        if line.startswith("#") or _key_value(line) is None:
            raise FileFormatError(
                f"{where}: line {lineno} {line.strip()[:60]!r} comes before the column names (line "
                f"{names_at + 1}) but is neither a '# key: value' header line nor a 'Key: value' line; "
                "pass skiprows=<lines before the column names> to skip it"
            )
    return preamble, names_at


def _norm(key: str) -> str:
    return " ".join(key.replace("_", " ").lower().split())


def _is_rate_key(norm: str) -> bool:
    return norm in _PREAMBLE_RATE_KEYS or norm.replace(" ", "_") in _PREAMBLE_RATE_KEYS


def _positive(
    value: str, key: str, lineno: int, where: str, units: Optional[dict[str, float]] = None
) -> float:
    """The positive number ``value`` states, times the factor of its unit (from ``units``; none allowed
    without them)."""
    number, _, unit = value.strip().partition(" ")
    factor = (units or {"": 1.0}).get(unit.strip().lower())
    try:
        v = float(number)
    except ValueError:
        v = math.nan
    if not (math.isfinite(v) and v > 0):
        raise FileFormatError(f"{where}: line {lineno}: {key!r} = {value[:40]!r} is not a positive number")
    if factor is None:
        raise FileFormatError(
            f"{where}: line {lineno}: {key!r} = {value[:40]!r}: unit {unit.strip()[:20]!r} not understood "
            f"(known: {', '.join(u for u in (units or {}) if u)})"
        )
    return v * factor


def read_preamble(lines: Sequence[tuple[int, str]], where: str) -> Preamble:
    """The sampling rate (from a rate or an interval, which must agree), the sample count, and the other
    ``Key: value`` pairs as metadata (keys a header line cannot carry, or this library's, are left out)."""
    rates: list[tuple[str, float]] = []
    count: Optional[int] = None
    metadata: dict[str, str] = {}
    for lineno, line in lines:
        kv = _key_value(line)
        if kv is None:
            continue
        key, value = kv
        norm = _norm(key)
        if _is_rate_key(norm):
            rates.append((key, _positive(value, key, lineno, where, _RATE_UNITS)))
        elif norm in _PREAMBLE_STEP_KEYS:
            rates.append((key, 1.0 / _positive(value, key, lineno, where, _STEP_UNITS)))
        elif norm in _PREAMBLE_COUNT_KEYS:
            n = _positive(value, key, lineno, where)
            if not n.is_integer():
                raise FileFormatError(f"{where}: line {lineno}: {key!r} = {value!r} is not a whole number")
            count = int(n)
        if key in RESERVED_KEYS or key in _RESERVED:
            continue
        try:
            metadata[check_metadata_key(key)] = value
        except InvalidParameterError:
            continue  # a key no header line can carry (e.g. with a ':'): not kept
    if rates and max(r for _, r in rates) - min(r for _, r in rates) > _PREAMBLE_RTOL * rates[0][1]:
        shown = ", ".join(f"{k} -> {r:.9g} Hz" for k, r in rates)
        raise FileFormatError(
            f"{where}: the lines before the columns state different sampling rates ({shown})"
        )
    # A rate stated in Hz is taken as written (1 / 0.001 is not exactly 1000).
    hz = [r for k, r in rates if _is_rate_key(_norm(k))]
    chosen = hz[0] if hz else rates[0][1] if rates else None
    return Preamble(chosen, count, metadata)


def _role_of(name: str) -> tuple[str, Optional[str]]:
    """A column name without its unit suffix (``Force (N)``, ``disp [mm]``), and that unit."""
    m = _UNIT.match(name)
    return (m.group(1).strip().lower(), m.group(2).strip()) if m else (name.strip().lower(), None)


def _unit_of(name: str) -> Optional[str]:
    """The unit a column's name carries: in brackets (:func:`_role_of`), or as its last ``_`` part when that
    is a unit symbol (:data:`_SUFFIX`: ``force_N``). The second only labels a column already chosen (by its
    name or ``columns=``); it does not make ``force_N`` the output by itself (a ``time_s`` column beside a
    stated sampling rate would then be checked against it, where such files were read)."""
    unit = _role_of(name)[1]
    m = _SUFFIX.match(name.strip())
    return unit if unit or not (m and m.group(2) in _SUFFIX_UNITS) else m.group(2)


def _timed(name: str, role: str) -> bool:
    """``t [ms]``, ``time_ms``, ``t_us``: a time column by its name and a unit of time (then converted to
    seconds, :mod:`bouc_wen_id.timeunits`; ``time_N`` stays a name).  A ``_s`` suffix alone does not make
    the time column (``time_s`` beside a stated rate was left alone before, and a file relies on it: see
    ``test_io``); a unit other than seconds does, since reading past it would lose the declared unit."""
    if role != "t":
        return False
    base, unit = _role_of(name)
    if unit is not None:
        return base in ("t", "time") and time_scale(unit) is not None
    m = _SUFFIX.match(name.strip())
    scale = time_scale(m.group(2)) if m else None
    return m is not None and m.group(1).strip().lower() in ("t", "time") and scale not in (None, 1.0)


def infer_roles(
    names: Sequence[str], columns: dict[str, Union[str, int]], where: str
) -> tuple[dict[str, Union[str, int]], dict[str, str]]:
    """``columns`` completed with the signals a column's name states, and the units the names carry.

    ``Displacement (mm)`` is ``u`` (the whole name but its unit is one of the words; ``disp_mm`` is not, but
    mapped to ``u`` it carries its unit ``mm``: :func:`_unit_of`).
    A signal is inferred only when no column bears its own name, ``columns`` does not map it, and exactly
    one column's name says it; two candidates are an error naming both.
    """
    out = dict(columns)
    units: dict[str, str] = {}
    taken = {names[c] if isinstance(c, int) and c < len(names) else c for c in out.values()}
    for role, words in _ROLE_WORDS.items():
        if role in out or role in names:
            continue
        found = [n for n in names if n not in taken and (_role_of(n)[0] in words or _timed(n, role))]
        if len(found) > 1:
            raise FileFormatError(
                f"{where}: columns {', '.join(map(repr, found))} could each be {role!r}; choose with "
                f"columns={{{role!r}: ...}}"
            )
        if found:
            out[role] = found[0]
            taken.add(found[0])
    for role, col in out.items():
        name = names[col] if isinstance(col, int) and col < len(names) else col
        unit = _unit_of(str(name))
        if unit and role in ("t", "u", "y"):
            units[role] = unit
    return out, units


def ambiguous(names: Sequence[str], first_row: Sequence[str], where: str) -> FileFormatError:
    """No column is (or names) the input or the output: say which columns hold numbers and how to map."""
    numeric = [n for n, cell in zip(names, first_row) if is_number(cell)]
    example = numeric[-2:] if len(numeric) >= 2 else ["<input column>", "<output column>"]
    return FileFormatError(
        f"{where}: which column is the input u and which the output y? The columns are "
        f"{', '.join(map(repr, names))}, of which {', '.join(map(repr, numeric)) or 'none'} hold numbers, "
        f"and none is named u or y (nor displacement/force): map them with columns={{'u': {example[0]!r}, "
        f"'y': {example[1]!r}}} (command line: --columns u={example[0]} y={example[1]})"
    )


def event_column(names: Sequence[str], used: set[int]) -> Optional[int]:
    """The column of acquisition events (``Events``), unless a signal reads it."""
    return next(
        (j for j, n in enumerate(names) if n.strip().lower() in _EVENT_COLUMNS and j not in used), None
    )


def blocks(events: Sequence[str], n: int) -> list[tuple[int, int]]:
    """The acquisition blocks (start, stop) of ``n`` rows: a block ends after a row marked ``... Pause``
    or ``... Stop`` and a new one starts at a row marked ``... Resume`` or ``... Start``."""
    cuts = {0, n}
    for i, cell in enumerate(events):
        word = cell.strip().lower()
        if word.endswith(("pause", "stop")):
            cuts.add(i + 1)
        elif word.endswith(("resume", "start")):
            cuts.add(i)
    edges = sorted(c for c in cuts if 0 <= c <= n)
    return [(a, b) for a, b in zip(edges, edges[1:]) if b > a]


def event_cells(rows: Sequence[str], delimiter: Optional[str], column: int) -> list[str]:
    out = []
    for row in rows:
        cells = row.split(delimiter) if delimiter else row.split()
        out.append(cells[column] if column < len(cells) else "")
    return out
