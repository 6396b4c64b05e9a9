"""Loops that have not settled, across conditions: ``diagnose_across`` leaves them out as ``diagnose`` does.

:func:`.run.diagnose` tests every experiment's loop for a drift from period to period beyond the noise
(:func:`.settling._unsettled`) and, unless degradation explains it, leaves the drifting experiments out
(:func:`.settling.settled_only`), saying which; when none is settled it names nothing (issue 18: "a loop that
has not settled is not physics"). ``diagnose_across`` fitted every experiment of every condition: a
low-amplitude loop still settling its centre at one condition left a misfit the joint selection read as
structure. Here the same rule per condition:

- given the condition's own diagnosis, the experiments it left out (recorded in its ``settings`` under
  :data:`.settling.LEFT_OUT`) stay out (its experiments and plain fit are the settled ones);
- without it, :func:`.settling.settled_only` on the condition's prepared experiments; when some drift,
  the condition's own judgement of the drift, as diagnose makes it (:func:`degrades`: ``diagnose`` of that
  condition with the candidates' drift terms). Degradation is not modelled across conditions (its test
  runs on period blocks), so a drift it explains is said, not hidden: the drifting experiments are left
  out *because the loop degrades* ("diagnose the condition alone"), never "not settled, and no
  degradation explains it", which was said without a test (session 31 review: a degrading specimen at
  one condition, named by diagnose, read "adequate ... at every condition");
- a condition whose own diagnosis names degradation is treated the same way (its experiments and plain
  fit are not reused: the joint selection on its degrading loops named Dahl friction on x);
- a condition with no settled experiment is left out of the joint structure (:class:`NotSettled`), and
  with fewer than two conditions left nothing is named (:func:`too_few`'s verdict).

The verdict says which experiments and conditions were left out (:func:`clause`), and the notes why
(:func:`.settling.left_out_note`, prefixed by the condition). A drift is said at diagnose's standard
(drift_said.records_drift, session 46): "still drifts" only when every record's trend test, Holm over the
condition's records (:func:`.settling.drift_p`), is below drift_said.FIRM, else "may drift" with each
record's adjusted p; the records that still ring (ring_down.py) are said as ringing, not drifting, and a
condition where most of the experiments ring is left out whole (:data:`RINGS`: diagnose names nothing from
such a set, ring_down.not_settled; counted per condition over its experiments, a measurement's segments
each one).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Sequence
from typing import Any, Optional

from .data import DiagExperiment
from .settling import LEFT_OUT, LEFT_OUT_P, drift_p, left_out_note, settled_only

#: Why experiments were left out (``_Group.left_why``, :class:`NotSettled`): degradation explains their
#: drift at the condition, or it was not tested (no drift term among the candidates); a whole condition:
#: most of its experiments still ring (ring_down.py).
DEGRADES, UNTESTED, RINGS = "degrades", "untested", "rings"

#: What a record that still rings holds (ring_down.not_settled's words).
RING = (
    "the free ring-down of the dynamics from the start of the record (a change from period to period that "
    "falls geometrically)"
)


class NotSettled(Exception):
    """No experiment of a condition has settled (or most still ring): the condition is left out of the joint
    structure. ``p``: each one's adjusted p of the trend test (NaN: not known, or left out as ringing)."""

    def __init__(self, label: str, names: Sequence[str], why: str = "", p: Sequence[float] = ()) -> None:
        super().__init__(f"{label}: not settled ({', '.join(names)})")
        self.label = label
        self.names = tuple(names)
        self.left_why = why
        self.p = tuple(p)
        self.total = len(names)


def why_own(own: Any) -> str:
    """Why the condition's own diagnosis left its experiments out: :data:`UNTESTED` when it had no drift term
    among its candidates (degradation not tested), else "" (tested, and none named)."""
    from .drift import DRIFT_TERMS

    cands = (own.settings or {}).get("candidates", DRIFT_TERMS)
    return "" if any(c in DRIFT_TERMS for c in cands) else UNTESTED


def names_degradation(d: Any) -> bool:
    """Whether the diagnosis ``d`` names degradation (diagnose's own rule: a drift term named, or its
    degradation test named, or passed when ``d`` ran without the held-out test)."""
    from .drift import DRIFT_TERMS

    deg = d.degradation  # a Diagnosis always has the field (None when the test was not formed)
    held_out = (d.settings or {}).get("held_out_test", True)
    named = deg is not None and deg.accepted(held_out)
    return named or any(t.term in DRIFT_TERMS for t in d.named)


def degrades(items: Any, cands: Sequence[str], alpha: float, held_out_test: bool) -> Optional[bool]:
    """The condition's own judgement of a drift: ``diagnose`` of its ``items`` with ``cands`` (the user's,
    drift terms included), whether it names degradation; None when no drift term is a candidate (not
    tested)."""
    from .drift import DRIFT_TERMS
    from .run import diagnose

    if not any(c in DRIFT_TERMS for c in cands):
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the condition's warnings are diagnose's to give
        d = diagnose(items, candidates=list(cands), alpha=alpha, held_out_test=held_out_test)
    return names_degradation(d)


def from_own(own: Any, label: str) -> tuple[str, ...]:
    """The experiments the condition's own diagnosis left out as not settled (its experiments are then the
    settled ones); raises :class:`NotSettled` when it left out every one."""
    left = tuple(str(s) for s in (own.settings or {}).get(LEFT_OUT, ()))
    if left and {e.source for e in own.experiments} <= set(left):
        raise NotSettled(label, left, p=own_p(own, left))
    return left


def own_p(own: Any, left: Sequence[str]) -> tuple[float, ...]:
    """Each of ``left``'s adjusted p as the condition's own diagnosis recorded it (settling.LEFT_OUT_P), NaN
    when it did not (a ring-down left out, or a diagnosis from before the p was kept)."""
    ps = list((own.settings or {}).get(LEFT_OUT_P, ()) or ())
    return tuple(float(v) for v in ps) if len(ps) == len(left) else (math.nan,) * len(left)


def drop(
    exps: Sequence[DiagExperiment],
    label: str,
    judge: Callable[[], Optional[bool]],
    ringing: frozenset[str] = frozenset(),
) -> tuple[list[DiagExperiment], tuple[str, ...], str, tuple[float, ...]]:
    """``exps`` without those whose loop still drifts (:func:`.settling.settled_only`) or still rings (their
    names in ``ringing``: a free ring-down of G, which diagnose leaves out as a drift no degradation
    explains, ring_down.py), their names, why (:data:`DEGRADES` when ``judge``, the condition's own
    judgement run only when some drift, names degradation; :data:`UNTESTED` when it did not test it; else
    "") and each one's adjusted p of the trend test (:func:`.settling.drift_p`; NaN for one that rings);
    raises :class:`NotSettled` when none is left, or when most ring (:data:`RINGS`: counted over this
    condition's experiments, as diagnose counts over the set it is given)."""
    from .drift_majority import most

    rung = [i for i, e in enumerate(exps) if e.source in ringing]
    if rung and (len(rung) == len(exps) or most(len(rung), len(exps))):
        err = NotSettled(label, [exps[i].source for i in rung], RINGS, [math.nan] * len(rung))
        err.total = len(exps)
        raise err
    keep, drifting = settled_only(exps, False)
    keep = [i for i in keep if i not in rung]
    left = sorted({*drifting, *rung})
    ps = drift_p(exps) if drifting else [math.nan] * len(exps)
    names = tuple(exps[i].source for i in left)
    p = tuple(math.nan if i in rung else ps[i] for i in left)
    why = ""
    if set(drifting) - set(rung):  # a drift beside the rings: the condition's own judgement of it
        verdict = judge()
        why = UNTESTED if verdict is None else DEGRADES if verdict else ""
    if not keep:
        raise NotSettled(label, names, why, p)
    return [exps[i] for i in keep], names, why, p


def said(names: Sequence[str], p: Sequence[float], rung: Sequence[str] = ()) -> str:
    """Why ``names`` were left out: the drifting ones at drift_said's standard (:func:`.drift_said.
    records_drift`: "still drifts" only when every adjusted ``p`` is firm, else "may drift", each record's p
    said), those in ``rung`` as still ringing."""
    from .drift_said import records_drift

    ps = list(p) if len(p) == len(names) else [math.nan] * len(names)
    drift = [(n, v) for n, v in zip(names, ps) if n not in rung]
    parts = []
    if drift and all(math.isfinite(v) for _, v in drift):
        parts.append(records_drift([n for n, _ in drift], [v for _, v in drift]))
    elif drift:  # no p known (a diagnosis that did not record it): its own words, not a fact of ours
        parts.append("the loop may not have settled (left out by the condition's own diagnosis)")
    ring = [n for n in names if n in rung]
    if ring:
        parts.append(f"{', '.join(ring)} still hold{'s' if len(ring) == 1 else ''} {RING}")
    return "; ".join(parts)


def _reason(why: str, names: Sequence[str] = (), p: Sequence[float] = (), rung: Sequence[str] = ()) -> str:
    """The words on why ``names`` were left out, after their names (:func:`said`'s on a drift)."""
    if why == DEGRADES:
        return (
            "the loop degrades: diagnose of that condition alone names degradation, which the structure "
            "across conditions does not model (its test runs on period blocks); diagnose the condition alone"
        )
    if why == UNTESTED:
        return (
            f"{said(names, p, rung)}: not settled; degradation was not tested (no drift term among the "
            "candidates); record more settling periods"
        )
    return said(names, p, rung)


def _note(
    label: str, names: Sequence[str], why: str, p: Sequence[float] = (), rung: Sequence[str] = ()
) -> str:
    """A condition's note on what was left out for a drift: diagnose's wording (:func:`.settling.
    left_out_note`, with each record's p) when the drift was tested and is no degradation's, else
    :func:`_reason`'s; "" when only ringing records were left out (ring_down's note says each)."""
    ps = list(p) if len(p) == len(names) else [math.nan] * len(names)
    drift = [(n, v) for n, v in zip(names, ps) if n not in rung]
    if not drift:
        return ""
    dn, dp = [n for n, _ in drift], [v for _, v in drift]
    if not why and all(math.isfinite(v) for v in dp):
        return f"{label}: {left_out_note(', '.join(dn), dn, dp)}"
    return f"{label}: left out of the diagnosis: {', '.join(dn)} ({_reason(why, dn, dp)})"


def _not_settled(u: NotSettled) -> str:
    """The verdict's word on a condition left out whole (:class:`NotSettled`)."""
    if u.left_why == DEGRADES:
        return f"; condition {u.label} left out ({_reason(DEGRADES)})"
    if u.left_why == RINGS:
        return (
            f"; condition {u.label} left out: {len(u.names)} of its {u.total} experiments "
            f"({', '.join(u.names)}) still hold {RING}; nothing is named from a loop that has not settled"
        )
    from .drift_said import firm

    sure = len(u.p) == len(u.names) and all(firm(v) for v in u.p)
    why = _reason(u.left_why, u.names, u.p)
    return (
        f"; condition {u.label} left out: no experiment there has settled ({why}); "
        f"nothing is named from a loop that {'has not' if sure else 'may not have'} settled"
    )


def clause(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> str:
    """The verdict's word on what was left out as not settled: experiments per condition (each drift at
    drift_said's standard, :func:`said`), whole conditions."""
    text = ""
    untested = " (degradation not tested: no drift term among the candidates)"
    parts = [
        f"{', '.join(g.left_out)} at {g.label} ({said(g.left_out, _p(g), _rung(g))})"
        + (untested if _why(g) == UNTESTED else "")
        for g in groups
        if g.left_out and _why(g) != DEGRADES
    ]
    if parts:
        text += f"; left out as not settled: {'; '.join(parts)}"
    for g in groups:
        if g.left_out and _why(g) == DEGRADES:
            text += f"; left out at {g.label}: {', '.join(g.left_out)} ({_reason(DEGRADES)})"
    return text + "".join(_not_settled(u) for u in unsettled)


def _p(g: Any) -> tuple[float, ...]:
    return tuple(getattr(g, "left_p", ()) or ())


def _rung(g: Any) -> tuple[str, ...]:
    return tuple(getattr(g, "rung", ()) or ())


def _why(g: Any) -> str:
    return str(getattr(g, "left_why", ""))


def notes(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> tuple[str, ...]:
    """Each condition's left-out note, as diagnose words it (:func:`.settling.left_out_note`); a condition
    left out because most of it rings has its rings' notes (across_ring.py) and the verdict's clause."""
    out = [_note(g.label, g.left_out, _why(g), _p(g), _rung(g)) for g in groups if g.left_out]
    out += [_note(u.label, u.names, u.left_why, u.p) for u in unsettled if u.left_why != RINGS]
    return tuple(n for n in out if n)


def too_few(groups: Sequence[Any], unsettled: Sequence[NotSettled]) -> Optional[str]:
    """The verdict when fewer than two conditions have a settled experiment: nothing is named (None when
    two or more are left: the joint selection runs)."""
    if len(groups) >= 2:
        return None
    n = len(groups) + len(unsettled)
    return (
        f"across {n} conditions: not settled: only {len(groups)} condition(s) with a settled experiment, "
        "and one structure across conditions needs two; nothing is named from a loop that has not settled "
        "(record more settling periods, or a longer record)" + clause(groups, unsettled)
    )


def measured_noise(items: Any, wander: Any) -> bool:
    """Whether every experiment's noise floor is measured noise (settling._noise_floors set none), of a
    condition's ``items`` and ``wander`` as across._group reads them."""
    from . import baseline
    from .data import prepare
    from .settling import _noise_floors, _settled

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        settled, _ = _settled(baseline.removed(items, wander))
    return not _noise_floors(settled, prepare(settled))[1]


__all__ = [
    "measured_noise",
    "NotSettled",
    "from_own",
    "why_own",
    "drop",
    "degrades",
    "names_degradation",
    "clause",
    "notes",
    "too_few",
]
