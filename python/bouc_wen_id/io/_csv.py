"""CSV and delimited text: ``# key: value`` header lines (or a DAQ's ``Key: value`` lines, see ``_text``), a
line of column names, the rows; one experiment per file, or per acquisition block (:func:`read_text`)."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np

from .. import budget as _budget
from ..errors import FileFormatError, InvalidParameterError
from ..model import Recording
from ._common import ColumnMap, FloatArray, Item, PathLike, _check_columns, _check_rate, _pick, _regular_file
from ._header import _STRICT, _build, _check_header_keys, _header
from ._text import (
    Preamble,
    ambiguous,
    blocks,
    check_skiprows,
    delimiter_of,
    event_cells,
    event_column,
    find_preamble,
    infer_roles,
    is_number,
    read_preamble,
    split,
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
    size = _regular_file(path, "text", CSV_MEMORY_FACTOR)
    try:
        with open(path, "rb") as fh:
            # Never more than the size checked: a file that grows while read is cut at its checked size.
            raw = fh.read(size)
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FileFormatError(f"{path}: not a UTF-8 text file ({exc})") from exc
    except OSError as exc:
        raise FileFormatError(f"{path}: cannot be read ({exc})") from exc


def _diagnose(rows: Sequence[tuple[int, str]], delimiter: Optional[str], width: int, where: str) -> str:
    """Where a block of data rows that numpy refused goes wrong, by file line."""
    for lineno, line in rows:
        cells = split(line, delimiter)
        if len(cells) != width:
            return f"{where}: line {lineno} has {len(cells)} fields, the first data row {width} (ragged rows)"
        for j, cell in enumerate(cells):
            if not is_number(cell) or "_" in cell:
                return f"{where}: line {lineno}, field {j + 1}: {cell[:40]!r} is not a number"
    return f"{where}: the data rows are not numeric CSV"


def _comment_header(lines: Sequence[str], i: int, where: str) -> tuple[dict[str, Any], int]:
    """The ``# key: value`` lines from line ``i`` (values JSON, or text for free-form keys), and the line
    after them."""
    head: dict[str, Any] = {}
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
    return head, i


def _column_names(lines: Sequence[str], i: int, where: str) -> tuple[Optional[list[str]], int, Optional[str]]:
    """The column names at line ``i`` (None when it is already a row of numbers), where the rows start,
    and the delimiter."""
    if i == len(lines):
        raise FileFormatError(f"{where}: no column names and no data after the header")
    delimiter = delimiter_of(lines[i])
    cells = split(lines[i], delimiter)
    if all(is_number(c) for c in cells):
        return None, i, delimiter
    names = [c.strip("\"'").strip() for c in cells]
    for j, nm in enumerate(names):
        if not nm:
            raise FileFormatError(f"{where}: column {j + 1} of the column-name line {i + 1} has no name")
    dup = sorted({nm for nm in names if names.count(nm) > 1})
    if dup:
        raise FileFormatError(f"{where}: column names {dup} appear more than once")
    return names, i + 1, delimiter


def _load_rows(
    rows: Sequence[tuple[int, str]], delimiter: Optional[str], usecols: Optional[Sequence[int]], where: str
) -> FloatArray:
    """The numbers of ``rows`` (all their fields, or the columns ``usecols``) as a 2-D array."""
    width = len(split(rows[0][1], delimiter))
    try:
        return np.loadtxt(
            [r for _, r in rows],
            delimiter=delimiter,
            ndmin=2,
            dtype=np.float64,
            comments=None,
            usecols=usecols,
        )
    except (ValueError, TypeError, OverflowError) as exc:
        raise FileFormatError(_diagnose(rows, delimiter, width, where) + f" ({exc})") from exc


def _check_widths(
    rows: Sequence[tuple[int, str]], delimiter: Optional[str], names: Sequence[str], where: str
) -> None:
    """Every row has a field per name, except that text columns after the last numeric one (an event log,
    mostly empty) may be left out."""
    first = split(rows[0][1], delimiter)
    least = 1 + max(
        (j for j, cell in enumerate(first[: len(names)]) if is_number(cell)), default=len(names) - 1
    )
    for lineno, line in rows:
        n = line.count(delimiter) + 1 if delimiter else len(line.split())
        if n > len(names):
            raise FileFormatError(
                f"{where}: {len(names)} column names but {n} columns of data (line {lineno})"
            )
        if n < least:
            raise FileFormatError(
                f"{where}: line {lineno} has {n} fields; the {len(names)} columns "
                f"({', '.join(map(repr, names))}) need {least} (ragged rows)"
            )


def _signals(
    rows: Sequence[tuple[int, str]],
    delimiter: Optional[str],
    names: Optional[list[str]],
    cols: dict[str, Union[str, int]],
    where: str,
) -> tuple[dict[str, FloatArray], list[str], dict[str, int], dict[str, str]]:
    """The signals by role, the column names (``column <j>`` for a file without them), the column of each
    signal and the units the names carry."""
    if names is None:
        data = _load_rows(rows, delimiter, None, where)
        if not any(isinstance(c, int) for c in cols.values()):
            raise FileFormatError(
                f"{where}: the file has no line of column names; name them (e.g. 't,u,y') or pass "
                "columns={'u': <index>, 'y': <index>} with 0-based column indices"
            )
        names = [f"column {j}" for j in range(data.shape[1])]
        picked = _pick(names, cols, where)
        return {role: np.ascontiguousarray(data[:, j]) for role, j in picked.items()}, names, picked, {}
    lineno, first = rows[0]
    if not any(is_number(c) for c in split(first, delimiter)):
        raise FileFormatError(
            f"{where}: line {lineno} {first.strip()[:60]!r} is not a row of numbers (no data)"
        )
    cols, units = infer_roles(names, cols, where)
    picked = _pick(names, cols, where)
    if "u" not in picked and "y" not in picked:
        raise ambiguous(names, split(rows[0][1], delimiter), where)
    used = sorted(set(picked.values()))
    try:  # the common case, every field a number: one pass in numpy, which checks the widths itself
        data = np.loadtxt([r for _, r in rows], delimiter=delimiter, ndmin=2, dtype=np.float64, comments=None)
        if data.shape[1] != len(names):
            raise ValueError("not one field per name")
        data = data[:, used]
    except (ValueError, TypeError, OverflowError):
        _check_widths(rows, delimiter, names, where)
        data = _load_rows(rows, delimiter, used, where)
    arrays = {role: np.ascontiguousarray(data[:, used.index(j)]) for role, j in picked.items()}
    return arrays, names, picked, units


def _merge_preamble(head: dict[str, Any], pre: Preamble, nrows: int, where: str) -> None:
    """The preamble's rate and metadata into the header; its sample count checked against the rows."""
    if pre.count is not None and pre.count != nrows:
        raise FileFormatError(
            f"{where}: the lines before the columns state {pre.count} samples, the file has {nrows} rows "
            "(truncated, or rows added)"
        )
    if pre.rate is not None:
        stated = head.get("sample_rate")
        if isinstance(stated, (int, float)) and abs(stated - pre.rate) > 1e-9 * pre.rate:
            raise FileFormatError(
                f"{where}: '# sample_rate: {stated}' and the DAQ header's {pre.rate:.9g} Hz disagree"
            )
        head.setdefault("sample_rate", pre.rate)
    for key, value in pre.metadata.items():
        head.setdefault(key, value)


def read_text(
    path: PathLike,
    *,
    columns: Optional[ColumnMap] = None,
    sample_rate: Optional[float] = None,
    skiprows: Optional[int] = None,
) -> list[Item]:
    """Read the experiments of a delimited text file (``.csv``, ``.txt``, ``.dat``): one, or one per
    acquisition block when an ``Events`` column marks ``DAQ Pause`` / ``DAQ Resume``.

    As :func:`read_csv`, and also DAQ exports: ``Key: value`` lines before the column names (found, or
    skipped with ``skiprows``) may state the sampling rate (``Sampling Rate``, ``Sampling Interval``) and
    the sample count (checked); text columns (a date) are allowed beside the numeric ones.  Columns named
    for what they hold (``Time``, ``Displacement (mm)``, ``Force [N]``) are read as ``t``, ``u``, ``y``
    with their units; when no column says which is the input and which the output (``CHANNEL0``,
    ``CHANNEL1``), the :class:`FileFormatError` lists the numeric columns and the ``columns=`` to pass.
    """
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    skip = check_skiprows(skiprows)
    p = Path(path)
    where = str(p)
    lines = [line.rstrip("\r") for line in _read_text(p).split("\n")]
    _budget.check_samples(f"{where}: the text rows", len(lines))
    if not any(line.strip() for line in lines):
        raise FileFormatError(f"{where}: the file is empty")
    if skip is not None:
        pre_lines, i = find_preamble(lines, 0, skip, where)
        head, i = _comment_header(lines, i, where)
    else:
        head, i = _comment_header(lines, 0, where)
        pre_lines, i = find_preamble(lines, i, None, where)
    names, start, delimiter = _column_names(lines, i, where)
    rows = [
        (k + 1, lines[k])
        for k in range(start, len(lines))
        if lines[k].strip() and not lines[k].startswith("#")
    ]
    if not rows:
        raise FileFormatError(f"{where}: no data rows after the column names")
    _merge_preamble(head, read_preamble(pre_lines, where), len(rows), where)
    arrays, names, picked, units = _signals(rows, delimiter, names, cols, where)
    if units and "units" not in head:
        head["units"] = units
    sources = {role: names[j] for role, j in picked.items() if names[j] != role}
    spans = _blocks(rows, delimiter, names, set(picked.values()))
    if len(spans) == 1:
        return [_build(head, arrays, where, default_name=p.stem, sample_rate=rate, sources=sources)]
    out: list[Item] = []
    for b, (a, e) in enumerate(spans):
        block_head = {
            **head,
            "block": str(b),
            "first_line": str(rows[a][0]),
            "last_line": str(rows[e - 1][0]),
        }
        part = {role: np.ascontiguousarray(v[a:e]) for role, v in arrays.items()}
        at = f"{where}[{b}]"
        out.append(
            _build(block_head, part, at, default_name=f"{p.stem}[{b}]", sample_rate=rate, sources=sources)
        )
    return out


def _blocks(
    rows: Sequence[tuple[int, str]], delimiter: Optional[str], names: Sequence[str], used: set[int]
) -> list[tuple[int, int]]:
    """The acquisition blocks (row ranges) that an ``Events`` column marks; the whole file without one."""
    column = event_column(names, used)
    if column is None:
        return [(0, len(rows))]
    return blocks(event_cells([r for _, r in rows], delimiter, column), len(rows))


def read_csv(
    path: PathLike,
    *,
    columns: Optional[ColumnMap] = None,
    sample_rate: Optional[float] = None,
    skiprows: Optional[int] = None,
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
    skiprows : int, optional
        Lines at the top of the file to skip (a DAQ's header); found by themselves when each reads as
        ``Key: value`` (see :func:`read_text`).
    """
    items = read_text(path, columns=columns, sample_rate=sample_rate, skiprows=skiprows)
    if len(items) != 1:
        raise FileFormatError(
            f"{path}: holds {len(items)} acquisition blocks (DAQ pauses); read them with "
            "bouc_wen_id.io.read_text or bouc_wen_id.load"
        )
    return items[0]
