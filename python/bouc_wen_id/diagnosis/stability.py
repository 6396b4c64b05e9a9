"""Stability of a diagnosis under preprocessing: a term that comes and goes is an alternative, not a finding.

The same experiments, preprocessed in other reasonable ways (a shorter stretch of the steady record, fewer
harmonics in the averaged period), should name the same terms. :func:`stability` compares a main
diagnosis with its variants' diagnoses: a term the main run names and every completed variant names is a
*finding*; one named in k of n completed runs (0 < k < n, the main run counted) is an *alternative*, and
the revised verdict says so instead of naming it. A variant that failed (refused, or raised) is left out of
the count and said. :func:`diagnose_stable` runs the main diagnosis and the :data:`VARIANTS` on
Measurements and returns the comparison.

The rule is not the F-test's: each run's terms are already tested at its own level. It asks whether the
naming survives choices the data do not dictate, as a reader of the verdict assumes it does.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Union

from .result import TERM_LABELS, Diagnosis, NamedTerm, Status

#: The run every variant is compared with.
MAIN = "as recorded"

#: The preprocessing variants (key, description); the first is the main run.
VARIANTS: tuple[tuple[str, str], ...] = (
    (MAIN, "the whole steady stretch, the averaging's own harmonic count"),
    ("early", "the steady stretch without its last third"),
    ("late", "the steady stretch without its first third"),
    ("half harmonics", "half the harmonics in the averaged period (at least 8)"),
)

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

    @property
    def label(self) -> str:
        return TERM_LABELS.get(self.term, self.term)

    @property
    def finding(self) -> bool:
        """Named in the main run and in every completed variant (at least one variant completed)."""
        return self.main is not None and self.completed > 1 and len(self.named_in) == self.completed

    def to_dict(self) -> dict[str, Any]:
        return {
            "term": self.term,
            "label": self.label,
            "named_in": list(self.named_in),
            "completed": self.completed,
            "finding": self.finding,
            "main": None if self.main is None else self.main.to_dict(),
        }


@dataclass(frozen=True, eq=False)
class Stability:
    """The main diagnosis read against its preprocessing variants.

    ``status`` and ``verdict`` are the main run's, revised: a term named there but not in every completed
    variant is moved out of the named terms into an "alternative, not a finding" clause (with its count);
    a term only some variants named is mentioned likewise; failed variants are said. With no named term
    left the status is ``unexplained``; an ``explained`` whose named terms are not all findings becomes
    ``partly explained`` (the findings alone are not shown to reach the noise floor). When no variant
    completed, nothing is revised (stability not checked) and the verdict says so.
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
    order: dict[str, list[str]] = {}
    for k, d in done.items():
        for t in d.named:
            order.setdefault(t.term, [])
            if k not in order[t.term]:
                order[t.term].append(k)
    own = {t.term: t for t in main.named}
    terms = tuple(TermStability(t, tuple(ks), n, own.get(t)) for t, ks in order.items())
    status, verdict = _revised(main, terms, tuple(done), failed)
    return Stability(status, verdict, terms, tuple(done), failed, main, dict(variants))


def _count(t: TermStability, completed: Sequence[str]) -> str:
    missing = [k for k in completed if k not in t.named_in]
    return (
        f"named in {len(t.named_in)} of {t.completed} preprocessing variants "
        f"({', '.join(t.named_in)}; not {', '.join(missing)})"
    )


def _revised(
    main: Diagnosis, terms: tuple[TermStability, ...], completed: tuple[str, ...], failed: Mapping[str, str]
) -> tuple[Status, str]:
    """The main run's status and verdict with its unstable terms said as alternatives (see Stability)."""
    fails = ", ".join(f"{k} ({why})" for k, why in failed.items())
    if len(completed) < 2:
        if not failed:
            return main.status, main.verdict
        return (
            main.status,
            f"{main.verdict}; stability under preprocessing not checked: every variant failed: {fails}",
        )
    unstable = [t for t in terms if t.main is not None and not t.finding]
    others = [t for t in terms if t.main is None]
    if not unstable and not others:
        return main.status, main.verdict
    verdict, status = main.verdict, main.status
    kept = [t for t in main.named if t.term not in {u.term for u in unstable}]
    if unstable:
        listed = ", ".join(str(t) for t in main.named)
        if kept and listed in verdict:
            verdict = verdict.replace(listed, ", ".join(str(t) for t in kept), 1)
        elif not kept:
            verdict = "no term named in every preprocessing variant; the main run said: " + verdict
            status = "unexplained"
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
    tail = f" (variants that failed, not counted: {fails})" if failed else ""
    return status, f"{verdict}; {'; '.join(clauses)}{tail}"


def variant_items(measurements: Sequence[Any], variant: str) -> list[Any]:
    """The experiments of one preprocessing variant of :data:`VARIANTS`, from Measurements (the main run's
    items are the measurements themselves; the others are derived, the measurements left as they are)."""
    from .. import signal
    from ..measurement import Measurement
    from .data import _from_averaged

    keys = [k for k, _ in VARIANTS]
    if variant not in keys:
        raise ValueError(f"unknown preprocessing variant {variant!r}; one of {keys}")
    ms = list(measurements)
    bad = [type(m).__name__ for m in ms if not isinstance(m, Measurement)]
    if bad:
        raise TypeError(
            f"the preprocessing variants are cut from Measurements, not {', '.join(sorted(set(bad)))}"
        )
    if variant == MAIN:
        return ms
    if variant in ("early", "late"):
        return [_cut(m, variant) for m in ms]
    out = []
    for m in ms:
        for ap in signal.average_measurement(m):
            half = signal.average_measurement(m, harmonics=max(8, ap.harmonics // 2))
            out += [_from_averaged(h, m.t, m.y, m.u) for h in half if h.start == ap.start]
    return out


def _cut(m: Any, variant: str) -> Any:
    """``m`` restricted to part of its first steady stretch: the early or the late two thirds."""
    from .. import signal
    from ..measurement import Measurement

    ap = signal.average_measurement(m)[0]
    third = (ap.stop - ap.start) // 3
    a, b = (ap.start, ap.stop - third) if variant == "early" else (ap.start + third, ap.stop)
    return Measurement(
        m.t[a:b] - m.t[a],
        m.u[a:b],
        m.y[a:b],
        nominal_frequency=m.nominal_frequency,
        units={k: v for k, v in m.units.items() if k in ("u", "y")},
        name=f"{m.name} ({variant})",
    )


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
            runs[v] = diagnose(variant_items(ms, v), **diagnose_kwargs)
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
