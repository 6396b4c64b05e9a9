"""HDF5 (the ``hdf5`` extra, h5py): one experiment per group of datasets."""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from typing import Any, Optional

import numpy as np

from .. import _optional
from ..errors import BoucWenIdError, FileFormatError
from ..measurement import Measurement
from ._common import _ROLES, ColumnMap, Item, PathLike, _items, _reader_args
from ._containers import HEADER_KEY, _Channel, _container_items, _Group
from ._header import _header

#: Links to groups and datasets a file may hold (each group is walked once, by its address, so hard-link
#: cycles end): a file of millions of empty groups is refused rather than walked.
_HDF5_MAX_OBJECTS = 100_000
#: Soft links resolved through at most this many other soft links (a chain or a loop of them).
_HDF5_MAX_SOFT_HOPS = 16


def _refuse(where: str, path: str, what: str) -> FileFormatError:
    return FileFormatError(
        f"{where}: refused: {path!r} {what}; only the data inside the file named are read (copy the data "
        "into the file, e.g. h5py's Dataset[...] into a new dataset, to read them)"
    )


def _check_soft_link(h5py: Any, root: Any, group: Any, path: str, target: str, where: str) -> None:
    """Refuse a soft link whose target lies through an external link (in another file); follow it only
    link by link, never opening what an external link names."""
    current = root if target.startswith("/") else group
    parts = [c for c in target.split("/") if c and c != "."]
    hops = 0
    while parts:
        name = parts.pop(0)
        if not isinstance(current, h5py.Group) or name not in current:
            return  # dangling (or through a dataset): there is nothing it reaches
        link = current.get(name, getlink=True)
        if isinstance(link, h5py.SoftLink):
            hops += 1
            if hops > _HDF5_MAX_SOFT_HOPS:
                raise _refuse(where, path, f"is a chain of more than {_HDF5_MAX_SOFT_HOPS} soft links")
            current = root if link.path.startswith("/") else current
            parts = [c for c in link.path.split("/") if c and c != "."] + parts
        elif isinstance(link, h5py.HardLink):
            current = current[name]
        else:
            raise _refuse(where, path, f"is a soft link to {target!r}, which leads into another file")


def _check_dataset(dataset: Any, path: str, where: str) -> None:
    """Refuse a dataset whose samples live outside the file (external raw storage, a virtual dataset)."""
    if dataset.is_virtual:
        sources = ", ".join(sorted({f"{s.file_name}:{s.dset_name}" for s in dataset.virtual_sources()}))
        raise _refuse(where, path, f"is a virtual dataset (its samples come from {sources[:200]})")
    if dataset.external:
        files = ", ".join(sorted({os.fsdecode(name) for name, *_ in dataset.external}))
        raise _refuse(where, path, f"stores its samples in external files ({files[:200]})")


def _hdf5_groups(h5py: Any, root: Any, where: str) -> list[_Group]:
    """The root and every group below it, each once, with their datasets; refused when any object or link
    of the file leads outside it (external links, external raw storage, virtual datasets)."""
    out: list[_Group] = []
    info = h5py.h5o.get_info(root.id)
    seen: set[tuple[int, int]] = {(info.fileno, info.addr)}
    stack: list[tuple[Any, str]] = [(root, "")]
    count = 0
    while stack:
        group, prefix = stack.pop()
        channels: dict[str, _Channel] = {}
        subgroups = []
        for name in group:
            path = prefix + name
            link = group.get(name, getlink=True)
            if isinstance(link, h5py.SoftLink):
                # The object it names is read through its hard link (or is absent): check where it leads.
                _check_soft_link(h5py, root, group, path, link.path, where)
                continue
            if not isinstance(link, h5py.HardLink):
                target = f" ({link.filename}:{link.path})" if isinstance(link, h5py.ExternalLink) else ""
                raise _refuse(where, path, f"is an external link{target} into another file")
            obj = group[name]
            count += 1
            if count > _HDF5_MAX_OBJECTS:
                raise FileFormatError(f"{where}: more than {_HDF5_MAX_OBJECTS} links to groups and datasets")
            if isinstance(obj, h5py.Dataset):
                # A dataset shared by groups (hard links) is a channel of each; its size counts each time.
                _check_dataset(obj, path, where)
                size = int(obj.size) if obj.shape is not None else 0
                channels[name] = _Channel(name, path, size, dict(obj.attrs), _hdf5_reader(obj, where))
            elif isinstance(obj, h5py.Group):
                info = h5py.h5o.get_info(obj.id)
                if (info.fileno, info.addr) in seen:
                    continue  # a group already walked (a hard-link cycle, or a group linked twice)
                seen.add((info.fileno, info.addr))
                subgroups.append((obj, path + "/"))
        out.append(_Group(prefix.rstrip("/"), dict(group.attrs), channels))
        stack.extend(reversed(subgroups))  # depth first, in the order of the file's listing
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
    matrices).  A group written by :func:`write_hdf5` carries its header (attribute ``bouc_wen_id``) and
    reads back as written.

    Only the file named is read: a file holding an external link, a soft link that leads through one, a
    dataset with external raw storage or a virtual dataset is refused (:class:`FileFormatError`, naming
    the object), before any sample is read.  Soft links are not followed (what they name is read through
    its hard link); each group and dataset is visited once, however many hard links lead to it; the
    memory budget applies to all the experiments of the file together.
    """
    h5py = _optional.require("h5py", "reading .h5/.hdf5 files")
    p, where, cols, rate = _reader_args(path, columns, sample_rate, "HDF5")
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
