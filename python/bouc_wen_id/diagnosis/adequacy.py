"""One rule for every place a diagnosis says a model is adequate (session 37).

A diagnosis stated adequacy in four places with three rules: the status (the plain model's global test at
``alpha / 2``, gate.plain_passes, the other half being the targeted step's; a model with named terms at
``alpha``), the detection limits' voiding (limits_void.void, the same), and the localisation's
``adequate`` in the JSON (``before`` / ``after``) and its "where the model misses" words in the summary and
the HTML report (locate.LEVEL = 0.05 on the localisation's own p-value, whatever ``alpha`` the user set). A
plain model at p = 0.03 was "adequate" in the status and ``"after": {"adequate": false}`` with "where the
final model misses: spread over the cycle" in the same result.

The rule, here and in docs/diagnosis.md ("One rule for adequacy"): a model passes its adequacy test when its
p-value (:class:`.result.ModelSummary`'s ``p_value``: the status's own) is at least :func:`level`: ``alpha``
when the verdict names a term, ``alpha / 2`` when it names none (the plain model's global test); a loop
drifting from period to period (the plain model's ``drift_detected``) is not adequate whatever its p-value
(with named terms: a drift left beyond a named drift term, as the status weighs it). A status "adequate" or
"explained" implies the final model passes; the converse need not hold (a law that failed, a value outside
its physical range or held at a bound keep the status from them). The localisation's harmonics and regions
then only say where a model that fails misses.
"""

from __future__ import annotations

import math
from typing import Any

from . import gate

#: The adequacy test's level when a diagnosis carries none in its settings (run.diagnose's default).
DEFAULT_ALPHA = 0.05

#: The words for a model that passes its adequacy test, where the summary and the report say where it misses.
NOWHERE = "nowhere above the noise"


def alpha_of(d: Any) -> float:
    """The diagnosis' ``alpha`` (its settings'; :data:`DEFAULT_ALPHA` without)."""
    return float(getattr(d, "settings", {}).get("alpha", DEFAULT_ALPHA))


def level(alpha: float, named: bool) -> float:
    """The adequacy test's level: ``alpha`` for a model with named terms, ``alpha / 2`` for the plain model
    (gate.plain_passes: the other half is the targeted step's)."""
    return alpha if named else 0.5 * alpha


def passes(p_value: float, alpha: float, named: bool, drifting: bool = False) -> bool:
    """Whether a model at ``p_value`` passes its adequacy test (:func:`level`), not drifting; the plain
    model's is the status's own gate (:func:`.gate.plain_passes`)."""
    if not named:
        return gate.plain_passes(p_value, alpha, moved=drifting)
    return bool(math.isfinite(p_value) and p_value >= alpha and not drifting)


def final_passes(d: Any) -> bool:
    """Whether ``d``'s final model passes its adequacy test (its named terms decide the level). Drifting as
    the status weighs it: with named terms, a drift left beyond a named drift term (drift_clause.beyond,
    which makes "explained" "explained in part"); with none, the plain model's loop drifting (its gate's
    ``moved``)."""
    from . import drift_clause  # here: drift_clause imports result, which imports this module
    from .left_out import not_judged

    if not_judged(d):
        return False
    named = tuple(getattr(d, "named", ()))
    after, before = getattr(d, "after", None), getattr(d, "before", None)
    if named and after is not None and before is not None:
        drifting = drift_clause.beyond(drift_clause.clause(after, before, named))
    else:
        drifting = not named and bool(getattr(before, "drift_detected", False))
    return passes(float(d.final.p_value), alpha_of(d), bool(named), drifting)


def plain_passes(d: Any) -> bool:
    """Whether ``d``'s plain model passes its global test (at ``alpha / 2``), not drifting."""
    from .left_out import not_judged

    if not_judged(d):
        return False
    before = getattr(d, "before", None)
    drifting = bool(getattr(before, "drift_detected", False))
    return passes(float(d.plain.p_value), alpha_of(d), False, drifting)


def where(d: Any, final: bool) -> str:
    """Where the final (``final``) or plain model misses, in words: :data:`NOWHERE` when it passes its
    adequacy test (:func:`final_passes` / :func:`plain_passes`), else its localisation's description."""
    from .left_out import not_judged

    ok = final_passes(d) if final else plain_passes(d)
    loc = d.after if final else d.before
    if ok:
        return NOWHERE
    if not_judged(d):
        return f"not judged: {not_judged(d)}"
    return loc.describe() or "spread over the cycle"


def localisation_dict(d: Any, final: bool) -> dict[str, Any]:
    """The localisation's JSON (``before`` / ``after``) with ``adequate`` by this module's rule, the level
    it was tested at, the records it was judged on and why it was not judged (left_out.py; '' when it
    was), and no harmonic flagged on a model that passes (closed testing, as locate.py)."""
    from .left_out import judged_on, not_judged

    loc = d.after if final else d.before
    out: dict[str, Any] = dict(loc.to_dict())
    ok = final_passes(d) if final else plain_passes(d)
    out["adequate"] = ok
    out["adequacy_level"] = level(alpha_of(d), final and bool(getattr(d, "named", ())))
    out["adequacy_p_value"] = float((d.final if final else d.plain).p_value)
    out["judged_on"] = list(judged_on(d))
    out["not_judged"] = not_judged(d)
    if ok:
        out["harmonics"] = [{**h, "significant": False} for h in out["harmonics"]]
        out["where"] = NOWHERE
    return out


__all__ = [
    "DEFAULT_ALPHA",
    "NOWHERE",
    "alpha_of",
    "final_passes",
    "level",
    "localisation_dict",
    "passes",
    "plain_passes",
    "where",
]
