"""The model as JSON with a schema version, read back exactly by :func:`load_model`.

Document (schema version 1)::

    {"format": "bouc_wen_id.model", "version": 1,
     "plant": {"linear": {"num": [...], "den": [...], "delay": s},
               "hysteresis": {"alpha": .., "beta": .., "gamma": .., "mu": .., "w0": ..},
               "terms": [{"kind": code name, <symbol>: value, ...}, ...]},
     "units": {"u": "mm", "y": "N"},
     "metadata": {free-form strings}}

``units`` (optional) are those the model was fitted in (``WienerPlant.units``): written when the plant
states them, read back onto the plant, so that ``validate`` converts or refuses records in other units.  A
document without them (written before models carried units) still loads, as a plant without units; validating
it notes that the records' units cannot be checked.

Numbers are written by Python's ``json`` (``repr``: the shortest decimal that reads back to the same
double), so a model read back is the model written, bit for bit. Every term of the registry may be written,
including those the time-domain simulator does not simulate (a term on x): the file holds the model, not a
simulation of it.  Reading is strict: an unknown version, a missing or unknown field, a field of the wrong
type is :class:`FileFormatError` naming the field; a well-formed file with an inadmissible value (an unstable
G, beta + gamma <= 0) keeps the model's own error.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import fields
from typing import Any, Optional, Union

from ..errors import FileFormatError, InvalidParameterError
from ..model import BoucWen, TransferFunction, WienerPlant
from ..terms import TERMS

__all__ = ["MODEL_FORMAT", "MODEL_VERSION", "model_to_json", "model_from_json", "save_model", "load_model"]

#: The ``format`` field of a model document.
MODEL_FORMAT = "bouc_wen_id.model"
#: The schema version this library writes and reads.
MODEL_VERSION = 1

_LINEAR = {"num", "den", "delay"}
_HYSTERESIS = {"alpha", "beta", "gamma", "mu", "w0"}


def model_to_json(plant: Any, *, metadata: Optional[Mapping[str, str]] = None, indent: int = 2) -> str:
    """``plant`` as a JSON document (module docstring); ``metadata`` free-form strings (provenance).

    ``plant``: a WienerPlant, or a fit holding one (``TimeDomainFit``: its ``plant``, with the units it
    was fitted in)."""
    if not isinstance(plant, WienerPlant) and isinstance(getattr(plant, "plant", None), WienerPlant):
        plant = plant.plant
    if not isinstance(plant, WienerPlant):
        raise InvalidParameterError(f"model_to_json needs a WienerPlant, got {type(plant).__name__}")
    meta = dict(metadata or {})
    bad = [k for k, v in meta.items() if not isinstance(k, str) or not isinstance(v, str)]
    if bad:
        raise InvalidParameterError(f"metadata must map strings to strings; not so for {bad}")
    doc = {
        "format": MODEL_FORMAT,
        "version": MODEL_VERSION,
        "plant": {
            "linear": plant.linear.to_dict(),
            "hysteresis": plant.hysteresis.to_dict(),
            "terms": [t.to_dict() for t in plant.terms],
        },
        "metadata": meta,
    }
    if plant.units:
        doc["units"] = dict(plant.units)
    return json.dumps(doc, indent=indent, allow_nan=False)


def _fields(where: str, d: Any, required: set[str], optional: frozenset[str] = frozenset()) -> dict[str, Any]:
    if not isinstance(d, Mapping):
        raise FileFormatError(f"{where} must be a JSON object, got {type(d).__name__}")
    missing = sorted(required - set(d))
    unknown = sorted(set(d) - required - optional)
    if missing:
        raise FileFormatError(f"{where}: missing field(s) {missing}")
    if unknown:
        raise FileFormatError(f"{where}: unknown field(s) {unknown}; expected {sorted(required | optional)}")
    return dict(d)


def _number(where: str, v: Any) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise FileFormatError(f"{where} must be a number, got {type(v).__name__}")
    return float(v)


def _numbers(where: str, v: Any) -> list[float]:
    if not isinstance(v, list) or not v:
        raise FileFormatError(f"{where} must be a non-empty list of numbers")
    return [_number(f"{where}[{i}]", x) for i, x in enumerate(v)]


def _plant(d: Any) -> WienerPlant:
    p = _fields("plant", d, {"linear", "hysteresis"}, frozenset({"terms"}))
    lin = _fields("plant.linear", p["linear"], _LINEAR)
    hys = _fields("plant.hysteresis", p["hysteresis"], _HYSTERESIS)
    g = TransferFunction(
        _numbers("plant.linear.num", lin["num"]),
        _numbers("plant.linear.den", lin["den"]),
        _number("plant.linear.delay", lin["delay"]),
    )
    vals = {k: _number(f"plant.hysteresis.{k}", hys[k]) for k in sorted(_HYSTERESIS)}
    h = BoucWen(vals["beta"], vals["gamma"], vals["mu"], vals["alpha"], vals["w0"])
    raw_terms = p.get("terms", [])
    if not isinstance(raw_terms, list):
        raise FileFormatError("plant.terms must be a list of term objects")
    terms = []
    for i, t in enumerate(raw_terms):
        where = f"plant.terms[{i}]"
        if not isinstance(t, Mapping) or t.get("kind") not in TERMS:
            kind = t.get("kind") if isinstance(t, Mapping) else None
            raise FileFormatError(f"{where}: unknown term kind {kind!r}; the terms are {', '.join(TERMS)}")
        cls = TERMS[str(t["kind"])]
        names = {f.name for f in fields(cls)}
        body = _fields(f"{where} ({cls.kind})", t, {"kind", cls.symbol}, frozenset(names))
        terms.append(cls(**{k: _number(f"{where}.{k}", v) for k, v in body.items() if k != "kind"}))
    return WienerPlant(g, h, tuple(terms))


def model_from_json(text: Union[str, bytes]) -> WienerPlant:
    """The plant of a model document (:func:`model_to_json`).

    Raises
    ------
    FileFormatError
        Not JSON, not a model document, an unknown ``version``, a missing, unknown or mistyped field.
    InvalidParameterError, UnstableSystemError, ImproperTransferFunctionError
        A well-formed document whose values the model refuses.
    """
    try:
        doc = json.loads(text)
    except (ValueError, TypeError) as exc:
        raise FileFormatError(f"not a JSON document: {exc}") from None
    if not isinstance(doc, Mapping) or doc.get("format") != MODEL_FORMAT:
        from .._diagnosis_json import HINT, looks_like

        got = doc.get("format") if isinstance(doc, Mapping) else type(doc).__name__
        said = f"; {HINT}" if looks_like(doc) else ""
        raise FileFormatError(
            f"not a bouc_wen_id model document: format {got!r}, expected {MODEL_FORMAT!r}{said}"
        )
    version = doc.get("version")
    if isinstance(version, bool) or version != MODEL_VERSION:
        raise FileFormatError(
            f"model schema version {version!r} is not known to this library (it reads version "
            f"{MODEL_VERSION}); upgrade bouc_wen_id or write the model with the version it knows"
        )
    top = _fields("the document", doc, {"format", "version", "plant"}, frozenset({"metadata", "units"}))
    meta = top.get("metadata", {})
    if not isinstance(meta, Mapping) or not all(isinstance(v, str) for v in meta.values()):
        raise FileFormatError("metadata must be a JSON object of strings")
    units = top.get("units", {})
    if (
        not isinstance(units, Mapping)
        or not set(units) <= {"u", "y"}
        or not all(isinstance(v, str) for v in units.values())
    ):
        raise FileFormatError('units must be a JSON object of strings keyed "u" and "y", e.g. {"u": "mm"}')
    plant = _plant(top["plant"])
    return plant.with_units(units) if units else plant


def save_model(
    plant: Any, path: Union[str, os.PathLike[str]], *, metadata: Optional[Mapping[str, str]] = None
) -> None:
    """Write ``plant`` (a WienerPlant, or a fit holding one) to ``path`` as a model document (UTF-8 JSON),
    with the units it was fitted in."""
    text = model_to_json(plant, metadata=metadata)
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text + "\n")


def load_model(path: Union[str, os.PathLike[str]]) -> WienerPlant:
    """The plant saved in ``path`` by :func:`save_model` (or any model document); errors as
    :func:`model_from_json`, with the file named."""
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except OSError as exc:
        raise FileFormatError(f"{os.fspath(path)}: cannot read the model: {exc.strerror or exc}") from None
    try:
        return model_from_json(text)
    except FileFormatError as exc:
        raise FileFormatError(f"{os.fspath(path)}: {exc}") from None
