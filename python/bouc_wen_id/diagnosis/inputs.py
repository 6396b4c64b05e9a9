"""The input checks ``identify`` makes, made by ``diagnose`` and ``diagnose_across`` too (review 31a item 4).

A Recording states its input, ``U cos(omega t)``; ``identify`` refuses one whose recorded ``u`` is not that
sine (``prepare.check_input``: the frequency, the amplitude and the phase at ``t = 0``). The diagnosis
takes an input with harmonics (the measured-waveform term), so it asks that the input repeat at omega
rather than be a pure sine, and checks the fundamental's amplitude and phase by identify's own code
(``prepare.check_fundamental``). The diagnosis took
the stated values on trust, so a stated amplitude of 2U halved the named viscous coefficient and a sine that
starts at zero was "explained" by a parallel stiffness. The same function now refuses them here, by the
same named errors, before any fit; and the same recording given twice (which would test it on itself in
the held-out test) is refused by name.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._text import item_label
from ..errors import BoucWenIdError, FrequencyMismatchError, InsufficientDataError, InvalidParameterError


def _source(i: int, item: Any) -> str:
    return item_label(i, item)


def _check_recording(i: int, rec: Any, at: str) -> None:
    """identify's checks of the stated input over the periods the diagnosis averages, each error prefixed
    by the item: the sizes, the input repeating at the stated omega (identify asks for a pure sine; the
    diagnosis takes an input with harmonics, the measured-waveform term's data), the fundamental's amplitude
    and its phase at ``t = 0`` (``prepare.check_fundamental``, identify's own)."""
    from ..prepare import check_fundamental, check_sizes, input_fundamental

    p, s = int(rec.samples_per_period), int(rec.settle_periods)
    n = int(rec.whole_periods) - s
    if n < 1:
        return  # too short: data.py names it
    try:
        check_sizes(rec, s * p, (s + n) * p)
        _check_periodic(rec, s * p, n, p)
        check_fundamental(rec, *input_fundamental(rec, s * p, (s + n) * p), (s * p, (s + n) * p))
    except BoucWenIdError as err:
        raise type(err)(f"{at}{_source(i, rec)}: {err}") from err


def _check_periodic(rec: Any, start: int, n: int, p: int) -> None:
    """Refuse an input that does not repeat at the stated omega: its periods differ from their mean by more
    than ``INPUT_MISFIT_MAX`` of its spread (identify's bound on the misfit of its sine)."""
    from ..prepare import INPUT_MISFIT_MAX, noisy_input, swapped_hint

    if n < 2:
        return
    rows = np.asarray(rec.u[start : start + n * p], dtype=np.float64).reshape(n, p)
    spread = float(np.sum((rows - rows.mean()) ** 2))
    misfit = math.sqrt(float(np.sum((rows - rows.mean(axis=0)) ** 2)) / spread) if spread > 0 else math.inf
    if misfit > INPUT_MISFIT_MAX:
        noisy = noisy_input(rows - rows.mean(axis=0), misfit, rec.frequency, "its mean period")
        if noisy is not None:
            raise noisy
        from .._timehint import hint

        raise hint(
            FrequencyMismatchError(
                f"the recorded input does not repeat at omega = {rec.frequency:.6g} rad/s (its periods "
                f"differ from their mean by a relative {misfit:.2g} > {INPUT_MISFIT_MAX}); check the stated "
                "frequency and its units" + swapped_hint(rec, (start, start + n * p))
            ),
            rec.t,
            rec.u,
            rec.frequency,
        )


def _fingerprint(item: Any) -> tuple[Any, ...] | None:
    arrays = [getattr(item, name, None) for name in ("t", "u", "y")]
    if any(a is None for a in arrays):
        return None
    return tuple(hash(np.ascontiguousarray(a, dtype=np.float64).tobytes()) for a in arrays)


def check_items(experiments: Any, where: str = "") -> None:
    """Refuse what ``identify`` refuses in the stated input, an empty set, and a recording given twice.

    Raises
    ------
    InsufficientDataError
        No experiment (``where`` names the group, e.g. a condition of ``diagnose_across``).
    FrequencyMismatchError, InvalidParameterError
        A Recording whose ``u`` is not its stated ``U cos(omega t)`` (as ``identify``), or the same
        recording (equal t, u and y) passed twice.
    """
    from ..model import Recording

    seq = list(experiments) if isinstance(experiments, (list, tuple)) else [experiments]
    at = f"{where}: " if where else ""
    if not seq:
        raise InsufficientDataError(f"{at}no experiment given: nothing to diagnose")
    seen: dict[tuple[Any, ...], int] = {}
    for i, item in enumerate(seq):
        if isinstance(item, Recording):
            _check_recording(i, item, at)
        key = _fingerprint(item)
        if key is None:
            continue
        if key in seen:
            raise InvalidParameterError(
                f"{at}{_source(i, item)} is the same recording as {_source(seen[key], seq[seen[key]])} "
                "(equal t, u and y): a repeated experiment adds no information and would be tested on "
                "itself in the held-out test; pass each experiment once"
            )
        seen[key] = i
