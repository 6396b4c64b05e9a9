"""The terms on the measured output y (:attr:`Place.OUTPUT`): what the sensor adds to the output (an offset)
or how it filters it (a first-order lag).

Part of the registry :mod:`bouc_wen_id.terms` (import from there).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from ._base import NON_NEGATIVE, StartContext, Term


@dataclass(frozen=True)
class Offset(Term):
    """Output offset ``y0``: a constant added to the measured output (sensor zero, preload)."""

    y0: float

    kind: ClassVar[str] = "offset"
    symbol: ClassVar[str] = "y0"
    unit: ClassVar[str] = "{y}"
    description: ClassVar[str] = "constant output offset (sensor zero, static preload)"
    signature: ClassVar[str] = "a constant residual: the loop is shifted up or down as a whole (DC)"
    label: ClassVar[str] = "output offset"
    linear: ClassVar[bool] = True
    scaling: ClassVar[tuple[float, float, float]] = (1.0, 0.0, 0.0)
    # Physical range: any sign (a sensor zero or a static preload either way): UNBOUNDED.


@dataclass(frozen=True)
class SensorLag(Term):
    """First-order output (sensor) lag ``tau``: the output is seen through ``1/(tau s + 1)``."""

    tau: float

    kind: ClassVar[str] = "sensor_lag"
    symbol: ClassVar[str] = "tau"
    unit: ClassVar[str] = "s"
    description: ClassVar[str] = "first-order lag of the output sensor or its filter, 1/(tau s + 1)"
    signature: ClassVar[str] = (
        "the whole output delayed by about tau: a residual like -tau ydot, growing with frequency"
    )
    label: ClassVar[str] = "sensor lag"
    bounds: ClassVar[tuple[float, float]] = NON_NEGATIVE
    physical: ClassVar[tuple[float, float]] = NON_NEGATIVE
    unphysical: ClassVar[str] = "a negative lag (an output ahead of its cause)"
    beyond: ClassVar[str] = "a time offset between the recorded channels (y stamped ahead of u)"

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # 1 % and 10 % of a radian of lag at the highest frequency.
        return tuple(f / context.max_frequency for f in (0.01, 0.1))
