"""Where the ring-down check could not run: recorded always, said in the notes only where it matters.

:func:`.ring_down.rings` reads a lab segment's first :data:`.ring_down.LEAST_PERIODS` whole periods; the real
lab records (the MR damper, the friction damper, the wire rope, the microwire) hold 1-7 periods a segment, so
session 45's note "a free ring-down ... was not checked" was in every real data set's notes: a caveat that
fires on every case says nothing (session 46).

What a free ring-down of G left in the averaged periods misleads is a reading of the loop's change from
period to period (ring_down.py: review 44's design D read as stiffness degradation; its records left out as
not settled): a drift term or degradation named, or records left out because their loop drifts. The
segments not checked are recorded in the settings under :data:`KEY` (which ones, and what to do) on every
diagnosis; the notes say them only when the diagnosis read such a drift (:func:`drift_read`): there the
drift may be the ring-down the check could not see. A steady loop read from short segments gets no note:
the signal analysis's steady-segment test refuses a stretch still ringing strongly (ring_down.py), and
nothing in its verdict rests on a change from period to period.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any, TypeVar

from .ring_down import LEAST_PERIODS

_D = TypeVar("_D")

#: Where a diagnosis records the segments the ring-down check could not read (its ``settings``).
KEY = "ring_down_unchecked"

#: What to do about it, said with the segments.
TODO = f"record steady segments of at least {LEAST_PERIODS} whole periods to check it"


def note(short: Sequence[str], drift: str) -> str:
    """The note on the segments ``short`` ("name (periods)") not checked, when the diagnosis read ``drift``
    (what it read of a change from period to period)."""
    return (
        f"{drift}, but a free ring-down of the dynamics before the hysteresis, which falls from period to "
        f"period as a drift does, was not checked in the steady segments shorter than the {LEAST_PERIODS} "
        f"whole periods its test reads: {', '.join(short)} (only the signal analysis's steady-segment test "
        f"looked for a transient there); {TODO}"
    )


def drift_read(d: Any, rung: Sequence[Any] = ()) -> str:
    """What the diagnosis ``d`` (a Diagnosis) read of a change of the loop from period to period: a drift
    term or degradation named, records left out as drifting (not those found ringing, ``rung``: their
    ring-down was checked and said); "" when nothing."""
    from .drift import DRIFT_TERMS
    from .settling import LEFT_OUT

    named = [t.term for t in d.named if t.term in DRIFT_TERMS]
    deg = d.degradation
    if named or (deg is not None and deg.accepted((d.settings or {}).get("held_out_test", True))):
        return (
            "the diagnosis names a drift of the loop from period to period ("
            + (", ".join(named) or "its degradation test")
            + ")"
        )
    ringing = {r.source for r in rung}
    left = [s for s in (d.settings or {}).get(LEFT_OUT) or () if s not in ringing]
    if left:
        return f"records were left out as drifting from period to period ({', '.join(map(str, left))})"
    return ""


def said(d: _D, short: Sequence[str], drift: str) -> _D:
    """``d`` (a Diagnosis or an AcrossDiagnosis) with the segments ``short`` in its settings (:data:`KEY`),
    and in its notes when ``drift`` (what it read of a change from period to period) is not ""."""
    if not short:
        return d
    settings = {**(getattr(d, "settings", None) or {}), KEY: {"segments": list(short), "what_to_do": TODO}}
    notes = (*getattr(d, "notes", ()), note(short, drift)) if drift else getattr(d, "notes", ())
    return replace(d, settings=settings, notes=notes)  # type: ignore[type-var]


__all__ = ["KEY", "TODO", "drift_read", "note", "said"]
