"""HDF5 (the ``hdf5`` extra, h5py): one experiment per group of datasets."""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, Optional

import numpy as np

from .. import _optional
from ..errors import BoucWenIdError, FileFormatError
from ..measurement import Measurement
from ._common import (
    _ROLES,
    ColumnMap,
    Item,
    PathLike,
    _check_columns,
    _check_rate,
    _items,
    _regular_file,
)
from ._containers import HEADER_KEY, _Channel, _container_items, _Group
from ._header import (
    _header,
)

#: HDF5 groups nested deeper than this are not searched (hard links can make cycles).
_HDF5_MAX_DEPTH = 8


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
