"""Reading and writing recordings and results.

Two recording formats, both documented in the README:

* **CSV**, one experiment per file: ``# key: value`` header lines (``format``, ``version``, ``amplitude``,
  ``frequency``, ``settle_periods``, optional ``plant`` as JSON, any other key becomes metadata), then a
  column header ``t,u,y`` (optionally ``x,w``) and one row per sample.
* **NPZ**, one or several experiments in one bundle: arrays ``t_<i>``, ``u_<i>``, ``y_<i>`` (and ``x_<i>``,
  ``w_<i>``) and one JSON string ``meta`` holding, per experiment, the header fields of the CSV format.

Results are written as JSON (``IdentificationResult.to_json``).
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any, Union

import numpy as np

from .errors import FileFormatError
from .model import Recording, WienerPlant

__all__ = ["save_recordings", "load_recordings", "write_csv", "read_csv", "write_npz", "read_npz"]

PathLike = Union[str, "os.PathLike[str]"]
FORMAT = "bouc_wen_id.recording"
VERSION = 1
_RESERVED = {"format", "version", "amplitude", "frequency", "settle_periods", "plant"}


def _header(rec: Recording) -> dict[str, Any]:
    head: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "amplitude": rec.amplitude,
        "frequency": rec.frequency,
        "settle_periods": rec.settle_periods,
    }
    if rec.plant is not None:
        head["plant"] = rec.plant.to_dict()
    for k, v in rec.metadata.items():
        if k not in _RESERVED:
            head[k] = str(v)
    return head


def _from_header(head: dict[str, Any], arrays: dict[str, np.ndarray], where: str) -> Recording:
    if head.get("format", FORMAT) != FORMAT:
        raise FileFormatError(f"{where}: format {head.get('format')!r} is not {FORMAT!r}")
    if int(head.get("version", VERSION)) > VERSION:
        raise FileFormatError(
            f"{where}: version {head['version']} is newer than this library reads ({VERSION})"
        )
    for key in ("amplitude", "frequency"):
        if key not in head:
            raise FileFormatError(f"{where}: the header has no {key!r} (the known input U cos(omega t))")
    for key in ("t", "u", "y"):
        if key not in arrays:
            raise FileFormatError(f"{where}: no column {key!r}; expected t,u,y (and optionally x,w)")
    plant = head.get("plant")
    try:
        return Recording(
            t=arrays["t"],
            u=arrays["u"],
            y=arrays["y"],
            amplitude=float(head["amplitude"]),
            frequency=float(head["frequency"]),
            settle_periods=int(head.get("settle_periods", 0)),
            x=arrays.get("x"),
            w=arrays.get("w"),
            plant=None if plant is None else WienerPlant.from_dict(plant),
            metadata={k: str(v) for k, v in head.items() if k not in _RESERVED},
        )
    except (KeyError, TypeError) as exc:
        raise FileFormatError(f"{where}: malformed header field ({exc})") from exc


def write_csv(path: PathLike, rec: Recording) -> None:
    """Write one recording as CSV with a ``# key: value`` header."""
    cols = ["t", "u", "y"] + [c for c in ("x", "w") if getattr(rec, c) is not None]
    data = np.column_stack([getattr(rec, c) for c in cols])
    with open(path, "w", encoding="utf-8") as fh:
        for k, v in _header(rec).items():
            fh.write(f"# {k}: {json.dumps(v)}\n")
        fh.write(",".join(cols) + "\n")
        np.savetxt(fh, data, delimiter=",", fmt="%.17g")


def read_csv(path: PathLike) -> Recording:
    """Read one recording written by :func:`write_csv` (or by hand in the same layout)."""
    head: dict[str, Any] = {}
    with open(path, encoding="utf-8") as fh:
        line = fh.readline()
        while line.startswith("#"):
            key, sep, value = line[1:].partition(":")
            if not sep:
                raise FileFormatError(f"{path}: header line {line.strip()!r} is not '# key: value'")
            try:
                head[key.strip()] = json.loads(value)
            except json.JSONDecodeError:
                head[key.strip()] = value.strip()
            line = fh.readline()
        cols = [c.strip() for c in line.strip().split(",")]
        try:
            data = np.loadtxt(fh, delimiter=",", ndmin=2)
        except ValueError as exc:
            raise FileFormatError(f"{path}: the data rows are not numeric CSV ({exc})") from exc
    if data.shape[1] != len(cols):
        raise FileFormatError(f"{path}: {len(cols)} column names but {data.shape[1]} columns of data")
    return _from_header(head, {c: data[:, i] for i, c in enumerate(cols)}, str(path))


def write_npz(path: PathLike, recordings: Sequence[Recording]) -> None:
    """Write several recordings into one compressed NPZ bundle."""
    arrays: dict[str, np.ndarray] = {}
    meta = []
    for i, rec in enumerate(recordings):
        for c in ("t", "u", "y", "x", "w"):
            v = getattr(rec, c)
            if v is not None:
                arrays[f"{c}_{i}"] = np.asarray(v)
        meta.append(_header(rec))
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez_compressed(path, **arrays)  # type: ignore[arg-type]


def read_npz(path: PathLike) -> list[Recording]:
    """Read every recording of an NPZ bundle written by :func:`write_npz`."""
    with np.load(path, allow_pickle=False) as z:
        if "meta" not in z:
            raise FileFormatError(f"{path}: no 'meta' entry; not a bouc_wen_id recording bundle")
        meta = json.loads(str(z["meta"]))
        out = []
        for i, head in enumerate(meta):
            arrays = {c: z[f"{c}_{i}"] for c in ("t", "u", "y", "x", "w") if f"{c}_{i}" in z}
            out.append(_from_header(head, arrays, f"{path}[{i}]"))
    return out


def save_recordings(path: PathLike, recordings: Sequence[Recording]) -> list[Path]:
    """Save recordings: ``*.npz`` gives one bundle, anything else a folder of ``exp_<i>.csv`` files."""
    p = Path(path)
    if p.suffix == ".npz":
        write_npz(p, recordings)
        return [p]
    p.mkdir(parents=True, exist_ok=True)
    written = []
    for i, rec in enumerate(recordings):
        f = p / f"exp_{i:03d}.csv"
        write_csv(f, rec)
        written.append(f)
    return written


def load_recordings(paths: PathLike | Iterable[PathLike]) -> list[Recording]:
    """Load recordings from files (``.csv``, ``.npz``) and folders of such files, in sorted order."""
    items = [paths] if isinstance(paths, (str, os.PathLike)) else list(paths)
    out: list[Recording] = []
    for item in items:
        p = Path(item)
        if p.is_dir():
            files = sorted(f for f in p.iterdir() if f.suffix in (".csv", ".npz"))
            if not files:
                raise FileFormatError(f"{p}: the folder holds no .csv or .npz recordings")
            out.extend(load_recordings(files))
        elif not p.exists():
            raise FileFormatError(f"{p}: no such file or folder")
        elif p.suffix == ".npz":
            out.extend(read_npz(p))
        elif p.suffix == ".csv":
            out.append(read_csv(p))
        else:
            raise FileFormatError(f"{p}: unknown recording format {p.suffix!r} (expected .csv or .npz)")
    return out
