"""Files and folders: :func:`load` and :func:`save` choose the format by suffix."""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Literal, Optional

from ..errors import FileFormatError, InvalidParameterError
from ..measurement import Measurement
from ..model import Recording
from ..units import harmonise
from ._common import ColumnMap, Item, PathLike, _check_columns, _check_rate, _items
from ._csv import read_text, write_csv
from ._hdf5 import read_hdf5, write_hdf5
from ._mat import read_mat, write_mat
from ._npz import read_npz, write_npz
from ._tdms import read_tdms, write_tdms
from ._text import check_skiprows, holds_numbers

#: File suffixes the loaders read (case-insensitive); folders are scanned for these.
#: (``.txt`` and ``.dat`` files without a row of numbers, notes beside the data, are passed over in folders.)
SUFFIXES = (".csv", ".txt", ".dat", ".npz", ".mat", ".tdms", ".h5", ".hdf5")
#: Suffixes of delimited text (read by :func:`read_text`: CSV, and DAQ exports with header lines).
TEXT_SUFFIXES = (".csv", ".txt", ".dat")


def _read_file(
    p: Path, cols: Optional[ColumnMap], rate: Optional[float], skiprows: Optional[int] = None
) -> list[Item]:
    suffix = p.suffix.lower()
    if suffix in TEXT_SUFFIXES:
        return read_text(p, columns=cols, sample_rate=rate, skiprows=skiprows)
    if suffix == ".npz":
        return read_npz(p, columns=cols, sample_rate=rate)
    if suffix == ".mat":
        return read_mat(p, columns=cols, sample_rate=rate)
    if suffix == ".tdms":
        return read_tdms(p, columns=cols, sample_rate=rate)
    if suffix in (".h5", ".hdf5"):
        return read_hdf5(p, columns=cols, sample_rate=rate)
    raise FileFormatError(
        f"{p}: unknown recording format {p.suffix!r} (expected .csv, .txt, .dat, .npz, .mat, .tdms, .h5 or "
        f".hdf5){_json_hint(p) if suffix == '.json' else ''}"
    )


def _json_hint(p: Path) -> str:
    """What a JSON file given as a recording is read by: a diagnosis by load_diagnosis, a model by
    load_model (review 35: diagnosis.json was refused without naming a reader)."""
    from .._diagnosis_json import HINT, looks_like

    try:
        doc = json.loads(p.read_text(encoding="utf-8")) if p.stat().st_size < 200_000_000 else None
    except (OSError, ValueError):
        doc = None
    if looks_like(doc):
        return f"; {HINT}"
    return (
        "; a JSON file is no recording: a diagnosis is read by bouc_wen_id.load_diagnosis, a model document "
        "by bouc_wen_id.export.load_model"
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
                if f.is_file()
                and f.suffix.lower() in SUFFIXES
                and not f.name.startswith(".")
                # Notes beside the data (a README.txt) are not recordings; a named file is always read.
                and (f.suffix.lower() not in (".txt", ".dat") or holds_numbers(f))
            )
            if not files:
                said = (
                    f"; it holds diagnosis.json: {_json_hint(p / 'diagnosis.json')[2:]}"
                    if (p / "diagnosis.json").is_file()
                    else ""
                )
                raise FileFormatError(
                    f"{p}: the folder holds no .csv or .npz recordings (nor .txt, .dat, .mat, .tdms, .h5 or "
                    f".hdf5 files){said}"
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
    skiprows: Optional[int] = None,
) -> list[Item]:
    """Load experiments from files (``.csv``, ``.txt``, ``.dat``, ``.npz``, ``.mat``; ``.tdms``, ``.h5``,
    ``.hdf5`` with the ``tdms``/``hdf5`` extras) and folders of such files (sorted by name).

    Each experiment is a :class:`Recording` when its header states the input's ``amplitude`` and
    ``frequency`` (or ``format: "bouc_wen_id.recording"``), a :class:`Measurement` otherwise.
    ``columns`` and ``sample_rate`` apply to every file (see :func:`read_csv`; in TDMS and HDF5 files
    ``columns`` names channels or datasets, or pins ``"group/channel"`` paths: see :func:`read_tdms`).
    Text files may start with a DAQ's ``Key: value`` lines (found by themselves, or skipped with
    ``skiprows``) and hold one experiment per acquisition block: see :func:`read_text`.

    The experiments are one data set: their units must agree (:mod:`bouc_wen_id.units`).  A file whose
    column names state another unit of the same quantity than the first file's (``disp_m`` beside
    ``disp_mm``, ``Force (kN)`` beside ``Force (N)``) is converted to the first file's unit, with a
    :class:`~bouc_wen_id.errors.UnitWarning` (new arrays; the conversion is recorded in the experiment's
    ``metadata["units_converted"]``); a file stating no unit is taken to be in the others'.

    Raises
    ------
    FileFormatError
        A missing file, an unknown suffix, or a malformed file (named, with what is wrong).
    UnitMismatchError
        Two files state units of one quantity that no known scale relates (``mm`` and ``N``).
    """
    cols = _check_columns(columns)
    rate = _check_rate(sample_rate)
    skip = check_skiprows(skiprows)
    out: list[Item] = []
    names: list[str] = []
    for f in _files(paths):
        read = _read_file(f, cols, rate, skip)
        here = [f.name if len(read) == 1 else f"{f.name}[{b}]" for b in range(len(read))]
        out.extend(_named(item, name) for item, name in zip(read, here))
        names.extend(here)
    # One data set: one unit per quantity (later files converted to the first's, or a UnitMismatchError).
    return harmonise(out, names).items if len(out) > 1 else out


def _named(item: Item, name: str) -> Item:
    """A recording whose header names no experiment, named after its file (``metadata["name"]``, as a
    measurement's ``name`` is): messages then say "item 3 (exp3.csv)", not "item 3".  A new object with the
    same samples; nothing read from the file is changed."""
    if not isinstance(item, Recording) or item.metadata.get("name"):
        return item
    return Recording(
        item.t,
        item.u,
        item.y,
        item.amplitude,
        item.frequency,
        item.settle_periods,
        x=item.x,
        w=item.w,
        plant=item.plant,
        metadata={"name": name, **item.metadata},
    )


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
        read = _read_file(f, cols, rate)
        for b, item in enumerate(read):
            item = _named(item, f.name if len(read) == 1 else f"{f.name}[{b}]")
            if not isinstance(item, Recording):
                raise FileFormatError(
                    f"{f}: holds a measurement (no 'amplitude' and 'frequency' in its header), not a "
                    "recording; read lab data with bouc_wen_id.io.load"
                )
            out.append(item)
    return harmonise(out).items if len(out) > 1 else out


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
    seq = _items([items] if isinstance(items, (Recording, Measurement)) else items, "save")
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
