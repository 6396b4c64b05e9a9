"""MAT (MATLAB v5/v7, through :func:`scipy.io.loadmat`): plain variables or an ``experiments`` bundle."""

from __future__ import annotations

import io as _stdio
import json
from collections.abc import Mapping, Sequence
from typing import Any, Optional, Union

import numpy as np

from ..errors import FileFormatError
from ._common import (
    _ROLES,
    ColumnMap,
    Item,
    PathLike,
    _items,
    _parse_json,
    _pick,
    _reader_args,
)
from ._header import _header, _read_single
from ._matv5 import _guard_mat5


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

    items = _items(items)
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

    p, where, cols, rate = _reader_args(path, columns, sample_rate, "MAT")
    wanted = {"t", "u", "y", "x", "w", "fs", "sample_rate", "meta", "experiments"}
    wanted |= {c for c in cols.values() if isinstance(c, str)}
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
