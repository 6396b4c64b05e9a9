"""The verdict's clause on a measured output with flat tops (a sensor or DAQ out of range).

The diagnosis checked the input for a drive that is not a sine (:mod:`.input_note`, :mod:`.clean_share`,
:mod:`.clean_value`), but not the output: a load cell or DAQ channel driven past its range holds its rail
value for part of every period, and the diagnosis read that as device physics (a null, pure-sine inputs,
the output of two of five experiments clipped at 92 % of its peak, 24 % of their samples on the rail:
"unexplained structure remains ... not named: inertia on the measured input u, inertia across the
hysteretic element", nothing said of the output; ``Measurement.check`` refuses that channel, but only when
the user calls it). :func:`clause` runs the same test (:func:`..measurement.clipping_check`) on every
experiment's recorded output and says which are clipped, and that a verdict on them is about the sensor's
range, not the device. Nothing is left out or refitted: the user decides whether to drop those records.
A coarsely quantised output is not judged (:func:`coarse`): its own flat top passes for a clip.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ..errors import ClippingError
from ..measurement import clipping_check

#: An output whose quantisation step exceeds this share of its range is not judged (:func:`coarse`).
COARSE_STEP = 1e-3


def coarse(y: np.ndarray) -> bool:
    """Whether ``y`` is coarsely quantised: its smallest gap between distinct values is more than
    :data:`COARSE_STEP` of its range. ``clipping_check`` allows the top level the dwell of a sine's peak;
    a saturating Bouc-Wen loop is flatter there, and quantised coarsely with little noise it holds its top
    level for runs that pass for a clip (tests/test_diagnosis_across_gate.py's outputs, a step of 0.8 % of
    the range with a dither of 0.05 steps: 3-4 of 8 flagged). Such outputs are not judged: a clip there is
    not told from a quantised loop's own flat top."""
    span = float(np.max(y) - np.min(y)) if y.size else 0.0
    if span <= 0.0 or not np.all(np.isfinite(y)):
        return False
    gaps = np.diff(np.unique(y))
    gaps = gaps[gaps > 1e-12 * span]
    return bool(gaps.size) and float(np.min(gaps)) > COARSE_STEP * span


def clipped(items: Sequence[Any]) -> list[str]:
    """The names of the experiments whose recorded output ``y`` has flat tops (``clipping_check``); an
    item without a raw output (an averaged period) or with a coarsely quantised one (:func:`coarse`) is not
    judged."""
    out = []
    for i, item in enumerate(items):
        y = getattr(item, "y", None)
        if y is None:
            continue
        meta = getattr(item, "metadata", None)
        name = getattr(item, "name", "") or (meta.get("name", "") if isinstance(meta, dict) else "")
        arr = np.asarray(y, dtype=np.float64)
        if coarse(arr):
            continue
        try:
            clipping_check(arr, "y")
        except ClippingError:
            out.append(str(name or f"recording {i}"))
    return out


def clause(items: Sequence[Any]) -> str:
    """The verdict's clause ('' when no output is clipped)."""
    names = clipped(items)
    if not names:
        return ""
    one = len(names) == 1
    its = "its" if one else "their"
    return (
        f"; the measured output of {', '.join(names)} looks clipped (flat tops at {its} "
        "extremes, as Measurement.check finds them): a sensor or DAQ out of range, not device physics; what "
        f"the diagnosis says of {'that experiment' if one else 'those experiments'} is about the channel's "
        "range, not the device: check the sensor range and the DAQ gain, or drop the clipped records"
    )


__all__ = ["COARSE_STEP", "clause", "clipped", "coarse"]
