"""What every reader shares: the types, the regular-file and budget check, the ``columns=`` and
``sample_rate=`` arguments, and numeric vectors from containers."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np
from numpy.typing import NDArray

from .. import budget as _budget
from ..errors import FileFormatError, InvalidParameterError
from ..measurement import Measurement, check_sample_rate
from ..model import Recording

PathLike = Union[str, "os.PathLike[str]"]
#: What the loaders return: a recording (U and omega known) or a raw lab measurement.
Item = Union[Recording, Measurement]
#: ``columns=``: signal name (``t``, ``u``, ``y``, ``x``, ``w``) -> column name, or 0-based column index.
ColumnMap = Mapping[str, Union[str, int]]
FloatArray = NDArray[np.float64]

#: Signals a file can hold, in column order.
_ROLES = ("t", "u", "y", "x", "w")


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
    return check_sample_rate(sample_rate)


def _reader_args(
    path: PathLike, columns: Optional[ColumnMap], sample_rate: Optional[float], what: str
) -> tuple[Path, str, dict[str, Union[str, int]], Optional[float]]:
    """What a container reader checks first, in this order: ``columns=``, ``sample_rate=``, then that
    ``path`` is a regular ``what`` file within the byte budget; ``(path, where, columns, sample_rate)``."""
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    p = Path(path)
    _regular_file(p, what)
    return p, str(p), cols, rate


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
    return check_sample_rate(arr[0], where)


def _parse_json(text: str, where: str, what: str) -> Any:
    try:
        return json.loads(text)
    except (ValueError, RecursionError) as exc:
        raise FileFormatError(f"{where}: {what} is not valid JSON ({exc})") from exc


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


def _items(items: Sequence[Item], verb: str = "write") -> list[Item]:
    """The experiments to write or save: at least one, each a Recording or a Measurement."""
    seq = list(items)
    if not seq:
        raise InvalidParameterError(f"nothing to {verb}: no experiments")
    for item in seq:
        if not isinstance(item, (Recording, Measurement)):
            raise InvalidParameterError(
                f"expected Recording or Measurement objects, got {type(item).__name__}"
            )
    return seq
