"""What the lab containers (NI TDMS, HDF5) share: groups of channels, their stated rates, units and
headers, and the experiments found in them."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Optional, Union

import numpy as np

from .. import budget as _budget
from ..errors import BoucWenIdError, FileFormatError, InvalidParameterError
from ..measurement import RESERVED_KEYS, check_metadata_key
from ._common import Item, _array, _parse_json, _pick
from ._header import _build

#: Group property (TDMS) or attribute (HDF5) holding an experiment's header as JSON (what :func:`write_tdms`
#: and :func:`write_hdf5` write); a group without it is read as lab data.
HEADER_KEY = "bouc_wen_id"
#: Channel, group or file attributes that state the sampling rate in Hz ...
RATE_ATTRS = ("sample_rate", "sampling_rate", "fs")
#: ... or the sampling step in s (``wf_increment``: the step of an NI waveform channel).
STEP_ATTRS = ("wf_increment", "dt")
#: Channel attributes holding the channel's unit (``unit_string``: NI's).
UNIT_ATTRS = ("unit_string", "units", "unit")
#: Lab group properties that may set a header key (the others among RESERVED_KEYS would change the kind
#: of experiment or clash with what the file states elsewhere, so they are left out).
_LAB_HEADER_KEYS = ("nominal_frequency", "nominal_frequency_hz")
#: Relative disagreement allowed between two stated sampling rates (they are copies of one number).
_STATED_RTOL = 1e-9


@dataclass(frozen=True)
class _Channel:
    """One channel of a lab container, read only when needed."""

    name: str
    #: ``group/channel`` (TDMS) or the dataset's path without its leading ``/`` (HDF5).
    path: str
    size: int
    props: Mapping[str, Any]
    read: Callable[[], Any]


@dataclass(frozen=True)
class _Group:
    """A TDMS group or an HDF5 group (``path`` '' for the HDF5 root) and its channels by name."""

    path: str
    props: Mapping[str, Any]
    channels: Mapping[str, _Channel]


def _plain(value: Any) -> Any:
    """A property value as a Python scalar (bytes decoded, one-element arrays unwrapped); None if it is
    not a string, number or time stamp."""
    if isinstance(value, np.ndarray) and value.size == 1:
        value = value.reshape(())[()]  # a numpy scalar (datetime64 kept as such)
    if isinstance(value, np.generic) and value.dtype.kind != "M":
        value = value.item()
    if isinstance(value, bytes):
        return value.decode("utf-8", "replace")
    if isinstance(value, np.datetime64):
        return str(value)
    if isinstance(value, (str, int, float)) and not isinstance(value, bool):
        return value
    return None


def _stated_rate(props: Mapping[str, Any], where: str, what: str) -> Optional[float]:
    """The sampling rate (Hz) that ``props`` state, if any."""
    for keys, is_step in ((RATE_ATTRS, False), (STEP_ATTRS, True)):
        for key in keys:
            if key not in props:
                continue
            v = _plain(props[key])
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0:
                raise FileFormatError(
                    f"{where}: {what} attribute {key!r} = {props[key] if v is None else v!r} is not a "
                    "positive "
                    f"{'step (s)' if is_step else 'rate (Hz)'}"
                )
            return 1.0 / float(v) if is_step else float(v)
    return None


def _file_rate(
    picked: Mapping[str, _Channel], chain: Sequence[tuple[str, Mapping[str, Any]]], where: str
) -> Optional[float]:
    """The rate the channels state (they must agree), else the first their group or the file states."""
    rates = {}
    for role, ch in picked.items():
        if role != "t":
            r = _stated_rate(ch.props, where, f"{ch.path!r}:")
            if r is not None:
                rates[ch.path] = r
    if rates:
        lo, hi = min(rates.values()), max(rates.values())
        if hi - lo > _STATED_RTOL * hi:
            shown = ", ".join(f"{k} {v:.9g} Hz" for k, v in rates.items())
            raise FileFormatError(f"{where}: the channels are sampled at different rates ({shown})")
        return hi
    for what, props in chain:
        r = _stated_rate(props, where, what)
        if r is not None:
            return r
    return None


def _group_header(group: _Group, picked: Mapping[str, _Channel], where: str) -> dict[str, Any]:
    """The header this library wrote (HEADER_KEY), or one made of a lab group's properties and units."""
    if HEADER_KEY in group.props:
        text = _plain(group.props[HEADER_KEY])
        if not isinstance(text, str):
            raise FileFormatError(f"{where}: property {HEADER_KEY!r} must be a JSON string")
        head = _parse_json(text, where, f"property {HEADER_KEY!r}")
        if not isinstance(head, dict):
            raise FileFormatError(
                f"{where}: property {HEADER_KEY!r} must hold a JSON object, not {type(head).__name__}"
            )
        return head
    head = {}
    for key, raw in group.props.items():
        value = _plain(raw)
        if value is None or (key in RESERVED_KEYS and key not in _LAB_HEADER_KEYS):
            continue
        if key in STEP_ATTRS or key in RATE_ATTRS:
            continue
        try:
            check_metadata_key(key)
        except InvalidParameterError:
            continue  # a property name no header line can carry: not kept
        head[key] = value
    units = {}
    for role in ("u", "y"):
        ch = picked.get(role)
        unit = next((_plain(ch.props[k]) for k in UNIT_ATTRS if ch and k in ch.props), None)
        if isinstance(unit, str) and unit:
            units[role] = unit
    if units:
        head["units"] = units
    start = picked["u"].props.get("wf_start_time") if "u" in picked else None
    if start is not None and _plain(start) is not None and "start_time" not in head:
        head["start_time"] = str(_plain(start))
    return head


def _container_item(
    group: _Group,
    picked: Mapping[str, _Channel],
    chain: Sequence[tuple[str, Mapping[str, Any]]],
    where: str,
    default_name: str,
    rate: Optional[float],
    what: str,
) -> Item:
    """One experiment from the channels ``picked`` (role -> channel); :func:`_check_file_budget` has
    checked their declared sizes before any is read."""
    arrays = {}
    for role, ch in picked.items():
        try:
            raw = ch.read()
        except BoucWenIdError:
            raise
        except Exception as exc:  # noqa: BLE001 - any decoder failure of an untrusted file is a format error
            raise FileFormatError(
                f"{where}: {what} {ch.path!r} cannot be read ({type(exc).__name__}: {exc})"
            ) from exc
        arrays[role] = _array(where, ch.path, raw)
    head = _group_header(group, picked, where)
    stated = _file_rate(picked, [(f"group {group.path!r}:", group.props), *chain], where)
    if stated is not None and head.get("sample_rate") is None:
        head["sample_rate"] = stated
    if "t" not in arrays and head.get("sample_rate") is None and rate is None:
        raise FileFormatError(
            f"{where}: no sample rate: no time {what} 't' and no attribute "
            f"{', '.join(map(repr, RATE_ATTRS + STEP_ATTRS))} on the channels, their group or the file; "
            f"map a time {what} with columns={{'t': ...}} or pass sample_rate= (Hz)"
        )
    sources = {role: ch.name for role, ch in picked.items() if ch.name != role}
    return _build(head, arrays, where, default_name=default_name, sample_rate=rate, sources=sources)


@dataclass(frozen=True)
class _Plan:
    """One experiment to read: its group, the channels by role, where it is named, its default name."""

    group: _Group
    picked: Mapping[str, _Channel]
    at: str
    name: str


def _check_file_budget(plans: Sequence[_Plan], where: str, what: str) -> None:
    """The memory budget of the whole file, from the sizes its channels declare, before any is read.

    Per file, not per experiment: a small file of many groups whose channels declare huge sizes (or one
    channel reached from many groups) is refused as a whole.
    """
    total = 0
    for plan in plans:
        for ch in plan.picked.values():
            _budget.check_samples(f"{plan.at}: {what} {ch.path!r}", ch.size)
            total += ch.size
    _budget.check_bytes(f"{where}: the signals of its {len(plans)} experiment(s)", 8 * total)


def _pinned_plan(
    groups: Sequence[_Group],
    pinned: Mapping[str, str],
    cols: Mapping[str, Union[str, int]],
    where: str,
    stem: str,
    what: str,
    listing: str,
) -> _Plan:
    """The one experiment that ``group/channel`` paths in ``cols`` pin."""
    by_path = {ch.path: (g, ch) for g in groups for ch in g.channels.values()}
    chosen = {}
    for role, path in pinned.items():
        if path not in by_path:
            raise FileFormatError(f"{where}: no {what} {path!r} (for {role!r}); the file has {listing}")
        chosen[role] = by_path[path]
    home = (chosen["u"] if "u" in chosen else next(iter(chosen.values())))[0]
    at = f"{where}, group {home.path!r}" if home.path else where
    rest = {role: col for role, col in cols.items() if role not in pinned}
    names = list(home.channels)
    picked = {role: home.channels[names[j]] for role, j in _pick(names, rest, at, what).items()}
    picked = {r: c for r, c in picked.items() if c.path not in pinned.values()}
    picked.update({role: ch for role, (_, ch) in chosen.items()})
    return _Plan(home, picked, at, home.path.split("/")[-1] or stem)


def _group_plans(
    groups: Sequence[_Group], cols: Mapping[str, Union[str, int]], where: str, stem: str, what: str
) -> list[_Plan]:
    """One experiment per group holding the ``u`` and ``y`` channels (their names or those ``cols`` maps)."""
    plans = []
    for g in groups:
        names = list(g.channels)
        if not any(cols.get(role, role) in g.channels for role in ("u", "y")):
            continue  # a group of other channels (settings, temperatures, ...)
        at = f"{where}, group {g.path!r}" if g.path else where
        for role in ("u", "y"):
            if cols.get(role, role) not in g.channels:
                raise FileFormatError(
                    f"{at}: no {what} {cols.get(role, role)!r} (for {role!r}); the group has "
                    f"{', '.join(map(repr, names))}; map yours with columns={{{role!r}: ...}}"
                )
        picked = {role: g.channels[names[j]] for role, j in _pick(names, cols, at, what).items()}
        plans.append(_Plan(g, picked, at, g.path.split("/")[-1] or stem))
    return plans


def _container_items(
    groups: Sequence[_Group],
    root: Mapping[str, Any],
    cols: Mapping[str, Union[str, int]],
    where: str,
    stem: str,
    rate: Optional[float],
    what: str,
) -> list[Item]:
    """The experiments of a TDMS or HDF5 file: one per group holding the ``u`` and ``y`` channels (their
    own names or those ``cols`` maps), or the one that ``cols`` pins with ``group/channel`` paths."""
    for role, col in cols.items():
        if isinstance(col, int):
            raise FileFormatError(
                f"{where}: columns[{role!r}] = {col}: column indices apply to CSV files; name the {what} "
                f"(or 'group/{what}')"
            )
    listing = "; ".join(
        f"{g.path or '/'}: {', '.join(map(repr, g.channels)) or 'no ' + what + 's'}" for g in groups
    )
    # A "/" pins a group, unless the whole name is a channel's (e.g. a channel called "Force/kN").
    names_anywhere = {name for g in groups for name in g.channels}
    pinned = {
        role: str(col).strip("/")
        for role, col in cols.items()
        if "/" in str(col) and str(col) not in names_anywhere
    }
    if pinned:
        plans = [_pinned_plan(groups, pinned, cols, where, stem, what, listing)]
    else:
        plans = _group_plans(groups, cols, where, stem, what)
    if not plans:
        u, y = cols.get("u", "u"), cols.get("y", "y")
        raise FileFormatError(
            f"{where}: no group holds the {what}s {u!r} (u) and {y!r} (y); the file has "
            f"{listing or 'nothing'}; "
            f"map yours with columns={{'u': ..., 'y': ...}} ({what} names, or 'group/{what}' paths)"
        )
    _check_file_budget(plans, where, what)
    chain = [("the file's", root)]
    return [_container_item(p.group, p.picked, chain, p.at, p.name, rate, what) for p in plans]
