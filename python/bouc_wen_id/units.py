"""Units of experiments joined into one data set: they must agree, quantity by quantity.

Each file (or :class:`~bouc_wen_id.measurement.Measurement`) states the units of its input ``u`` and output
``y`` (``Displacement (mm)``, ``force_kN``: :mod:`bouc_wen_id.io`).  A joint fit (``load`` of several files,
``identify``, ``diagnose``, ``diagnose_across``, the command line) treats every experiment as one unit per
quantity; one file in ``m`` beside others in ``mm`` would be fitted 1000x off and every term on ``u`` would
take a wrong value or a wrong name.  :func:`harmonise` therefore

* **converts** a later experiment to the unit the *first* one states when a known scale relates the two:
  SI prefixes of one base (``m``/``mm``/``um``, ``N``/``kN``/``mN``, ``V``/``mV``, ``A``/``mA``, ``s``/``ms``,
  ``Pa``/``kPa``, ...) and the imperial units the readers recognise (``in``, ``ft`` to ``m``; ``lbf``,
  ``lb``, ``kip`` to ``N``; ``psi`` to ``Pa``; ``deg`` to ``rad``).  The arrays are new ones (nothing the
  user gave is modified); a :class:`~bouc_wen_id.errors.UnitWarning` says so once and the result's notes
  repeat it ("converted the input u from m to mm (x 1000) in exp3.csv, exp4.csv");
* **refuses** two units no known scale relates (``mm`` beside ``N``; two different unit strings it does
  not know) with :class:`~bouc_wen_id.errors.UnitMismatchError`, naming both experiments and units;
* **assumes** an experiment that states no unit for a quantity is in the unit the others state: the
  result's notes say so (it cannot be checked), without a warning (simulated recordings and arrays built
  in Python carry no units and often sit beside lab files in the right ones).

A converted Measurement carries the conversion in its metadata (``units_converted``: ``"u: m -> mm"``), so
that ``diagnose`` of experiments ``load`` already converted names the conversion in its notes without
warning twice.  Time is always in seconds (a Measurement refuses another unit for ``t``); a file's time column
in another unit was converted on reading (:mod:`bouc_wen_id.timeunits`), and the notes say so.  A fitted
model carries the units it was fitted in (:func:`against_model`: new recordings are converted to them).
"""

from __future__ import annotations

import json
import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Optional

from ._timehint import time_scale
from .errors import UnitMismatchError, UnitWarning

__all__ = [
    "Against",
    "Joined",
    "against_model",
    "harmonise",
    "harmonise_groups",
    "model_units",
    "scale_between",
    "units_of",
]

#: The quantities whose units must agree (``t`` is always seconds).
QUANTITIES = {"u": "the input u", "y": "the output y"}
#: Metadata key of a converted experiment: ``"u: m -> mm; y: kN -> N"``.
MARK = "units_converted"
#: Base units and what they measure (for the message when two units measure different things).
_BASES = {
    "m": "a length",
    "N": "a force",
    "s": "a time",
    "g": "a mass",
    "Pa": "a pressure",
    "V": "a voltage",
    "A": "a current",
    "W": "a power",
    "J": "an energy",
    "Hz": "a frequency",
    "rad": "an angle",
    "K": "a temperature",
}
_PREFIXES = {
    "": 1.0,
    "p": 1e-12,
    "n": 1e-9,
    "u": 1e-6,
    "\u00b5": 1e-6,
    "\u03bc": 1e-6,
    "m": 1e-3,
    "c": 1e-2,
    "k": 1e3,
    "M": 1e6,
    "G": 1e9,
}
#: Other units the readers recognise, as (base, factor to the base).
_OTHER = {
    "in": ("m", 0.0254),
    "inch": ("m", 0.0254),
    "ft": ("m", 0.3048),
    "micron": ("m", 1e-6),
    "lbf": ("N", 4.4482216152605),
    "lb": ("N", 4.4482216152605),
    "kip": ("N", 4448.2216152605),
    "psi": ("Pa", 6894.757293168361),
    "deg": ("rad", math.pi / 180.0),
    "sec": ("s", 1.0),
}


def parse(unit: str) -> Optional[tuple[str, float]]:
    """``(base, factor)`` with ``1 unit = factor base`` (``"mm"`` -> ``("m", 1e-3)``); None when unknown.

    Case as written: ``mN`` is a milli-newton, ``MN`` a mega-newton."""
    text = unit.strip()
    if text in _OTHER:
        return _OTHER[text]
    for base in sorted(_BASES, key=len, reverse=True):
        if text.endswith(base) and text[: len(text) - len(base)] in _PREFIXES:
            return base, _PREFIXES[text[: len(text) - len(base)]]
    return None


def scale_between(src: str, dst: str) -> Optional[float]:
    """The factor that turns a value in ``src`` into one in ``dst`` (None: no known scale relates them)."""
    if src.strip() == dst.strip():
        return 1.0
    a, b = parse(src), parse(dst)
    if a is None or b is None or a[0] != b[0]:
        return None
    return a[1] / b[1]


def units_of(item: Any) -> dict[str, str]:
    """The units an experiment states for ``u`` and ``y`` (a Measurement's ``units``, a Recording's
    ``metadata["units"]`` JSON object; nothing for an AveragedPeriod)."""
    units = getattr(item, "units", None)
    if units is None:
        text = getattr(item, "metadata", {}).get("units")
        try:
            units = json.loads(text) if isinstance(text, str) else None
        except ValueError:
            units = None
    if not isinstance(units, dict):
        return {}
    return {q: str(v).strip() for q, v in units.items() if q in QUANTITIES and str(v).strip()}


def label_of(item: Any, index: int) -> str:
    """How an experiment is named in a message: its name (a file's stem), its source, or its place."""
    for name in (
        getattr(item, "name", ""),
        getattr(item, "source", ""),
        getattr(item, "metadata", {}).get("name"),
    ):
        if isinstance(name, str) and name:
            return name
    return f"experiment {index}"


def _marks(item: Any) -> list[tuple[str, str, str]]:
    """The conversions an experiment's metadata records: ``(quantity, from, to)``."""
    text = getattr(item, "metadata", {}).get(MARK, "")
    out = []
    for part in str(text).split(";"):
        q, _, rest = part.partition(":")
        src, _, dst = rest.partition("->")
        if q.strip() in QUANTITIES and src.strip() and dst.strip():
            out.append((q.strip(), src.strip(), dst.strip()))
    return out


def _why(ru: str, ou: str) -> str:
    """Why no known scale relates the units ``ru`` and ``ou``."""
    known = [parse(ru), parse(ou)]
    if all(known) and known[0] is not None and known[1] is not None:
        return f"{ru!r} is {_BASES[known[0][0]]}, {ou!r} {_BASES[known[1][0]]}"
    unknown = " and ".join(repr(u) for u, k in ((ru, known[0]), (ou, known[1])) if k is None)
    verb = "is not a unit" if " and " not in unknown else "are not units"
    return (
        f"{unknown} {verb} this library converts "
        "(SI prefixes of m, N, s, g, Pa, V, A, W, J, Hz, rad, K; in, ft, lbf, kip, psi, deg)"
    )


def _mismatch(q: str, ref: tuple[str, str], other: tuple[str, str]) -> UnitMismatchError:
    (rl, ru), (ol, ou) = ref, other
    why = _why(ru, ou)
    return UnitMismatchError(
        f"{QUANTITIES[q]} is in {ru!r} in {rl} but in {ou!r} in {ol}, and no known scale relates them "
        f"({why}): one data set needs one unit per quantity. Correct the unit in the column name or "
        f"header of the wrong file, convert {ol} to {ru!r} yourself (e.g. Measurement.scaled({q}=<factor>, "
        f"units={{{q!r}: {ru!r}}})), or fit the files apart"
    )


def _converted(item: Any, factors: dict[str, float], new: dict[str, str], mark: str) -> Any:
    """A copy of ``item`` with ``u``, ``y`` multiplied by ``factors`` and its units set to ``new``."""
    from .measurement import Measurement
    from .model import Recording

    old = getattr(item, "metadata", {}).get(MARK, "")
    meta = {**item.metadata, MARK: f"{old}; {mark}" if old else mark}
    fu, fy = factors.get("u", 1.0), factors.get("y", 1.0)
    if isinstance(item, Measurement):
        scaled = item.scaled(u=fu, y=fy, units=new)
        return Measurement(
            scaled.t,
            scaled.u,
            scaled.y,
            nominal_frequency=scaled.nominal_frequency,
            units=scaled.units,
            channels=scaled.channels,
            name=scaled.name,
            metadata=meta,
        )
    assert isinstance(item, Recording)
    units = {**units_of(item), **new}
    meta["units"] = json.dumps(units)
    # The simulated inner signals and the true plant are in the old units: left out of the copy.
    return Recording(
        item.t,
        item.u * fu,
        item.y * fy,
        item.amplitude * fu,
        item.frequency,
        item.settle_periods,
        metadata=meta,
    )


@dataclass(frozen=True)
class Joined:
    """Experiments in one unit per quantity: the items (converted copies where needed), what was done
    (one line per conversion or assumption, for the result's notes) and the units (the first stated)."""

    items: list[Any]
    notes: tuple[str, ...]
    units: dict[str, str]


def harmonise(
    items: Sequence[Any], labels: Optional[Sequence[str]] = None, *, warn: bool = True, stacklevel: int = 3
) -> Joined:
    """The experiments in the units of the first that states each quantity's unit (module docstring).

    ``labels`` name the experiments in messages (default: :func:`label_of`).  Warns (``UnitWarning``, at
    ``stacklevel``) once for every conversion made here (not for those the metadata records as made
    before); an experiment without units is only noted.

    Raises
    ------
    UnitMismatchError
        Two experiments state units of one quantity that no known scale relates.
    """
    items = list(items)
    labs = list(labels) if labels is not None else [label_of(x, i) for i, x in enumerate(items)]
    stated = [units_of(x) for x in items]
    factors: list[dict[str, float]] = [{} for _ in items]
    new: list[dict[str, str]] = [{} for _ in items]
    done: dict[tuple[str, str, str], list[str]] = {}  # (quantity, from, to) -> the experiments converted
    fresh: set[tuple[str, str, str]] = set()
    assumed: dict[tuple[str, str, str], list[str]] = {}  # (quantity, unit, its source) -> without a unit
    units: dict[str, str] = {}
    refs: dict[str, str] = {}  # quantity -> the experiment whose unit the others take
    for q in QUANTITIES:
        ref = next(((labs[i], s[q]) for i, s in enumerate(stated) if q in s), None)
        if ref is None:
            continue
        refs[q], units[q] = ref
        for i, s in enumerate(stated):
            if q not in s:
                assumed.setdefault((q, ref[1], ref[0]), []).append(labs[i])
            elif s[q] != ref[1]:
                f = scale_between(s[q], ref[1])
                if f is None:
                    raise _mismatch(q, ref, (labs[i], s[q]))
                factors[i][q], new[i][q] = f, ref[1]
                done.setdefault((q, s[q], ref[1]), []).append(labs[i])
                fresh.add((q, s[q], ref[1]))
    out = []
    for i, x in enumerate(items):
        for key in _marks(x):
            if key[0] in units and key[2] == units[key[0]] and labs[i] not in done.get(key, []):
                done.setdefault(key, []).append(labs[i])
        mark = "; ".join(f"{q}: {src} -> {dst}" for (q, src, dst), who in done.items() if labs[i] in who)
        out.append(_converted(x, factors[i], new[i], mark) if new[i] else x)
    notes = []
    for (q, src, dst), who in done.items():
        f = scale_between(src, dst)
        notes.append(
            f"converted {QUANTITIES[q]} from {src} to {dst} (x {f:.6g}) in {', '.join(who)} (the unit of "
            f"{refs[q]})"
        )
        if warn and (q, src, dst) in fresh:
            warnings.warn(notes[-1], UnitWarning, stacklevel=stacklevel)
    notes += [n for n in (note_of(x, labs[i]) for i, x in enumerate(items)) if n]
    for (q, unit, src), who in assumed.items():
        notes.append(
            f"{', '.join(who)} state{'s' if len(who) == 1 else ''} no unit for {QUANTITIES[q]}: taken to be "
            f"{unit} as in {src}"
        )
    return Joined(out, tuple(notes), units)


def harmonise_groups(
    groups: Sequence[Sequence[Any]], *, fixed: bool = False, warn: bool = True
) -> tuple[list[list[Any]], Joined]:
    """:func:`harmonise` over several sets at once (``diagnose_across``: one unit across the conditions).

    ``fixed``: the sets were already fitted as they are (``per_condition`` diagnoses), so a conversion
    would leave those fits in the old units: refused with :class:`UnitMismatchError`."""
    flat = [x for g in groups for x in g]
    joined = harmonise(flat, warn=warn)
    if fixed and any(a is not b for a, b in zip(flat, joined.items)):
        raise UnitMismatchError(
            "the conditions state different units (" + "; ".join(joined.notes) + ") and per_condition "
            "diagnoses were fitted in the old ones: convert the groups first (bouc_wen_id.units."
            "harmonise_groups(groups)[0]) and diagnose them again, or leave out per_condition"
        )
    out, at = [], 0
    for g in groups:
        out.append(joined.items[at : at + len(g)])
        at += len(g)
    return out, joined


@dataclass(frozen=True)
class Against:
    """A record set beside the model it meets: the factors that put its ``u`` and ``y`` in the model's
    units (absent: 1), what was done or assumed (notes), and the units the comparison is in."""

    factors: dict[str, float]
    notes: tuple[str, ...]
    units: dict[str, str]


def model_units(model: Any) -> dict[str, str]:
    """The units a fitted model states: a plant's ``units``, a fit's (``TimeDomainFit.plant``,
    ``IdentificationResult.units``); empty when it states none (a model saved before models carried
    units, or built in Python without them)."""
    for holder in (model, getattr(model, "plant", None)):
        units = getattr(holder, "units", None)
        if isinstance(units, dict) and units:
            return {q: str(v).strip() for q, v in units.items() if q in QUANTITIES and str(v).strip()}
    return {}


def against_model(model: Any, data: Any, label: str, *, warn: bool = True, stacklevel: int = 3) -> Against:
    """A record (``data``: its units, or anything :func:`units_of` reads) checked against the units the
    ``model`` was fitted in (:func:`model_units`, or a units mapping).

    * the same unit, or the record states none for a quantity (noted: it cannot be checked): nothing done;
    * another unit of the same quantity (``m`` for the model's ``mm``): factors to the model's unit, with a
      :class:`~bouc_wen_id.errors.UnitWarning` naming the record and both units;
    * the model states no units (an older saved model): the record is taken to be in the model's units,
      noted as unchecked.

    Raises
    ------
    UnitMismatchError
        A unit no known scale relates to the model's (``N`` for the model's ``mm``), naming the record and
        both units.
    """
    have = (
        model_units(model)
        if not isinstance(model, dict)
        else {q: str(v).strip() for q, v in model.items() if q in QUANTITIES and str(v).strip()}
    )
    given = (
        units_of(data)
        if not isinstance(data, dict)
        else {q: str(v).strip() for q, v in data.items() if q in QUANTITIES and str(v).strip()}
    )
    shown = ", ".join(f"{q} in {v}" for q, v in given.items())
    if not have:
        notes = (
            (
                f"the model states no units (saved before models carried them, or built without them): "
                f"{label} ({shown}) is taken to be in the model's units, which cannot be checked",
            )
            if given
            else ()
        )
        return Against({}, notes, dict(given))
    factors: dict[str, float] = {}
    notes_l: list[str] = []
    for q, unit in have.items():
        if q not in given:
            notes_l.append(f"{label} states no unit for {QUANTITIES[q]}: taken to be the model's {unit}")
            continue
        f = scale_between(given[q], unit)
        if f is None:
            raise UnitMismatchError(
                f"{label}: {QUANTITIES[q]} is in {given[q]!r} but the model was fitted in {unit!r}, and no "
                f"known scale relates them ({_why(unit, given[q])}): its parameters hold only in "
                f"{unit!r}. Correct the unit in the record's column name or header, convert the record to "
                f"{unit!r}, or use a model fitted in {given[q]!r}"
            )
        if given[q] != unit:
            factors[q] = f
            notes_l.append(
                f"converted {QUANTITIES[q]} of {label} from {given[q]} to the model's {unit} (x {f:.6g})"
            )
            if warn:
                warnings.warn(notes_l[-1], UnitWarning, stacklevel=stacklevel)
    return Against(factors, tuple(notes_l), {**given, **have})


def note_of(item: Any, label: str) -> Optional[str]:
    """The note of a time axis converted on reading (``"t: ms -> s"`` in the metadata), or None."""
    meta = getattr(item, "metadata", {})
    text = meta.get(MARK, "") if isinstance(meta, Mapping) else ""
    for part in str(text).split(";"):
        q, _, rest = part.partition(":")
        src, _, dst = rest.partition("->")
        if q.strip() == "t" and src.strip():
            scale = time_scale(src.strip())
            return f"read the time column of {label} in {src.strip()} as seconds (x {scale:g})"
    return None
