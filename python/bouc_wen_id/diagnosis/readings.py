"""The headline never says more than the details allow (issue 18: a name users can trust blind).

A verdict is read in two layers (:mod:`.verdict_text`): its headline (what is named, with value ± se and
share, or what is left) and its details. Several details qualify what the headline names; a user who reads
only the headline ("explained by: viscous damping across the hysteretic element (on x) c = ...") was told
more than the data back (review 33 ``pi_u_10``: a Prandtl-Ishlinskii loop on u, outside the library, whose
viscous value did not refuse a rate-independent loop's 1/omega law, said only in a detail clause).

Each clause kind was audited (docs/diagnosis.md, "What the headline may claim"). Those that qualify the
named terms put a few words into the headline (" — or a rate-independent loop outside the library (see
details)") and are kept as :class:`Reading` s on the result (``Diagnosis.readings``):

- **rival readings** the data do not refuse (``rival=True``; the status is then reported as "not the only
  reading", :func:`status_text`): the rate caveat (:mod:`.rate_rival`); a rival the experiments cannot
  tell from a named term, or one passed over for its law only (:func:`.caveats.rivals_of`, the clauses of
  :func:`.caveats.alternatives_text`); a set of terms that holds its laws in a named term's place
  (:mod:`.revisit`'s "not the only reading" and "alternative to"; a revisit that named the set says the
  single term is the rival); Dahl friction's family (:func:`.caveats.family_text`), play's output backlash
  (:func:`.caveats.play_text`) and a spring on x's Masing loop (:func:`.masing.masing_text`);
- **limits of the evidence** (``rival=False``): what remains unexplained shown only by the adequacy test at a
  modest p-value (:mod:`.borderline`: the only reading kept when nothing is named, said in the status too); a
  named term's law untested, or named without the held-out
  test (:mod:`.law_untested`); a waveform's ``lam`` far from 1, no property of the device
  (:mod:`.input_note`); across conditions, diagnose's revisit not run (:func:`.across_pairs.revisit_clause`).

With two or more named terms, each rival says which named term it stands in place of (``instead_of``, code
names; the headline's "or output offset instead of asymmetry", :func:`_said_instead`): "— or Dahl friction
on u, or output offset" beside a damping and an asymmetry did not say which each replaces (MR 0.5 A).

Clauses that do not change what the headline claims are left in the details: law_chance's "refused by chance"
(said only when nothing is named: "unexplained structure remains" holds under either reading), the clean
share on clipped sets (the headline's share is the pooled one, the smaller), a place that fits only with a
non-physical value (it strengthens the name), stand-ins not named, and notes on the data (loop centres,
baselines, hum, unsettled experiments, detection limits of an "adequate" verdict).

The status values are unchanged (``d.status`` is what it was, the CLI's exit codes too): the readings are
an attribute, and :func:`status_text` (:func:`.result.status_text`) is the status as printed (the HTML
report's, ``Diagnosis.status_text``, ``to_dict()["status_text"]``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol, TypeVar

from ..terms import TERMS, Play
from . import borderline
from .result import NOT_ONLY, status_text
from .verdict_text import clauses

#: Joins the headline's own first clause and its qualifiers.
DASH = " — "
#: Closes the headline's qualifiers.
SEE = " (see details)"


@dataclass(frozen=True)
class Reading:
    """A qualifier of what the headline names: its kind, the headline's words, and whether it is a rival
    reading the data do not refuse (else a limit of the evidence behind the name)."""

    kind: str
    words: str
    rival: bool = True
    #: The named terms (code names) this rival reading stands in place of (() when the clause does not say
    #: or when it is a limit of the evidence); with two or more named terms the headline says which
    #: (":func:`of_verdict`: "or output offset instead of asymmetry").
    instead_of: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind,
            "words": self.words,
            "rival": self.rival,
            "instead_of": list(self.instead_of),
        }


def _label(kind: str) -> str:
    return TERMS[kind].place_label() if kind in TERMS else kind


def _between(text: str, start: str, end: str) -> str:
    """The part of ``text`` after ``start`` and before the next ``end`` ("" when either is missing)."""
    i = text.find(start)
    if i < 0:
        return ""
    j = text.find(end, i + len(start))
    return text[i + len(start) : j] if j >= 0 else ""


def _kinds_in(text: str, named: Sequence[str]) -> tuple[str, ...]:
    """The ``named`` terms (code names) whose labels ``text`` says, in the order ``named`` has them; the
    longer labels first, so "degradation" is not read inside "stiffness degradation"."""
    found: set[str] = set()
    for kind in sorted(named, key=lambda k: -len(_label(k))):
        if _label(kind) in text:
            found.add(kind)
            text = text.replace(_label(kind), "\0")
    return tuple(k for k in named if k in found)


def _of_clause(c: str, named: Sequence[str]) -> list[Reading]:
    """The readings one detail clause carries (module docstring), by the words its module writes; a rival's
    ``instead_of``: the ``named`` terms the clause says it stands in place of."""
    from .bounds_said import BEYOND_MARK, MU_MARK
    from .caveats import FAMILY_MARK, PLAY_MARK
    from .masing import MASING_MARK
    from .one_amplitude import ONE_AMPLITUDE_MARK, reading_words
    from .rate_rival import RATE_MARK

    out: list[Reading] = []
    if RATE_MARK in c and "may stand for" in c:
        of = _kinds_in(c.split(" may stand for")[0], named)
        out.append(Reading("rate", f"or {RATE_MARK} outside the library", instead_of=of))
    if FAMILY_MARK in c:
        words = f"or a distribution of stops or another Dahl exponent (Dahl: {FAMILY_MARK})"
        out.append(Reading("family", words, instead_of=_kinds_in(c.split(" names ")[0], named)))
    if ONE_AMPLITUDE_MARK in c:  # a loop-shape term from one amplitude per frequency (one_amplitude.py)
        of = _kinds_in(c.split(": a loop of another family")[0], named)
        out.append(Reading("one_amplitude", reading_words(c), instead_of=of))
    if PLAY_MARK in c:
        words = f"or a backlash on the measured output (play: {PLAY_MARK})"
        out.append(Reading(Play.kind, words, instead_of=_kinds_in(c.split(" names ")[0], named)))
    if MASING_MARK in c and "may be the elastic part" in c:
        words = f"or the elastic part of {MASING_MARK} (a Prandtl-Ishlinskii loop on x)"
        of = _kinds_in(c.split(" may be the elastic part")[0], named)
        out.append(Reading("masing", words, instead_of=of))
    both = _between(c, "not the only reading: ", ", jointly")
    of = _kinds_in(c.split(" in place of ")[-1].split(" (not named")[0], named)
    if not both and c.startswith("alternative to "):  # the set kept as the named term's rival
        both = _between(c, ": ", ", jointly")
        of = _kinds_in(_between(c, "alternative to ", ": "), named)
    if both:  # a set that holds its laws in place of the named term(s)
        out.append(Reading("revisit", f"or {both} together", instead_of=of))
    one = _between(c, "named in its place. ", " is the rival")  # a revisit named a set: the single term
    if one:
        out.append(Reading("revisit", f"or {one}", instead_of=_kinds_in(c.split(", jointly")[0], named)))
    if ": law untested" in c:
        out.append(Reading("law_untested", f"{c.split(': law untested')[0]}'s law untested", rival=False))
    if c.startswith("named without the held-out test"):
        out.append(Reading("untested", "named without the held-out or the law test", rival=False))
    if "is far from 1 (the measured waveform" in c:
        out.append(Reading("not_device", f"{c.split(' = ')[0]} not a property of the device", rival=False))
    if c.startswith(MU_MARK):
        face = c[len(MU_MARK) :].split(" end of")[0].strip()
        out.append(
            Reading("mu_bracket", f"conditional on mu held at the {face} end of its bracket", rival=False)
        )
    if c.startswith(BEYOND_MARK):
        out.append(Reading("beyond", "or a reading beyond a term's physical range"))
    if c.startswith("not run across conditions: diagnose's revisit"):
        out.append(Reading("revisit_untried", "a level's revisit not run across", rival=False))
    return out


def _short(kind: str, named: Sequence[str]) -> str:
    """A named term as the headline's "instead of" says it: its family's label ("viscous damping") when no
    other named term shares the family, else its place label."""
    if kind not in TERMS:
        return kind
    base = TERMS[kind].base_kind
    same = [k for k in named if k in TERMS and TERMS[k].base_kind == base]
    return TERMS[base].label if len(same) == 1 and base in TERMS else _label(kind)


def _said_instead(rs: Sequence[Reading], named: Sequence[str]) -> list[Reading]:
    """``rs`` with a rival's words saying which named term it stands in place of ("or output offset instead
    of asymmetry") when two or more terms are named: a headline naming several terms and listing "or X"
    did not say which one X replaces. The same words for several named terms are said once, for all."""
    merged: dict[str, Reading] = {}
    apart: set[str] = set()  # words found as a rival of each named term on its own, not of them jointly
    for r in rs:
        was = merged.get(r.words)
        if was is None:
            merged[r.words] = r
        elif r.instead_of:
            of = tuple(k for k in named if k in set(was.instead_of) | set(r.instead_of))
            if set(of) != set(was.instead_of):
                apart.add(r.words)
            merged[r.words] = replace(was, instead_of=of)
    if len(set(named)) < 2:
        return list(merged.values())
    out = []
    for r in merged.values():
        if r.rival and r.instead_of:
            join = " or of " if r.words in apart else " and "  # one term for each, or one for both
            r = replace(r, words=f"{r.words} instead of {join.join(_short(k, named) for k in r.instead_of)}")
        out.append(r)
    return out


def of_verdict(verdict: str, named: Sequence[str], alternatives: Sequence[Any]) -> tuple[Reading, ...]:
    """The readings of a verdict whose ``named`` terms (code names) have ``alternatives``
    (:class:`.select.Alternative`): its detail clauses' (:func:`_of_clause`) and the named terms' rivals
    (:func:`.caveats.rivals_of`), each said once (with the named terms it stands for, :func:`_said_instead`);
    () when nothing is named."""
    from .caveats import rivals_of

    said = clauses(verdict)
    # weak evidence that structure remains (borderline.py): read whether or not a term is named
    weak = [
        Reading(borderline.KIND, borderline.reading_words(c), rival=False)
        for c in said[:2]
        if borderline.reading_words(c)
    ]
    if not named:
        return tuple(weak)
    rivals, by_law = rivals_of(alternatives, named)
    # a rival named itself (two named terms each the other's rival) is no other reading of the headline
    out = [
        Reading("alternative", f"or {_label(r)}", instead_of=(t,))
        for t, rs in rivals.items()
        for r in rs
        if r not in named
    ]
    out += [
        Reading("alternative", f"or {_label(a.rival)} (law p = {a.law_p_value:.2g})", instead_of=(a.term,))
        for a in by_law
        if a.rival not in named
    ]
    # a rival the details list as "not named: ... its law fails" is refused by the data: no other reading
    details = said[1:]
    refused = " ".join(_between(c, "not named: ", ": each fits") for c in details)
    out = [
        r
        for r in out
        if not (r.kind == "alternative" and r.words.removeprefix("or ").split(" (law")[0] in refused)
    ]
    for c in details:
        out += _of_clause(c, named)
    out += weak
    return tuple(_said_instead(out, named))


def headlined(verdict: str, readings: Sequence[Reading]) -> str:
    """``verdict`` with the readings' words in its headline (its first clause), rivals first; the clauses
    after it unchanged, so the verdict splits into the same clauses (:func:`.verdict_text.clauses`)."""
    if not readings:
        return verdict
    parts = clauses(verdict)
    # a reading the headline already says in full (a weak remainder's p-value, borderline.py) is not repeated
    readings = [r for r in readings if not (r.kind == borderline.KIND and borderline.MARK in parts[0])]
    if not readings:
        return verdict
    words = [r.words for r in readings if r.rival] + [r.words for r in readings if not r.rival]
    head = parts[0] + DASH + ", ".join(words) + SEE
    rest = verdict[verdict.find(parts[0]) + len(parts[0]) :]
    return head + rest


class _Verdict(Protocol):
    @property
    def verdict(self) -> str: ...


_D = TypeVar("_D", bound=_Verdict)


def qualified(d: _D, named: Sequence[str], alternatives: Sequence[Any]) -> _D:
    """``d`` (a :class:`.result.Diagnosis` or :class:`.across.AcrossDiagnosis`) with its readings and the
    headline that carries them."""
    verdict = d.verdict
    rs = of_verdict(verdict, named, alternatives)
    return replace(d, verdict=headlined(verdict, rs), readings=rs)  # type: ignore[type-var]


__all__ = ["DASH", "NOT_ONLY", "SEE", "Reading", "headlined", "of_verdict", "qualified", "status_text"]
