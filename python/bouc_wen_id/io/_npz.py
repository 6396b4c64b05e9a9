"""NPZ: a bundle written by :func:`write_npz` or a plain archive of arrays ``u``, ``y`` (``t``/``fs``)."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Mapping, Sequence
from typing import Any, Optional

import numpy as np

from .. import budget as _budget
from ..errors import BoucWenIdError, FileFormatError
from ._common import (
    _ROLES,
    ColumnMap,
    Item,
    PathLike,
    _array,
    _items,
    _parse_json,
    _pick,
    _reader_args,
)
from ._header import _build, _header, _read_single


def write_npz(path: PathLike, items: Sequence[Item]) -> None:
    """Write several experiments (recordings and measurements, mixed) into one compressed NPZ bundle."""
    items = _items(items)
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
    p, where, cols, rate = _reader_args(path, columns, sample_rate, "NPZ")
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
