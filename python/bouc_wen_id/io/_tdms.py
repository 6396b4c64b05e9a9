"""NI TDMS (the ``tdms`` extra, npTDMS): one experiment per group of channels."""

from __future__ import annotations

import json
from collections.abc import Sequence
from functools import partial
from typing import Any, Optional

import numpy as np

from .. import _optional
from ..errors import BoucWenIdError, FileFormatError
from ..measurement import Measurement
from ._common import _ROLES, ColumnMap, Item, PathLike, _items, _reader_args
from ._containers import HEADER_KEY, _Channel, _container_items, _Group
from ._header import _header


class _LogRecords:
    """Collects the warnings a library logs (npTDMS reports truncated files only through its logger)."""

    def __init__(self, name: str) -> None:
        import logging

        self.messages: list[str] = []
        records = self.messages

        class Handler(logging.Handler):
            def emit(self, record: logging.LogRecord) -> None:
                records.append(record.getMessage())

        self._logger = logging.getLogger(name)
        self._handler = Handler(logging.WARNING)

    def __enter__(self) -> list[str]:
        self._logger.addHandler(self._handler)
        return self.messages

    def __exit__(self, *exc: object) -> None:
        self._logger.removeHandler(self._handler)


def read_tdms(
    path: PathLike, *, columns: Optional[ColumnMap] = None, sample_rate: Optional[float] = None
) -> list[Item]:
    """Read the experiments of an NI TDMS file (needs the ``tdms`` extra: npTDMS).

    Every group holding the channels ``u`` and ``y`` (their own names, or those ``columns`` maps, e.g.
    ``{"u": "Displacement", "y": "Force"}``) is one experiment, named after the group; groups holding
    neither are skipped.  A ``"group/channel"`` path in ``columns`` reads that one experiment.  The time
    axis is the ``t`` channel when there is one, else ``t = k / rate`` with the rate from the channels'
    ``wf_increment`` (NI waveforms; ``dt``, ``sample_rate``, ``sampling_rate`` or ``fs`` also read, on the
    channels, their group or the file) or ``sample_rate=``.  Units come from the channels'
    ``unit_string``; ``wf_start_time`` and the group's scalar properties go into the metadata.  A group
    written by :func:`write_tdms` carries its header (property ``bouc_wen_id``) and reads back as written.
    """
    nptdms = _optional.require("nptdms", "reading .tdms files")
    p, where, cols, rate = _reader_args(path, columns, sample_rate, "TDMS")
    with _LogRecords("nptdms") as logged, open(p, "rb") as fh:
        try:
            tdms = nptdms.TdmsFile.open(fh)
        except Exception as exc:  # noqa: BLE001 - any decoder failure of an untrusted file is a format error
            raise FileFormatError(f"{where}: not a readable TDMS file ({type(exc).__name__}: {exc})") from exc

        def truncated() -> FileFormatError:
            return FileFormatError(f"{where}: the TDMS file is truncated or corrupt (npTDMS: {logged[0]})")

        with tdms:
            if logged:
                raise truncated()
            groups = [
                _Group(
                    g.name,
                    dict(g.properties),
                    {
                        c.name: _Channel(
                            c.name, f"{g.name}/{c.name}", len(c), dict(c.properties), partial(_read_all, c)
                        )
                        for c in g.channels()
                    },
                )
                for g in tdms.groups()
            ]
            try:
                items = _container_items(groups, dict(tdms.properties), cols, where, p.stem, rate, "channel")
            except BoucWenIdError as exc:
                if logged:
                    raise truncated() from exc
                raise
            if logged:
                raise truncated()
    return items


def _read_all(channel: Any) -> Any:
    return channel[:]


def write_tdms(path: PathLike, items: Sequence[Item]) -> None:
    """Write experiments to an NI TDMS file (needs the ``tdms`` extra): one group ``exp_<i>`` each, with
    float64 channels ``t``, ``u``, ``y`` (``x``, ``w``), their ``wf_increment`` and ``unit_string``, and
    the header as the group property ``bouc_wen_id`` (JSON)."""
    nptdms = _optional.require("nptdms", "writing .tdms files")
    seq = _items(items)
    objects: list[Any] = [nptdms.RootObject({})]
    for i, item in enumerate(seq):
        group = f"exp_{i:03d}"
        objects.append(nptdms.GroupObject(group, {HEADER_KEY: json.dumps(_header(item))}))
        units = item.units if isinstance(item, Measurement) else {}
        step = float(np.median(np.diff(item.t))) if item.t.size > 1 else None
        for role in _ROLES:
            data = getattr(item, role, None)
            if data is None:
                continue
            props: dict[str, Any] = {}
            if role == "t":
                props["unit_string"] = "s"
            else:
                if step is not None:
                    props["wf_increment"] = step
                    props["wf_start_offset"] = float(item.t[0])
                if role in units:
                    props["unit_string"] = units[role]
            objects.append(nptdms.ChannelObject(group, role, np.asarray(data, dtype=np.float64), props))
    with nptdms.TdmsWriter(str(path)) as writer:
        writer.write_segment(objects)
