"""Stability of a diagnosis under preprocessing: a term that comes and goes is an alternative, not a finding.

The same experiments, preprocessed in other reasonable ways (a shorter stretch of the steady record, fewer
harmonics in the averaged period), should name the same terms. :func:`stability` compares a main
diagnosis with its variants' diagnoses: a term the main run names and every completed variant names is a
*finding*; one named in k of n completed runs (0 < k < n, the main run counted) is an *alternative*, and
the revised verdict says so instead of naming it. A variant that failed (refused, or raised) is left out of
the count and said. :func:`diagnose_stable` runs the main diagnosis and the :data:`VARIANTS` on
Measurements and returns the comparison.

The rule is not the F-test's: each run's terms are already tested at its own level. It asks whether the
naming survives choices the data do not dictate, as a reader of the verdict assumes it does. A variant
holds less data than the main run (early, late: two thirds of each steady stretch), so its silence is
evidence against a term only when it had the power to see it: a variant that did not name a term the main
run named, and whose own detection limit for it at 90 % power (``Diagnosis.limits``, limits.py) is above
the main run's value, is *unseen* there, said and not counted against the term. A variant that found the
term but left structure beside it (``Diagnosis.partial``) counts as naming it. A variant that reports no
detection limit for the term counts against it (its power is unknown).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Union

from .result import TERM_LABELS, Diagnosis, NamedTerm, Status
from .variants import MAIN, VARIANTS, variant_items

#: The head of an "explained" verdict (run._verdict).
EXPLAINED_BY = "explained by: "

#: A variant's outcome: its diagnosis, or why it did not complete (a message or the exception).
Outcome = Union[Diagnosis, str, BaseException]


@dataclass(frozen=True)
class TermStability:
    """One term named by at least one run: which runs named it."""

    term: str
    named_in: tuple[str, ...]
    completed: int
    #: The main run's estimate when it named the term, else None.
    main: NamedTerm | None = None
    #: Completed variants that did not name the main run's term but could not have seen it: their detection
    #: limit at 90 % power is above the main run's value (not counted against the term).
    unseen: tuple[str, ...] = ()

    @property
    def label(self) -> str:
        return TERM_LABELS.get(self.term, self.term)

    @property
    def finding(self) -> bool:
        """Named in the main run and in every completed variant that could have seen it (at least one variant
        completed)."""
        return (
            self.main is not None
            and self.completed > 1
            and len(self.named_in) + len(self.unseen) == self.completed
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "term": self.term,
            "label": self.label,
            "named_in": list(self.named_in),
            "completed": self.completed,
            "unseen": list(self.unseen),
            "finding": self.finding,
            "main": None if self.main is None else self.main.to_dict(),
        }


@dataclass(frozen=True, eq=False)
class Stability:
    """The main diagnosis read against its preprocessing variants.

    ``status`` and ``verdict`` are the main run's, revised: a term named there but not in every completed
    variant that could have seen it is moved out of the named terms into an "alternative, not a finding"
    clause (with its count); a term only some variants named is mentioned likewise; variants too small to
    see a term and failed variants are said. With no named term left the status is ``unexplained`` when
    some completed run left structure (status ``partly explained`` or ``unexplained``); when every completed
    run reached its noise floor (``adequate`` or ``explained``) nothing is shown to remain, so it is
    ``partly explained``: the data are accounted for, but only by alternatives, none of them a finding. An
    ``explained`` whose named terms are not all findings becomes ``partly explained`` (the findings alone are
    not shown to reach the noise floor). When no variant completed, nothing is revised (stability not
    checked) and the verdict says so.
    """

    status: Status
    verdict: str
    terms: tuple[TermStability, ...]
    completed: tuple[str, ...]
    failed: Mapping[str, str]
    main: Diagnosis = field(repr=False)
    variants: Mapping[str, Outcome] = field(repr=False, default_factory=dict)

    @property
    def findings(self) -> tuple[str, ...]:
        return tuple(t.term for t in self.terms if t.finding)

    @property
    def alternatives(self) -> tuple[str, ...]:
        return tuple(t.term for t in self.terms if not t.finding)

    @property
    def checked(self) -> bool:
        """At least one variant completed beside the main run."""
        return len(self.completed) > 1

    def to_dict(self) -> dict[str, Any]:
        return {
            "status": self.status,
            "verdict": self.verdict,
            "main_status": self.main.status,
            "main_verdict": self.main.verdict,
            "completed": list(self.completed),
            "failed": dict(self.failed),
            "findings": list(self.findings),
            "alternatives": list(self.alternatives),
            "terms": [t.to_dict() for t in self.terms],
            "variants": {
                k: (v.status if isinstance(v, Diagnosis) else _reason(v)) for k, v in self.variants.items()
            },
        }


def _reason(v: Union[str, BaseException]) -> str:
    return v if isinstance(v, str) else f"{type(v).__name__}: {v}"


def stability(main: Diagnosis, variants: Mapping[str, Outcome], main_key: str = MAIN) -> Stability:
    """The main diagnosis ``main`` compared with ``variants`` ({key: Diagnosis, or why it failed}).

    Raises TypeError for an outcome that is neither; ``main_key`` names the main run in the counts (a
    variant under the same key is an error: it would be counted twice)."""
    if not isinstance(main, Diagnosis):
        raise TypeError(f"main must be a Diagnosis, not {type(main).__name__}")
    if main_key in variants:
        raise ValueError(f"variant key {main_key!r} is the main run's")
    done: dict[str, Diagnosis] = {main_key: main}
    failed: dict[str, str] = {}
    for k, v in variants.items():
        if isinstance(v, Diagnosis):
            done[k] = v
        elif isinstance(v, (str, BaseException)):
            failed[k] = _reason(v)
        else:
            raise TypeError(f"variant {k!r}: a Diagnosis, a message or an exception, not {type(v).__name__}")
    n = len(done)
    own = {t.term: t for t in main.named}
    order: dict[str, list[str]] = {}
    for k, d in done.items():
        # A variant that found the main run's term beside structure it left (partial) found it too.
        seen = [*d.named, *(t for t in d.partial if k != main_key and t.term in own)]
        for t in seen:
            order.setdefault(t.term, [])
            if k not in order[t.term]:
                order[t.term].append(k)
    terms = tuple(
        TermStability(t, tuple(ks), n, own.get(t), _unseen(own.get(t), ks, done)) for t, ks in order.items()
    )
    status, verdict = _revised(main, terms, done, failed)
    return Stability(status, verdict, terms, tuple(done), failed, main, dict(variants))


def _limit_90(d: Diagnosis, term: str) -> float:
    """The smallest |value| of ``term`` that ``d``'s design detects with 90 % power (inf: none reported)."""
    lims = [abs(float(lim.limit_90)) for lim in d.limits if getattr(lim, "term", None) == term]
    return min((v for v in lims if math.isfinite(v)), default=math.inf)


def _unseen(
    main: NamedTerm | None, named_in: Sequence[str], done: Mapping[str, Diagnosis]
) -> tuple[str, ...]:
    """The completed runs that did not name the main run's term ``main`` and could not have seen it: their
    own detection limit at 90 % power is above its value (a variant reporting no limit could have)."""
    if main is None or not math.isfinite(main.value):
        return ()
    return tuple(
        k
        for k, d in done.items()
        if k not in named_in and abs(main.value) < _limit_90(d, main.term) < math.inf
    )


def _count(t: TermStability, completed: Sequence[str]) -> str:
    missing = [k for k in completed if k not in t.named_in and k not in t.unseen]
    return (
        f"named in {len(t.named_in)} of {len(t.named_in) + len(missing)} preprocessing variants "
        f"({', '.join(t.named_in)}; not {', '.join(missing)})" + _unseen_clause(t, "; ")
    )


def _unseen_clause(t: TermStability, head: str) -> str:
    if not t.unseen:
        return ""
    return (
        f"{head}not named in {', '.join(t.unseen)}, which could not have seen it (the value is below the "
        "detection limit at 90 % power there): not counted against it"
    )


def _revised(
    main: Diagnosis,
    terms: tuple[TermStability, ...],
    done: Mapping[str, Diagnosis],
    failed: Mapping[str, str],
) -> tuple[Status, str]:
    """The main run's status and verdict with its unstable terms said as alternatives (see Stability)."""
    fails = ", ".join(f"{k} ({why})" for k, why in failed.items())
    completed = tuple(done)
    if len(completed) < 2:
        if not failed:
            return main.status, main.verdict
        return (
            main.status,
            f"{main.verdict}; stability under preprocessing not checked: every variant failed: {fails}",
        )
    unstable = [t for t in terms if t.main is not None and not t.finding]
    others = [t for t in terms if t.main is None]
    unseen = [t for t in terms if t.main is not None and t.finding and t.unseen]
    if not unstable and not others:
        if not unseen:
            return main.status, main.verdict
        said = "; ".join(f"{t.main}: a finding{_unseen_clause(t, ', ')}" for t in unseen)
        return main.status, f"{main.verdict}; {said}"
    verdict, status = main.verdict, main.status
    kept = [t for t in main.named if t.term not in {u.term for u in unstable}]
    if unstable:
        listed = ", ".join(str(t) for t in main.named)
        if kept and listed in verdict:
            verdict = verdict.replace(listed, ", ".join(str(t) for t in kept), 1)
        elif not kept and any(d.status in ("partly explained", "unexplained") for d in done.values()):
            verdict = "no term named in every preprocessing variant; the main run said: " + verdict
            status = "unexplained"
        elif not kept:  # every run reached its noise floor: nothing is shown to remain, but no term is stable
            verdict = (
                "explained only by alternatives, not findings (every preprocessing variant fits at its noise "
                "floor, with or without them); the main run said: " + verdict
            )
            status = "partly explained"
        if kept and status == "explained":
            status = "partly explained"
            if verdict.startswith(EXPLAINED_BY):  # the findings alone are not shown to reach the noise floor
                verdict = "explained in part by: " + verdict[len(EXPLAINED_BY) :]
    counted = {
        "partly explained": " (the share of the excess above counts it)",
        "explained": " (the fit counts it)",
    }
    clauses = [
        f"{t.main} {_count(t, completed)}: an alternative, not a finding"
        + (counted.get(main.status, "") if kept else "")
        for t in unstable
        if t.main is not None
    ]
    clauses += [f"{t.label} {_count(t, completed)}: an alternative, not a finding" for t in others]
    clauses += [f"{t.main}: a finding{_unseen_clause(t, ', ')}" for t in unseen]
    tail = f" (variants that failed, not counted: {fails})" if failed else ""
    return status, f"{verdict}; {'; '.join(clauses)}{tail}"


def diagnose_stable(
    measurements: Sequence[Any],
    *,
    variants: Sequence[str] = ("early", "late", "half harmonics"),
    main: Diagnosis | None = None,
    **diagnose_kwargs: Any,
) -> Stability:
    """``diagnose`` on ``measurements`` and on each preprocessing variant, compared (:func:`stability`).

    ``main``: the main run's diagnosis when already at hand (else it is run). ``diagnose_kwargs`` go to
    every run (``candidates``, ``alpha``, units, ...). A variant that the library refuses (a
    :class:`~bouc_wen_id.errors.BoucWenIdError`, e.g. too short a stretch) is counted as failed and said;
    the main run's own errors propagate. Costs one diagnosis per variant."""
    from ..errors import BoucWenIdError
    from .run import diagnose

    keys = [k for k, _ in VARIANTS]
    unknown = [v for v in variants if v not in keys or v == MAIN]
    if unknown:
        raise ValueError(f"unknown preprocessing variants {unknown}; from {keys[1:]}")
    ms = variant_items(measurements, MAIN)
    if main is None:
        main = diagnose(ms, **diagnose_kwargs)
    runs: dict[str, Outcome] = {}
    for v in variants:
        try:
            # A variant's own value check would cut a cut (value_stability.py runs on the main run only).
            runs[v] = diagnose(variant_items(ms, v), **{**diagnose_kwargs, "value_stability": False})
        except BoucWenIdError as exc:
            runs[v] = exc
    return stability(main, runs)


def describe(st: Stability) -> str:
    """One line per term: how many runs named it (for a report)."""
    return "; ".join(f"{t.label}: {len(t.named_in)} of {t.completed}" for t in st.terms) or "nothing named"


__all__ = [
    "MAIN",
    "VARIANTS",
    "Outcome",
    "TermStability",
    "Stability",
    "stability",
    "variant_items",
    "diagnose_stable",
    "describe",
]
