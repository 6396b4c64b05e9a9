"""The preprocessing variants of a diagnosis (stability.py's, value_stability.py's): the same experiments cut
or averaged in other reasonable ways (a shorter stretch of each steady record, fewer harmonics in the
averaged period). Here alone so that the value check inside ``diagnose`` cuts them without importing the
study's re-diagnosis (which imports ``diagnose``).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

#: The run every variant is compared with.
MAIN = "as recorded"

#: The preprocessing variants (key, description); the first is the main run.
VARIANTS: tuple[tuple[str, str], ...] = (
    (MAIN, "the whole steady stretch, the averaging's own harmonic count"),
    ("early", "each steady stretch without its last third"),
    ("late", "each steady stretch without its first third (the third kept in its lead)"),
    ("half harmonics", "half the harmonics in the averaged period (at least 8)"),
)


def variant_items(measurements: Sequence[Any], variant: str) -> list[Any]:
    """The experiments of one preprocessing variant of :data:`VARIANTS`, from Measurements (the main run's
    items are the measurements themselves; the others are derived, one experiment per steady segment as in
    the main run, the measurements left as they are)."""
    from ..measurement import Measurement

    keys = [k for k, _ in VARIANTS]
    if variant not in keys:
        raise ValueError(f"unknown preprocessing variant {variant!r}; one of {keys}")
    ms = list(measurements)
    bad = [type(m).__name__ for m in ms if not isinstance(m, Measurement)]
    if bad:
        raise TypeError(
            f"the preprocessing variants are cut from Measurements, not {', '.join(sorted(set(bad)))}"
        )
    if variant == MAIN:
        return ms
    return [e for m in ms for e in _segments(m, variant)]


def _segments(m: Any, variant: str) -> list[Any]:
    """Every steady segment of ``m`` as the variant preprocesses it: ``early`` without the segment's last
    third, ``late`` without its first, ``half harmonics`` whole with half the harmonics (at least 8). Each is
    averaged on the main run's own input fit and on ``m``'s whole time axis, so what precedes the stretch
    (the settling, the dropped third) stays its lead (``DiagExperiment.lead_periods``, the drift's age)."""
    from .. import signal
    from .data import BASELINE_MARK, _from_averaged, _lab_marked

    seg = signal.average_segments(m)
    out = []
    for ap, kept, fit in zip(seg.periods, seg.report.kept, seg.report.fits):
        a, b, harmonics = kept.start, kept.stop, None
        third = (b - a) // 3
        if variant == "early":
            b -= third
        elif variant == "late":
            a += third
        else:
            harmonics = max(8, ap.harmonics // 2)
        cut = signal.synchronous_average(
            m.t, m.y, fit, start=a, stop=b, harmonics=harmonics, source=f"{ap.source} ({variant})"
        )
        e = _from_averaged(cut, m.t, m.y, m.u)
        out.append(_lab_marked(e) if BASELINE_MARK in m.metadata else e)
    return out


__all__ = ["MAIN", "VARIANTS", "variant_items"]
