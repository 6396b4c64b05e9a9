"""The terms on the measured output y (:attr:`Place.OUTPUT`): what the sensor adds to the output (an offset),
how it filters it (a first-order lag) or the dead band it is seen through (a play on the output).

Part of the registry :mod:`bouc_wen_id.terms` (import from there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from ._base import NON_NEGATIVE, Place, StartContext, Term
from ._hysteretic import Play


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


@dataclass(frozen=True)
class PlayOutput(Play):
    """Play (backlash) of half-width ``c`` on the measured output: ``y = Play_c[F]``, ``F`` the model's output
    (after the lag and the offset). The measured output follows the element's force through a dead band of
    ``2 c``, as a loose linkage between the element and the force sensor does; code name ``"play@output"``.

    ``c`` is in units of ``y`` at every alpha (the output's terms do not change with ``G -> alpha G``). Where
    the loop's slope at a reversal is ``s``, a play of ``b`` on x dwells as this one of ``c = s b``
    (``diagnosis/caveats.py``): the two are told apart by the slopes at the reversals changing with amplitude.
    """

    acts_on: ClassVar[Place] = Place.OUTPUT
    description: ClassVar[str] = (
        "backlash between the element and the output sensor: the output dwells for 2c after each reversal"
    )
    signature: ClassVar[str] = (
        "flat stretches after each reversal of y, 2c of output tall at every amplitude (a play on x dwells "
        "2b of x long, as tall as the loop's slope at the reversal makes it)"
    )
    unphysical: ClassVar[str] = "a negative backlash"

    @classmethod
    def start(cls, context: StartContext) -> tuple[float, ...]:
        # The residual it leaves is about c at the reversals: the plain fit's RMS, and 1 and 10 % of the
        # smallest latent amplitude (the output's size in the alpha = 1 model).
        a = min(context.latent_amplitudes)
        rms = context.residual_rms
        return ((rms,) if math.isfinite(rms) and rms > 0.0 else ()) + (0.01 * a, 0.1 * a)

    def normalized(self, alpha: float) -> Term:
        return self
