"""A diagnosis read back from its JSON (``Diagnosis.to_json``, the CLI's ``diagnosis.json``; review 35).

A diagnosis could be written (``to_json``/``to_dict``, ``diagnose --out``) but not read: comparing two
diagnoses (current levels, preprocessing variants) meant parsing the JSON by hand, and ``load``,
``load_model`` and ``export`` refused the file without naming a reader. :func:`load_diagnosis` reads it into
a :class:`SavedDiagnosis`: the verdict, headline, status (as stored and as printed), readings, the named and
partial terms with their values and standard errors, the plain and the final model's statistics, typed as on
a :class:`~.result.Diagnosis`; what the JSON holds beyond them (the selection steps, alternatives, where the
models miss, the experiments' digests, detection limits) as the dictionaries it holds. The fitted models and
the experiments' data are not in the JSON: a saved diagnosis cannot be refitted or re-reported, and it holds
no G (nothing to export: ``fit_time_domain`` with the named terms builds a model).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Union

from .._diagnosis_json import HINT, KEYS, looks_like
from ..errors import FileFormatError
from ..export._json import MODEL_FORMAT
from .readings import Reading
from .result import ModelSummary, NamedTerm, clean, status_text
from .verdict_text import details, headline

__all__ = ["HINT", "SavedDiagnosis", "load_diagnosis", "looks_like"]

#: Largest file read (a diagnosis JSON of a hundred experiments is well under 10 MB).
MAX_BYTES = 200_000_000


def _num(v: Any, what: str) -> float:
    if v is None:
        return math.nan  # to_json writes non-finite values as null
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise FileFormatError(f"diagnosis JSON: {what} must be a number or null, got {v!r}")
    return float(v)


def _term(d: Any) -> NamedTerm:
    if not isinstance(d, Mapping) or not isinstance(d.get("term"), str):
        raise FileFormatError(f"diagnosis JSON: a named term must be an object with 'term', got {d!r}")
    t = str(d["term"])
    return NamedTerm(
        t,
        str(d.get("symbol", "")),
        _num(d.get("value"), f"{t}'s value"),
        _num(d.get("standard_error"), f"{t}'s standard_error"),
        str(d.get("unit", "")),
    )


def _terms(v: Any, what: str) -> tuple[NamedTerm, ...]:
    if not isinstance(v, list):
        raise FileFormatError(f"diagnosis JSON: {what} must be a list, got {type(v).__name__}")
    return tuple(_term(x) for x in v)


def _model(d: Any, what: str) -> ModelSummary:
    if not isinstance(d, Mapping):
        raise FileFormatError(f"diagnosis JSON: {what} must be an object, got {type(d).__name__}")
    dof = d.get("dof")
    return ModelSummary(
        terms=_terms(d.get("terms", []), f"{what}.terms"),
        beta=_num(d.get("beta"), f"{what}.beta"),
        gamma=_num(d.get("gamma"), f"{what}.gamma"),
        mu=_num(d.get("mu"), f"{what}.mu"),
        cost=_num(d.get("cost"), f"{what}.cost"),
        dof=int(dof) if isinstance(dof, int) and not isinstance(dof, bool) else 0,
        p_value=_num(d.get("p_value"), f"{what}.p_value"),
        nrmse=tuple(_num(v, f"{what}.nrmse") for v in d.get("nrmse", []) or []),
        outputs=(),  # not in the JSON
    )


def _reading(d: Any) -> Reading:
    if (
        not isinstance(d, Mapping)
        or not isinstance(d.get("kind"), str)
        or not isinstance(d.get("words"), str)
    ):
        raise FileFormatError(
            f"diagnosis JSON: a reading must be an object with 'kind' and 'words', got {d!r}"
        )
    return Reading(d["kind"], d["words"], bool(d.get("rival", True)))


@dataclass(frozen=True, eq=False)
class SavedDiagnosis:
    """A diagnosis as its JSON holds it (module docstring): the same names as on a
    :class:`~.result.Diagnosis` for what the JSON keeps typed; ``document`` is the whole JSON object."""

    status: str
    verdict: str
    named: tuple[NamedTerm, ...]
    partial: tuple[NamedTerm, ...]
    readings: tuple[Reading, ...]
    plain: ModelSummary
    final: ModelSummary
    explained_fraction: float
    settings: dict[str, Any]
    notes: tuple[str, ...]
    seconds: float
    document: dict[str, Any] = field(repr=False)
    #: The file it was read from ("" when read from text).
    source: str = ""

    @classmethod
    def from_dict(cls, doc: Mapping[str, Any], source: str = "") -> SavedDiagnosis:
        """From ``Diagnosis.to_dict()`` (or its JSON parsed); :class:`FileFormatError` when it is none."""
        if not looks_like(doc):
            missing = [k for k in KEYS if not isinstance(doc, Mapping) or k not in doc]
            raise FileFormatError(
                f"{source or 'document'}: not a diagnosis JSON (missing {', '.join(missing)})"
                if isinstance(doc, Mapping)
                else f"{source or 'document'}: not a diagnosis JSON (a {type(doc).__name__}, not an object)"
            )
        if doc["status"] not in ("adequate", "explained", "partly explained", "unexplained"):
            raise FileFormatError(f"diagnosis JSON: unknown status {doc['status']!r}")
        if not isinstance(doc["verdict"], str):
            raise FileFormatError("diagnosis JSON: the verdict must be a string")
        settings = doc.get("settings") or {}
        return cls(
            status=str(doc["status"]),
            verdict=doc["verdict"],
            named=_terms(doc["named"], "named"),
            partial=_terms(doc["partial"], "partial"),
            readings=tuple(_reading(r) for r in doc.get("readings", []) or []),
            plain=_model(doc["plain"], "plain"),
            final=_model(doc["final"], "final"),
            explained_fraction=_num(doc["explained_fraction"], "explained_fraction"),
            settings=dict(settings) if isinstance(settings, Mapping) else {},
            notes=tuple(str(n) for n in doc.get("notes", []) or []),
            seconds=_num(doc.get("seconds"), "seconds"),
            document=json.loads(json.dumps(clean(dict(doc)))),  # a copy: nothing the caller gave is kept
            source=source,
        )

    @classmethod
    def from_json(cls, text: str, source: str = "") -> SavedDiagnosis:
        """From the text ``Diagnosis.to_json()`` wrote."""
        try:
            doc = json.loads(text)
        except ValueError as exc:
            raise FileFormatError(f"{source or 'text'}: not JSON ({exc})") from None
        return cls.from_dict(doc, source)

    @property
    def status_text(self) -> str:
        """The status as printed (:func:`.result.status_text`): as stored, else from status and readings."""
        said = self.document.get("status_text")
        return said if isinstance(said, str) else status_text(self.status, self.readings)

    @property
    def named_terms(self) -> tuple[str, ...]:
        return tuple(t.term for t in self.named)

    @property
    def headline(self) -> str:
        return headline(self.verdict)

    @property
    def details(self) -> tuple[str, ...]:
        return tuple(details(self.verdict))

    def __getitem__(self, key: str) -> Any:
        """What the JSON holds beyond the typed fields: ``saved["steps"]``, ``saved["alternatives"]``, ..."""
        return self.document[key]

    def summary(self) -> str:
        """The verdict (headline, then its clauses one per line), the models' statistics and the share."""
        lines = [f"Diagnosis: {self.headline}", *(f"  - {c}" for c in self.details), ""]
        for label, m in (("plain", self.plain), ("final", self.final)):
            lines.append(f"{label} model: chi2/dof = {m.cost / max(m.dof, 1):.3g} (p = {m.p_value:.2g})")
        lines.append(f"share of the plain model's excess explained: {100 * self.explained_fraction:.1f} %")
        lines += list(self.notes)
        return "\n".join(lines)

    def __str__(self) -> str:
        return self.summary()

    def to_dict(self) -> dict[str, Any]:
        """The JSON object it was read from (a copy)."""
        copy: dict[str, Any] = json.loads(json.dumps(self.document))
        return copy

    def to_json(self, indent: int = 2) -> str:
        return json.dumps(self.document, indent=indent, allow_nan=False)


def load_diagnosis(path: Union[str, os.PathLike[str]]) -> SavedDiagnosis:
    """The diagnosis in ``path`` (``Diagnosis.to_json``, or ``diagnosis.json`` of ``bouc-wen-id diagnose
    --out``/``--json``); a folder is read as its ``diagnosis.json``.

    Raises
    ------
    FileFormatError
        No such file, not JSON, or JSON of something else (the message says what it holds).
    TypeError
        ``path`` is not a path (a str or an os.PathLike).
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(
            f"load_diagnosis takes the path of a diagnosis JSON file or of the folder holding diagnosis.json "
            f"(a str or os.PathLike), not {type(path).__name__}"
        )
    p = os.fspath(path)
    if os.path.isdir(p):
        p = os.path.join(p, "diagnosis.json")
    try:
        size = os.path.getsize(p)
        if size > MAX_BYTES:
            raise FileFormatError(f"{p}: {size} bytes is no diagnosis JSON")
        with open(p, encoding="utf-8") as fh:
            text = fh.read()
    except OSError as exc:
        raise FileFormatError(f"{p}: cannot read the diagnosis: {exc.strerror or exc}") from None
    try:
        doc = json.loads(text)
    except ValueError as exc:
        raise FileFormatError(f"{p}: not JSON ({exc})") from None
    if isinstance(doc, Mapping) and not looks_like(doc):
        if doc.get("format") == MODEL_FORMAT:
            raise FileFormatError(f"{p}: a model document: read it with bouc_wen_id.export.load_model")
        if "conditions" in doc and "verdict" in doc:
            raise FileFormatError(
                f"{p}: a diagnosis across conditions (diagnose-across --json), not one diagnosis; read it "
                "with json.load"
            )
    return SavedDiagnosis.from_dict(doc, p)
