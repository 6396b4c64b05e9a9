"""Where a named term's law (one value for all experiments, :func:`.select.law_test`) could not be tested.

The law test compares the term's value between the experiments it acts on (a column not zero). The
input-waveform term acts only on experiments whose input carries harmonics: with fewer than two of them
there is nothing to compare, the test gives NaN, and a NaN law counted as passed said nothing of it (review
of session 30). The verdict says "law untested" beside such a named term instead.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ..terms import TERMS, Distortion


def carriers(exps: Sequence[Any], term: str) -> int:
    """How many of ``exps`` the term acts on: the input-waveform term on those whose input is distorted,
    any other on all."""
    if term in TERMS and issubclass(TERMS[term], Distortion):
        return sum(bool(getattr(e, "distorted", False)) for e in exps)
    return len(exps)


def text(named: Sequence[Any], exps: Sequence[Any]) -> str:
    """The verdict's clause for each named term carried by fewer than two of two or more experiments."""
    m = len(exps)
    if m < 2:
        return ""
    out = []
    for t in named:
        k = carriers(exps, t.term)
        if k < 2:
            out.append(
                f"; {t.label}: law untested (carried by only {k} of the {m} experiments: its one value "
                "for all cannot be compared between them)"
            )
    return "".join(out)
