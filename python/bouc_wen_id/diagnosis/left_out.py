"""The records a diagnosis left out of its statistics, said in its JSON, its summary, its report and its
verdict's headline (session 38, drifthonest).

A record whose loop still drifts from period to period, with no degradation to explain it
(settling.settled_only), is left out, and the settled ones are diagnosed alone (run._without_unsettled).
The left-out records were only in prose and in ``settings["left_out"]`` (names without a reason), and the
verdict's status and the JSON's adequacy were decided by two rules: a merge review found a drifting case
with the status "unexplained" (most records left out: drift_majority.py) beside ``"before": {"adequate":
true}``, computed on the settled records alone; and, with a minority left out, a bare "adequate: the plain
Wiener-Bouc-Wen model fits at the noise floor" headline whose records were not those the user gave.

Here: :func:`records` lists each left-out record with its reason and the statistics it was left out of
(the JSON's ``left_out_records``); :func:`judged_on` names the records the statistics were computed on; when
the status was not decided on the settled records (every one, or all but one, or most of them left out:
run._without_unsettled sets ``settings["not_judged"]``, the one place that rule lives), adequacy.py's rule
reads :func:`not_judged` and the JSON's ``adequate`` is false with the reason, as the status is not
"adequate". Otherwise :func:`qualified` gives the headline the records it was judged on and, as its second
clause, the left-out ones with what to do ("adequate on recording 0, recording 1: ...; recording 2,
recording 3 left out (not settled, ...): record more settling periods ..."). A drift that degradation
explains leaves nothing out: it is named, and nothing here applies.
"""

from __future__ import annotations

import html
from dataclasses import replace
from typing import Any, TypeVar

from . import deg_unnamed
from .drift_said import firm
from .settling import LEFT_OUT, LEFT_OUT_P, left_out_tail
from .verdict_text import clauses

#: Where run._without_unsettled says why the status was not decided on the settled records (settings key).
NOT_JUDGED = "not_judged"
#: The reason code of a record left out as still drifting (settling._unsettled).
UNSETTLED = "unsettled"
#: What the reason means (the drift test cannot tell the two readings apart: settling.left_out_note).
UNSETTLED_DETAIL = (
    "the loop still drifts from period to period and no degradation explains it: a transient not yet "
    "settled, or a sensor whose gain or zero drifts over the record"
)
#: The same when the record's adjusted p is not below drift_said.FIRM: a drift is evidence, not a fact.
UNSETTLED_MAY = (
    "the loop may drift from period to period and no degradation explains it: a transient not yet "
    "settled, or a sensor whose gain or zero drifts over the record"
)
#: The statistics such a record is left out of (it took part only in the drift tests that left it out).
UNSETTLED_OF = (
    "plain fit",
    "adequacy test",
    "term selection",
    "localisation",
    "degradation test",
    "detection limits",
    "held-out check",
)
#: What to do about a record left out as not settled.
WHAT_TO_DO = (
    "record more settling periods (a longer record), or check the sensor's calibration over the record"
)

_D = TypeVar("_D")


def left(d: Any) -> tuple[str, ...]:
    """The records ``d`` left out as not settled (``settings["left_out"]``), in order."""
    return tuple(str(s) for s in (getattr(d, "settings", None) or {}).get(LEFT_OUT, ()))


def p_adjusted(d: Any) -> tuple[float, ...]:
    """Each left-out record's adjusted p of the trend test (``settings["left_out_p"]``, settling.drift_p),
    in :func:`left`'s order; () when unknown (a ring-down, a diagnosis from before session 45)."""
    ps = tuple(float(p) for p in (getattr(d, "settings", None) or {}).get(LEFT_OUT_P, ()))
    return ps if len(ps) == len(left(d)) else ()


def judged_on(d: Any) -> tuple[str, ...]:
    """The records ``d``'s statistics were computed on: its experiments less those left out."""
    out = left(d)
    return tuple(e.source for e in getattr(d, "experiments", ()) if e.source not in out)


def not_judged(d: Any) -> str:
    """Why ``d``'s status was not decided on the records it was judged on ('' when it was)."""
    return str((getattr(d, "settings", None) or {}).get(NOT_JUDGED, ""))


def records(d: Any) -> list[dict[str, Any]]:
    """Each record left out of a statistic: its name, the reason, what that means, the statistics, and
    the trend test's adjusted p when known (the detail says "may drift" when it is not firm)."""
    ps = p_adjusted(d)
    out: list[dict[str, Any]] = []
    for i, s in enumerate(left(d)):
        row: dict[str, Any] = {"record": s, "reason": UNSETTLED, "detail": UNSETTLED_DETAIL}
        if ps:
            row["p_adjusted"] = ps[i]
            row["detail"] = UNSETTLED_DETAIL if firm(ps[i]) else UNSETTLED_MAY
        row["detail"] = deg_unnamed.detail(row["detail"], getattr(d, "settings", None))
        out.append({**row, "left_out_of": list(UNSETTLED_OF)})
    return out


def _tail(names: tuple[str, ...], ps: tuple[float, ...] = ()) -> str:
    """The clause the verdict ended with (run._without_unsettled, centre_decay.check)."""
    return f"{', '.join(names)} {left_out_tail(ps)}"


def _on(head: str, status: str, kept: str) -> str:
    """``head`` (the verdict's first clause) with the records it was judged on after its status word."""
    word = {"partly explained": "explained in part"}.get(status, status)
    after = head[len(word) :]
    if head.startswith(word) and (after[:1] in (":", "") or after.startswith(" by")):
        return f"{word} on {kept}{after}"
    # "unexplained structure remains at ...": the records go after the whole clause, not inside the phrase
    return f"{head} (judged on {kept})"


def qualified(d: _D) -> _D:
    """``d`` whose headline names the records it was judged on, and whose second clause the records left
    out with what to do, when some were left out and the status was decided on the others; else ``d``."""
    out, status = left(d), str(getattr(d, "status", ""))
    kept = judged_on(d)
    if not out or not kept or not_judged(d):
        return d
    parts = clauses(str(getattr(d, "verdict", "")))
    if not parts:
        return d
    tail = _tail(out, p_adjusted(d))
    rest = [c for c in parts[1:] if c not in (tail, _tail(out))]
    head = _on(parts[0], status, ", ".join(kept))
    verdict = "; ".join([head, f"{tail}: {WHAT_TO_DO}", *rest])
    return replace(d, verdict=verdict)  # type: ignore[type-var]


def to_dict(d: Any) -> dict[str, Any]:
    """The JSON's keys: ``left_out_records`` (:func:`records`) and ``judged_on`` (:func:`judged_on`)."""
    return {"left_out_records": records(d), "judged_on": list(judged_on(d))}


def summary_lines(d: Any) -> list[str]:
    """The summary's lines on the records left out ([] when none)."""
    lines = [
        f"left out: {r['record']} ({r['reason']}: {r['detail']}{_p_text(r)}; left out of: "
        f"{', '.join(r['left_out_of'])})"
        for r in records(d)
    ]
    if lines:
        lines.append(f"judged on: {', '.join(judged_on(d)) or 'no record'}")
    return lines


def _p_text(r: dict[str, Any]) -> str:
    """ ", trend test adjusted p = ..." for a record with its p, else ''."""
    return f", trend test adjusted p = {r['p_adjusted']:.2g}" if "p_adjusted" in r else ""


def report_html(d: Any) -> list[str]:
    """The report's section on the records left out ([] when none)."""
    rows = "".join(
        f"<li>{html.escape(r['record'])}: {html.escape(r['reason'])} "
        f"({html.escape(r['detail'] + _p_text(r))}); left out of: "
        f"{html.escape(', '.join(r['left_out_of']))}</li>"
        for r in records(d)
    )
    if not rows:
        return []
    on = html.escape(", ".join(judged_on(d)) or "no record")
    return [f"<h2>Records left out</h2><p>Judged on: {on}.</p><ul>{rows}</ul>"]


__all__ = [
    "NOT_JUDGED",
    "UNSETTLED",
    "UNSETTLED_DETAIL",
    "UNSETTLED_MAY",
    "UNSETTLED_OF",
    "WHAT_TO_DO",
    "judged_on",
    "left",
    "not_judged",
    "p_adjusted",
    "qualified",
    "records",
    "report_html",
    "summary_lines",
    "to_dict",
]
