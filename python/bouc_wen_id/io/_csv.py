"""CSV: one experiment per file, ``# key: value`` header lines, a line of column names, the rows."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Optional

import numpy as np

from .. import budget as _budget
from ..errors import FileFormatError, InvalidParameterError
from ..model import Recording
from ._common import (
    ColumnMap,
    Item,
    PathLike,
    _check_columns,
    _check_rate,
    _pick,
    _regular_file,
)
from ._header import (
    _STRICT,
    _build,
    _check_header_keys,
    _header,
)


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
