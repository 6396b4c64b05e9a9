"""Preprocessing of lab recordings: sine analysis, steady-segment detection, synchronous averaging.

The identification (:mod:`bouc_wen_id.identification`) needs one averaged period ``ybar`` per experiment on a
grid whose time origin is the input's phase zero (``u = U cos(omega t)`` at ``t = 0``).  Simulated data give
that grid for free: a whole number of samples per period and ``u`` starting at its peak.  Lab recordings do
not: the true frequency is off nominal (DAQ clock against signal generator), so a period holds a non-integer
number of samples; the steady periods sit between idle stretches, amplitude ramps and pauses; offsets,
quantisation and raw DAQ units come on top.  This module turns ``(t, u, y)`` arrays into such averaged
periods in three steps.

1. :func:`analyse_sine` estimates frequency, amplitude, phase and offset of ``u`` (windowed-DFT peak, then
   nonlinear least squares, which reaches the Cramer-Rao bound; the input's own harmonics are fitted too
   when they stand above the noise, so that they do not bias it) and checks that ``u`` is a usable sine.
2. :func:`find_steady_segments` cuts a record into its steady stretches of whole periods (one experiment
   each) and says why everything else was dropped.
3. :func:`synchronous_average` fits ``y`` over a steady stretch by linear least squares on harmonics of the
   input frequency and evaluates one period on ``P = 2K + 1`` points from the input's phase zero.  With an
   integer number of samples per period, whole periods and all harmonics it is exactly the paper's periodic
   average (4a-b) (``periodic_average`` of the core).

:func:`average_segments` runs steps 2 and 3 on a :class:`~bouc_wen_id.measurement.Measurement` and returns
the averaged periods with the segment report.  The modules: ``_sine`` (step 1), ``_windows`` and
``_segments`` (step 2), ``_averaging`` (step 3), ``_harmonic_ls`` (the least squares on harmonics they
share).

The least squares run on the lab kernels of the backend in force (``bouc_wen_id._backend``): the Rust ones by
default, the NumPy paths throughout inside an entry point called with ``backend="numpy"`` (``identify`` of a
Measurement, for one), so that ``backend=`` means the same thing for every step.

Reasons given for dropped stretches (:class:`SegmentReport`)
-------------------------------------------------------------
``"idle"``
    The input's fundamental is below 5 % of the record's steady amplitude (or below its noise) at the start
    or the end of the record.
``"pause"``
    The same between two active stretches (a test, then a pause, then the next test), across gaps of the
    time axis (DAQ pauses) too.
``"amplitude ramp"``
    At least two consecutive periods whose input amplitude moves the same way, by more than 5 % each,
    next to rest or a steady level.
``"level change"``
    The unsteady stretch between two steady levels that differ (input amplitude or offset, output
    waveform or offset).
``"transient"``
    Any other unsteady stretch: a one-period start or stop, a glitch, a phase jump, an output settling,
    the end period of a steady stretch that stands out of it.
``"too short"``
    Steady, but fewer whole periods than ``min_periods``.
``"partial period"``
    Less than one period left over at the end of a contiguous block or next to a kept segment.

References
----------
*Wiener System Identification in Presence of Hysteresis Nonlinearity*, the seed paper whose equation
numbers are cited; for the Bouc-Wen properties it relies on (Propositions 1-2): F. Ikhouane and
J. Rodellar, *Systems with Hysteresis: Analysis, Identification and Control using the Bouc-Wen Model*,
Wiley, 2007.
"""

from __future__ import annotations

from ._averaging import (
    AveragedPeriod,
    SegmentedMeasurement,
    average_measurement,
    average_segments,
    synchronous_average,
)
from ._segments import Segment, SegmentReport, find_steady_segments
from ._sine import SineFit, analyse_sine

__all__ = [
    "SineFit",
    "analyse_sine",
    "Segment",
    "SegmentReport",
    "find_steady_segments",
    "AveragedPeriod",
    "synchronous_average",
    "SegmentedMeasurement",
    "average_segments",
    "average_measurement",
]
