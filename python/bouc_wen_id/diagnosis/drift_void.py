"""A step of the drift correction that cannot be simulated: void, with the sentence that says why.

The correction (``drift.corrected``) simulates the fitted hysteresis with the drift term from rest through
each record; its inputs are the diagnosis's own fits, not the user's data. A degenerate fit can ask for a
simulation the library refuses: review 44's feedback plant (config D) reached mu = 22.8 with beta = -gamma
and d = 38.8 after one correction pass, whose loop overflows (``NonFiniteError``), and an age of 796551
periods asked for 2e8 samples (``BudgetExceededError``). Issue 18: "no crash on any shipped file"; every
statistic is valid or says why not. So the step is void, its sentence goes into the notes, and the
diagnosis goes on without it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Optional, TypeVar

from .. import budget
from ..errors import BoucWenIdError, BudgetExceededError
from .drift import DEGRADATION

T = TypeVar("T")


def attempt(
    step: Callable[[], Optional[T]], void: Callable[[BoucWenIdError], str], notes: list[str]
) -> Optional[T]:
    """``step()``, or None with ``void(error)`` in ``notes`` when it raises one of the library's own errors.

    A budget the user tightened below the defaults is theirs (issue 19: a budget stop is never read as a
    failed step): its error is raised. At the defaults or above, a step that asks for more is absurd (an
    age of 796551 periods) and is void like a simulation that blows up.
    """
    try:
        return step()
    except BudgetExceededError as exc:
        if _tightened():
            raise
        notes.append(void(exc))
    except BoucWenIdError as exc:
        notes.append(void(exc))
    return None


def _tightened() -> bool:
    """Whether some limit in force is below its default."""
    now = budget.get_budget()
    return (
        now.max_samples < budget.DEFAULT_MAX_SAMPLES
        or now.max_steps < budget.DEFAULT_MAX_STEPS
        or now.max_bytes < budget.DEFAULT_MAX_BYTES
    )


def why(exc: BoucWenIdError) -> str:
    """What the simulation could not do: the error's first clause (its advice, to change the parameters or
    raise a budget, is for a caller's own simulation, not for the diagnosis's fits)."""
    return str(exc).split(";")[0].strip()


def virgin(term: str) -> str:
    """What the correction brings the averaged periods back to, for ``term``."""
    return "virgin strength" if term == DEGRADATION else "virgin stiffness"


def ages_void(exc: BoucWenIdError) -> str:
    """The note when the unrecorded ages (age.py) cannot be simulated."""
    return (
        f"unrecorded ages: not fitted, the records are taken to start as declared (the step is void: the "
        f"simulation of an age could not run, {why(exc)})"
    )


def correction_void(exc: BoucWenIdError, term: str) -> str:
    """The note when the correction of the averaged periods cannot be simulated."""
    return (
        f"the averaged periods are used as recorded, not brought back to the {virgin(term)}: the drift "
        f"correction could not be simulated at the fitted drift ({why(exc)}), so the {term} rests on the "
        "block record's first-order test alone (its value not refined)"
    )


__all__ = ["attempt", "why", "virgin", "ages_void", "correction_void"]
