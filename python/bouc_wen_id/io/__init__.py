"""Reading and writing experiments: :class:`Recording` (U, omega known) and :class:`Measurement` (lab data).

Three file formats, each holding either kind, documented in the README:

* **CSV** (``.csv``), one experiment per file: ``# key: value`` header lines whose values are JSON, then a
  line of column names and one row per sample.  Columns are found by name (``t``, ``u``, ``y``; ``x``, ``w``
  for simulated recordings; any order, other columns ignored) or through ``columns={"u": "disp_mm", ...}``
  (names, or 0-based indices for a file without a line of names).  Without a ``t`` column the time axis is
  ``t = k / sample_rate`` from a ``# sample_rate: <Hz>`` header line or the ``sample_rate=`` argument.
* **Text** (``.txt``, ``.dat``, and ``.csv`` too) as a DAQ exports it: ``Key: value`` lines before the
  column names (``Sampling Rate: 1000`` sets the time axis; found by themselves or skipped with
  ``skiprows=``), text columns beside the numeric ones, and one experiment per acquisition block when an
  ``Events`` column marks ``DAQ Pause``/``DAQ Resume`` (see :func:`read_text`).
* **NPZ** (``.npz``), a bundle: arrays ``t_<i>``, ``u_<i>``, ``y_<i>`` (``x_<i>``, ``w_<i>``) and ``meta``, a
  JSON string holding the list of per-experiment headers (the CSV header as a JSON object).  A plain
  archive with arrays ``u``, ``y`` (``t``, or a scalar ``fs``/``sample_rate``) and an optional ``meta`` JSON
  object reads as one experiment.
* **TDMS** (``.tdms``, NI, extra ``tdms``) and **HDF5** (``.h5``, ``.hdf5``, extra ``hdf5``): one
  experiment per group holding the ``u`` and ``y`` channels (datasets), found by name or through
  ``columns`` (see :func:`read_tdms`, :func:`read_hdf5`); the sampling rate from the channels' attributes
  (``wf_increment``, ``sample_rate``, ...), a ``t`` channel or ``sample_rate=``.
* **MAT** (``.mat``, MATLAB v5/v7 via :func:`scipy.io.loadmat`): variables ``t``, ``u``, ``y`` (or a scalar
  ``fs``/``sample_rate`` instead of ``t``) and ``meta``, a JSON string; or a bundle, a variable
  ``experiments`` holding a struct array (or a cell array of structs) with the same fields.

The header decides the kind: ``format: "bouc_wen_id.recording"``, or ``amplitude`` and ``frequency`` without
a format, make a :class:`Recording`; ``format: "bouc_wen_id.measurement"``, or neither key, a
:class:`Measurement`.  Every malformed file raises :class:`FileFormatError` naming the file and the fault;
data problems inside a well-formed file keep their own names (``NonFiniteError``, ``TimeAxisError``, ...)
with the file name prefixed to the message.

Results are written as JSON (``IdentificationResult.to_json``).

The package keeps one module per format: ``_csv``, ``_npz``, ``_mat`` (with ``_matv5``, the guard that walks
a MAT v5 file before scipy reads it), ``_tdms`` and ``_hdf5`` (sharing ``_containers``); ``_header`` turns a
header and arrays into an experiment, ``_common`` holds the checks every reader shares (regular files, the
memory budget, the ``columns=`` and ``sample_rate=`` arguments) and ``_load`` chooses the format by suffix.
"""

from __future__ import annotations

# Public names outside __all__ (as before the split): the argument types, the container attributes read.
from ._common import ColumnMap as ColumnMap
from ._common import Item
from ._common import PathLike as PathLike
from ._containers import HEADER_KEY as HEADER_KEY
from ._containers import RATE_ATTRS as RATE_ATTRS
from ._containers import STEP_ATTRS as STEP_ATTRS
from ._containers import UNIT_ATTRS as UNIT_ATTRS
from ._csv import CSV_MEMORY_FACTOR as CSV_MEMORY_FACTOR
from ._csv import read_csv, read_text, write_csv
from ._hdf5 import read_hdf5, write_hdf5
from ._header import FORMAT, MEASUREMENT_FORMAT, VERSION
from ._load import SUFFIXES, load, load_recordings, save, save_recordings
from ._mat import read_mat, write_mat
from ._npz import read_npz, write_npz
from ._tdms import read_tdms, write_tdms

__all__ = [
    "Item",
    "load",
    "save",
    "load_recordings",
    "save_recordings",
    "read_csv",
    "read_text",
    "write_csv",
    "read_npz",
    "write_npz",
    "read_mat",
    "write_mat",
    "read_tdms",
    "write_tdms",
    "read_hdf5",
    "write_hdf5",
    "FORMAT",
    "MEASUREMENT_FORMAT",
    "VERSION",
    "SUFFIXES",
]
