"""Where a named term's law (one value for all experiments, :func:`.select.law_test`) could not be tested.

The law test compares the term's value between the experiments it acts on (a column not zero). The
input-waveform term acts only on experiments whose input carries harmonics: with fewer than two of them
there is nothing to compare, the test gives NaN, and a NaN law counted as passed said nothing of it (review
of session 30). The verdict says "law untested" beside such a named term instead; across conditions
(:func:`across_text`) at each condition where the term is present and its law could not be tested there.

With one experiment there is no held-out test either (leave-one-experiment-out needs two): a term was
named on the in-sample F test alone and nothing said so (review 31a item 7). The verdict says so.
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


def untested(term: str, exps: Sequence[Any]) -> bool:
    """Whether ``term``'s law cannot be compared between ``exps``: it acts on fewer than two of them."""
    return carriers(exps, term) < 2


def text(named: Sequence[Any], exps: Sequence[Any]) -> str:
    """The verdict's clause for each named term carried by fewer than two of two or more experiments, or,
    with one experiment, that the named terms passed neither the held-out test nor the law test."""
    m = len(exps)
    if m < 2:
        return (
            "; named without the held-out test: not possible with one experiment (a term is otherwise named "
            "only if it lowers the cost of experiments left out of its fit), and its one value for all "
            "experiments is untested; record a second experiment to test both"
            if named and m == 1
            else ""
        )
    out = []
    for t in named:
        if untested(t.term, exps):
            k = carriers(exps, t.term)
            out.append(
                f"; {t.label}: law untested (carried by only {k} of the {m} experiments: its one value "
                "for all cannot be compared between them)"
            )
    return "".join(out)


def across_text(named: Sequence[Any], groups: Sequence[tuple[str, Sequence[Any]]]) -> str:
    """The clause of :func:`text` for a structure named across conditions (``diagnose_across``): its law is
    one value for a condition's experiments, tested at each condition where the term is present (each
    ``named`` term's ``present``, one flag per ``(label, experiments)`` of ``groups``). Said for each named
    term at the conditions where it is present and carried by fewer than two of their experiments (one
    experiment alone included: there is nothing to compare either), and whether that is every such
    condition (then its law was tested nowhere)."""
    out = []
    for t in named:
        here = [(w, exps) for (w, exps), pr in zip(groups, t.present) if pr]
        bad = [(w, exps) for w, exps in here if untested(t.term, exps)]
        if not bad:
            continue
        where = ", ".join(f"{w} ({carriers(exps, t.term)} of {len(exps)})" for w, exps in bad)
        scope = "at every condition where it is present" if len(bad) == len(here) else "at some conditions"
        out.append(
            f"; {t.label}: law untested {scope} (carried by fewer than two of the condition's experiments at "
            f"{where}: its one value for a condition's experiments cannot be compared between them there)"
        )
    return "".join(out)
