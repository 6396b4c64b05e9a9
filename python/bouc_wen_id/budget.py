"""Work and memory budgets: every public entry estimates its cost first and refuses beyond a limit.

A hostile or careless size (``samples_per_period=10**7``, ``substeps=10**12``, ``phase_grid=10**8``, a
small NPZ file that inflates to gigabytes) is refused in microseconds with a
:class:`~bouc_wen_id.errors.BudgetExceededError` that says the size and how to raise the limit, instead of
running for hours or filling the memory.

Three process-wide limits (shared with the Rust core, ``rust/budget.rs``):

``max_samples``
    Samples of one signal a call creates or reads (default ``2**24``, 16.8 M: 134 MB per float64 array).
``max_steps``
    Elementary steps of one call: RK4 steps for the simulations and steady loops, one pass over a
    period's samples for the searches (default ``10**9``, about a minute).
``max_bytes``
    Memory one call may allocate, or a file may inflate to when it is read (default ``2**31``, 2 GiB).

Set them with :func:`set_budget`, temporarily with :func:`budget`, or before the process starts with the
environment variables ``BOUC_WEN_ID_MAX_SAMPLES``, ``BOUC_WEN_ID_MAX_STEPS`` and ``BOUC_WEN_ID_MAX_BYTES``
(these also reach the command line tool).

Examples
--------
>>> from bouc_wen_id import budget
>>> with budget.budget(max_steps=10**10):  # a long simulation, on purpose
...     pass
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Optional

from ._backend import push_budget
from .errors import BudgetExceededError, InvalidParameterError
from .validation import count

__all__ = [
    "Budget",
    "get_budget",
    "set_budget",
    "budget",
    "check_samples",
    "check_steps",
    "check_bytes",
    "check_environment",
]

#: Defaults, equal to rust/budget.rs DEFAULT_MAX_*.
DEFAULT_MAX_SAMPLES = 1 << 24
DEFAULT_MAX_STEPS = 1_000_000_000
DEFAULT_MAX_BYTES = 1 << 31
#: Largest RK4 steps per sample interval (rust/budget.rs MAX_SUBSTEPS, fixed).
MAX_SUBSTEPS = 1 << 20
_LIMIT_CEILING = 2**64 - 1


@dataclass(frozen=True)
class Budget:
    """The limits in force (see the module docstring for their meaning)."""

    max_samples: int
    max_steps: int
    max_bytes: int


_current = Budget(DEFAULT_MAX_SAMPLES, DEFAULT_MAX_STEPS, DEFAULT_MAX_BYTES)


def _positive_int(name: str, value: object) -> int:
    return count(f"budget {name}", value, 1, _LIMIT_CEILING)


def _push(b: Budget) -> None:
    """Writes the limits into the Rust core (the NumPy reference is held to ``_current`` in Python)."""
    push_budget(b.max_samples, b.max_steps, b.max_bytes)


def get_budget() -> Budget:
    """The limits in force (:class:`InvalidParameterError` while a ``BOUC_WEN_ID_MAX_*`` variable is bad)."""
    check_environment()
    return _current


def set_budget(
    *, max_samples: Optional[int] = None, max_steps: Optional[int] = None, max_bytes: Optional[int] = None
) -> Budget:
    """Set some limits (the others keep their value); return the previous :class:`Budget`.

    Raises
    ------
    InvalidParameterError
        A limit that is not an integer in ``[1, 2**64 - 1]``.
    """
    global _current, _environment_error
    old = _current
    new = Budget(
        _positive_int("max_samples", old.max_samples if max_samples is None else max_samples),
        _positive_int("max_steps", old.max_steps if max_steps is None else max_steps),
        _positive_int("max_bytes", old.max_bytes if max_bytes is None else max_bytes),
    )
    _push(new)
    _current = new
    _environment_error = None
    return old


@contextmanager
def budget(
    *, max_samples: Optional[int] = None, max_steps: Optional[int] = None, max_bytes: Optional[int] = None
) -> Iterator[Budget]:
    """Context manager: the given limits inside the ``with`` block, the previous ones after it.

    The limits are process-wide, not per thread: do not change them while another thread computes.
    """
    old = set_budget(max_samples=max_samples, max_steps=max_steps, max_bytes=max_bytes)
    try:
        yield _current
    finally:
        set_budget(max_samples=old.max_samples, max_steps=old.max_steps, max_bytes=old.max_bytes)


def _refuse(what: str, size: int, unit: str, name: str, limit: int) -> BudgetExceededError:
    return BudgetExceededError(
        f"budget exceeded: {what} needs {size} {unit}, above the budget {name} = {limit}; reduce the "
        f"request, or raise the limit with bouc_wen_id.budget.set_budget({name}=...) or the environment "
        f"variable BOUC_WEN_ID_{name.upper()}"
    )


def check_samples(what: str, n: int) -> None:
    """Refuse ``n`` samples of one signal above ``max_samples`` (:class:`BudgetExceededError`)."""
    check_environment()
    if n > _current.max_samples:
        raise _refuse(what, n, "samples", "max_samples", _current.max_samples)


def check_steps(what: str, steps: int) -> None:
    """Refuse ``steps`` elementary steps above ``max_steps`` (:class:`BudgetExceededError`)."""
    check_environment()
    if steps > _current.max_steps:
        raise _refuse(what, steps, "steps", "max_steps", _current.max_steps)


def check_bytes(what: str, n_bytes: int) -> None:
    """Refuse ``n_bytes`` of memory above ``max_bytes`` (:class:`BudgetExceededError`)."""
    check_environment()
    if n_bytes > _current.max_bytes:
        raise _refuse(what, n_bytes, "bytes", "max_bytes", _current.max_bytes)


def check_simulation(n_samples: int, substeps: int) -> None:
    """The cost of one RK4 simulation of ``n_samples`` samples (as rust/budget.rs check_simulation)."""
    check_environment()
    if substeps > MAX_SUBSTEPS:
        raise BudgetExceededError(
            f"budget exceeded: substeps = {substeps} is above {MAX_SUBSTEPS} RK4 steps per sample interval, "
            "where the step error is long at rounding; use fewer substeps or a finer sample grid"
        )
    check_samples("the simulation", n_samples)
    # Python's simulate keeps t, u, x, w, noise and y: six float64 arrays.
    check_bytes("the simulation's six signals", 48 * n_samples)
    check_steps("the simulation", max(n_samples - 1, 0) * max(substeps, 0))


#: A bad ``BOUC_WEN_ID_MAX_*`` value found at import: raised by every budget check (and :func:`get_budget`)
#: until the limits are set with :func:`set_budget`, never at import (issue 19: a raw traceback there).
_environment_error: Optional[InvalidParameterError] = None


def _parse_environment(name: str, raw: str) -> int:
    """The integer a ``BOUC_WEN_ID_MAX_*`` variable holds (``"1e9"`` allowed), checked as by set_budget."""
    var = f"BOUC_WEN_ID_{name.upper()}"
    try:
        number = float(raw) if "e" in raw.lower() else int(raw)
    except ValueError:
        raise InvalidParameterError(f"environment variable {var} = {raw!r} is not an integer") from None
    if isinstance(number, float) and not (number.is_integer() and 1 <= number <= _LIMIT_CEILING):
        raise InvalidParameterError(
            f"environment variable {var} = {raw!r} must be an integer in [1, 2**64 - 1]"
        )
    try:
        return _positive_int(name, int(number))
    except InvalidParameterError as exc:
        raise InvalidParameterError(f"environment variable {var} = {raw!r}: {exc}") from None


def _from_environment() -> None:
    global _environment_error
    values: dict[str, int] = {}
    try:
        for name in ("max_samples", "max_steps", "max_bytes"):
            raw = os.environ.get(f"BOUC_WEN_ID_{name.upper()}")
            if raw is None or not raw.strip():
                continue
            values[name] = _parse_environment(name, raw.strip())
        set_budget(**values)
    except InvalidParameterError as exc:
        # Not at import: the first call that consults a budget names the variable (the defaults stay in
        # the core meanwhile; set_budget clears it).
        _environment_error = exc


def check_environment() -> None:
    """Raise the :class:`InvalidParameterError` of a bad ``BOUC_WEN_ID_MAX_*`` variable, if one was found."""
    if _environment_error is not None:
        raise InvalidParameterError(
            f"{_environment_error}; fix or unset it (the budgets are not in force until then), or set the "
            "limits with bouc_wen_id.budget.set_budget(...)"
        )


_from_environment()
