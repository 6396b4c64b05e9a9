"""``Diagnosis.to_model``: the diagnosed model as a fitted plant, with G, that can be saved and used.

Why this module: the diagnosis's own fits (``final_fit``) hold a gain and a phase per experiment, not a G:
nothing to save, export, validate or compensate with. The model the diagnosis describes is the Wiener
cascade with the named terms, and the library fits that to records with
:func:`~bouc_wen_id.fit_time_domain`; this module makes the call the diagnosis implies:

* the **terms** are the named ones, each starting at the value the diagnosis gave it (clipped into the
  search's box), so the search starts where the steady loops already put it;
* the **start G** is the sine path's (identify, then ``fit_transfer_function`` of several orders, each
  screened with the terms: ``timedomain._starts``);
* each record's **settling** is left out as ``identify`` and ``diagnose`` leave it out: the lead-in is the
  shortest declared settling (``settle_periods`` periods) among the sine recordings, because a record
  whose first sample is not rest (a cosine switched on, a delay whose input before the record is not
  zero) otherwise leaves its initial transient in the residuals, where G's order and the terms trade
  against it. (The initial hysteretic state is not fitted: after the settling the loop has forgotten it,
  and a ``w0`` the data do not pin would only spoil a simulation from the record's start.)

A diagnosis that named a structure (Bouc-Wen in feedback, ``structure``) describes another model class:
refused by name, with the fit that makes it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from ..errors import InvalidParameterError
from ..model import Recording
from ..terms import Term
from ..timedomain._records import TimeRecord, settling_lead_in
from ..timedomain._terms import term_bounds, term_class

if TYPE_CHECKING:  # pragma: no cover - typing only
    from ..timedomain import TimeDomainFit
    from .result import Diagnosis


def named_term_starts(diagnosis: Diagnosis) -> tuple[Term, ...]:
    """The named terms as term instances at the diagnosis's values (clipped into the search's box); a
    value the term refuses, or one that is not finite, starts the term at 0 instead."""
    out: list[Term] = []
    for named in diagnosis.named:
        cls = term_class(named.term)
        lo, hi = term_bounds(cls)
        value = min(max(named.value, lo), hi) if math.isfinite(named.value) else 0.0
        try:
            out.append(cls(value))  # type: ignore[call-arg]
        except (InvalidParameterError, ValueError, TypeError):
            out.append(cls(0.0))  # type: ignore[call-arg]
    return tuple(out)


def diagnosis_model(diagnosis: Diagnosis, recordings: Sequence[Any], **options: Any) -> TimeDomainFit:
    """The model the diagnosis describes, fitted to ``recordings``: see :meth:`Diagnosis.to_model`."""
    from ..timedomain import fit_time_domain

    if diagnosis.structure is not None and getattr(diagnosis.structure, "named", False):
        raise InvalidParameterError(
            "this diagnosis named a structure (Bouc-Wen in feedback), not terms of the cascade: fit it with "
            "bouc_wen_id.fit_feedback, not to_model"
        )
    if "terms" in options:
        raise InvalidParameterError("to_model fits the named terms; call fit_time_domain for other terms")
    from ..measurement import Measurement

    recs: list[Any] = (
        list(recordings) if not isinstance(recordings, (Recording, Measurement)) else [recordings]
    )
    # A lab Measurement is a raw record from its first sample (review 36b: diagnose FILES --model on lab
    # CSV files refused it and lost the report): fitted as it was recorded, its time in seconds.
    recs = [TimeRecord(r.t, r.u, r.y, name=r.name) if isinstance(r, Measurement) else r for r in recs]
    for i, r in enumerate(recs):
        if not isinstance(r, (Recording, TimeRecord, tuple)):
            raise InvalidParameterError(
                f"recordings[{i}] is a {type(r).__name__}: to_model fits the raw records (Recording, "
                "Measurement, TimeRecord or (t, u, y))"
            )
    options.setdefault("lead_in", settling_lead_in(recs))
    return fit_time_domain(recs, terms=named_term_starts(diagnosis), **options)
