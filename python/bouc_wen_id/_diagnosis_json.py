"""How a reader that is not :func:`bouc_wen_id.load_diagnosis` recognises a diagnosis JSON and names the
reader (review 35: ``load``, ``load_model`` and ``export`` refused diagnosis.json without naming one). No
imports: the recording and model readers use it without pulling in the diagnosis."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

#: The keys every diagnosis JSON holds (``Diagnosis.to_dict``).
KEYS = ("status", "verdict", "named", "partial", "plain", "final", "explained_fraction")
#: What a reader that is not load_diagnosis says of a diagnosis JSON.
HINT = (
    "a diagnosis (diagnose's diagnosis.json, Diagnosis.to_json) is read by bouc_wen_id.load_diagnosis; it "
    "holds no G to load or export (fit_time_domain with the named terms builds a model)"
)


def looks_like(doc: Any) -> bool:
    """Whether a parsed JSON document is a diagnosis (:data:`KEYS`)."""
    return isinstance(doc, Mapping) and all(k in doc for k in KEYS)
