"""The library's terms in the time-domain Wiener class (issue #20): which ones, their bounds, their Jacobian.

Every term of the registry (:data:`~bouc_wen_id.terms.TERMS`) that the time-domain simulator takes is fitted,
at every place the registry allows (on u, inside the hysteresis, on x): the list is derived from the
registry, so a new term with a simulation form is fitted without an edit here. A term with no time-domain
meaning (the input distortion: in a record the measured input itself drives the model) is refused by name.

Two Jacobians:

* **exact** (the dual-number kernel ``timedomain_sensitivities`` plus the regressor columns): when every
  fitted term is one of :data:`REGRESSOR_TERMS`, the output terms on u whose output is ``value x
  regressor`` with a regressor fixed by the data (``1, u, udot, uddot``);
* **central differences of the discrete map** otherwise: the whole model (G, Bouc-Wen and the terms with
  their states) is simulated by the library's simulator with terms (``simulate_sampled(..., terms=)``,
  the map ``simulate_input`` runs, Rust or its NumPy oracle) at ``theta +- h_i e_i``,
  ``h_i = FD_STEP max(|theta_i|, s_i)`` with ``s_i`` the parameter's natural scale (the term's own units
  from :meth:`~bouc_wen_id.terms.Term.scale_factor` at the data's output and input RMS); one-sided at a
  bound. For the smooth terms that is the derivative of the same discrete map to ~1e-8 relative; for play
  (the backlash's mode switches and clamp are non-smooth in ``x``) the map is piecewise smooth in the
  parameters and the difference is the one-sided derivative almost everywhere (a step that straddles a
  switch of the mode at some sample averages the two sides there).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError, NonFiniteError
from ..terms import TERMS, Inertia, Offset, SensorLag, Stiffness, Term, Viscous, core_terms

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

#: Output terms on u with an exact regressor column (``y = ... + value * regressor(u)``).
REGRESSOR_TERMS: tuple[type[Term], ...] = (Offset, Stiffness, Viscous, Inertia)
#: Relative step of the central differences.
FD_STEP = 1e-6


def _sample(cls: type[Term]) -> Term:
    """An admissible instance of ``cls`` (0 where 0 is admissible, else the lower bound, else 1)."""
    lo = cls.bounds[0]
    last: Exception = InvalidParameterError(f"{cls.kind}: no admissible value found")
    for v in (0.0, lo if math.isfinite(lo) else 0.0, 1.0):
        try:
            return cls(v)  # type: ignore[call-arg]
        except (InvalidParameterError, TypeError) as exc:
            last = exc
    raise last


def _why_not(cls: type[Term]) -> Optional[str]:
    """None when the simulator's term list takes ``cls`` and the fit can free it alone, else the reason."""
    if cls.companion or cls.part_of:  # Dahl friction: simulated, but its two parameters are one element
        return (
            f"{cls.label!r} is one parameter of a two-parameter element (with "
            f"{cls.companion or cls.part_of!r}), which the simulator integrates but this fit frees term by "
            "term (alone, one parameter has no effect while the other is 0); fit it on averaged periods "
            "(identify_augmented, diagnose)"
        )
    try:
        core_terms([_sample(cls)])
    except (InvalidParameterError, TypeError) as exc:
        return str(exc)
    return None


def time_domain_terms() -> tuple[type[Term], ...]:
    """The registry's terms that have a time-domain form, in the registry's order."""
    return tuple(cls for cls in TERMS.values() if _why_not(cls) is None)


def refuse(cls: type[Term]) -> InvalidParameterError:
    """The named refusal of a term without a time-domain form."""
    why = _why_not(cls) or "it has no time-domain form here"
    return InvalidParameterError(
        f"the term {cls.kind!r} cannot be fitted in the time domain: {why}. The time-domain terms are "
        f"{', '.join(c.kind for c in time_domain_terms())}"
    )


def term_class(item: object) -> type[Term]:
    """A term class from a class, an instance or a code name of the registry (any place)."""
    if isinstance(item, Term):
        return type(item)
    if isinstance(item, type) and issubclass(item, Term):
        return item
    if isinstance(item, str) and item in TERMS:
        return TERMS[item]
    raise InvalidParameterError(
        f"terms: {item!r} is not a term class, a term or a code name; the time-domain terms are "
        f"{', '.join(c.kind for c in time_domain_terms())}"
    )


def term_bounds(cls: type[Term]) -> tuple[float, float]:
    """The search box of a term's value: its admissible range within its physical range (registry)."""
    lo = max(cls.bounds[0], cls.physical[0])
    hi = min(cls.bounds[1], cls.physical[1])
    return lo, hi


def term_memory(terms: Sequence[Term]) -> float:
    """Memory the terms add to G's (s): three time constants of a sensor lag."""
    return sum(3.0 * t.value for t in terms if isinstance(t, SensorLag))


def difference_jacobian(
    simulate: Callable[[FloatArray], FloatArray],
    theta: FloatArray,
    free: BoolArray,
    scales: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
) -> tuple[FloatArray, FloatArray]:
    """``(y, J)``: ``y = simulate(theta)`` and its central-difference Jacobian on the free columns (the held
    columns are 0). A difference that cannot be simulated on one side is taken on the other; on neither
    side the column is NaN (the caller's search rejects the point)."""
    y = simulate(theta)
    jac = np.zeros((y.size, theta.size))
    for i in (int(k) for k in np.flatnonzero(free)):
        h = FD_STEP * max(abs(float(theta[i])), float(scales[i]))
        up = theta[i] + h <= upper[i]
        down = theta[i] - h >= lower[i]
        y_hi = _try(simulate, theta, i, h) if up else None
        y_lo = _try(simulate, theta, i, -h) if down else None
        if y_hi is not None and y_lo is not None:
            jac[:, i] = (y_hi - y_lo) / (2.0 * h)
        elif y_hi is not None:
            jac[:, i] = (y_hi - y) / h
        elif y_lo is not None:
            jac[:, i] = (y - y_lo) / h
        else:
            jac[:, i] = math.nan
    return y, jac


def _try(
    simulate: Callable[[FloatArray], FloatArray], theta: FloatArray, i: int, h: float
) -> Optional[FloatArray]:
    moved = theta.copy()
    moved[i] += h
    try:
        out = simulate(moved)
    except (InvalidParameterError, NonFiniteError):
        return None
    return out if bool(np.all(np.isfinite(out))) else None
