"""Named errors raised by bouc_wen_id.

Every failure the library can detect ends in one of these exceptions.  They all derive from
:class:`BoucWenIdError`, itself a :class:`ValueError`, so ``except ValueError`` keeps working for callers
that do not care which check failed.  The Rust core raises the same classes (it imports them from this
module), and so does the NumPy reference implementation, so a test can hold both to the same behaviour.
"""

from __future__ import annotations

__all__ = [
    "BoucWenIdError",
    "InvalidParameterError",
    "NonFiniteError",
    "UnstableSystemError",
    "ImproperTransferFunctionError",
    "InsufficientDataError",
    "FrequencyMismatchError",
    "NoisyInputError",
    "ZeroAmplitudeError",
    "SingularNormalMatrixError",
    "SearchAtBoundError",
    "NotConvergedError",
    "BudgetExceededError",
    "FileFormatError",
    "UnitMismatchError",
    "TimeUnitError",
    "UnitWarning",
    "TimeAxisError",
    "ClippingError",
    "UndersampledError",
    "NotPeriodicError",
    "IdentifiabilityWarning",
    "ConvergenceWarning",
    "TransientWarning",
    "GapWarning",
    "DistortedInputWarning",
    "PoorFitWarning",
    "UnreachableReferenceError",
]


class BoucWenIdError(ValueError):
    """Base class of every error raised by bouc_wen_id."""


class InvalidParameterError(BoucWenIdError):
    """A model or method parameter is out of its admissible range (e.g. mu <= 1, dt <= 0)."""


class NonFiniteError(BoucWenIdError):
    """An input array or parameter holds NaN or infinity."""


class UnstableSystemError(BoucWenIdError):
    """The transfer function has a pole in the closed right half-plane."""


class ImproperTransferFunctionError(BoucWenIdError):
    """The transfer function has more zeros than poles (or a zero leading denominator coefficient)."""


class InsufficientDataError(BoucWenIdError):
    """The recording is too short for the requested settling and averaged periods."""


class FrequencyMismatchError(BoucWenIdError):
    """The stated frequency does not give a whole number of samples per period on the recording's grid."""


class NoisyInputError(FrequencyMismatchError):
    """The measured input repeats at the stated frequency but carries more noise than the averaging takes (a
    ``FrequencyMismatchError`` as well: the same check refuses it, so code catching that still catches it)."""


class ZeroAmplitudeError(BoucWenIdError):
    """The input amplitude is zero (or the output is constant), so nothing can be identified."""


class SingularNormalMatrixError(BoucWenIdError):
    """The least-squares normal matrix is singular or too badly conditioned to be solved."""


class SearchAtBoundError(BoucWenIdError):
    """The search for mu ended on an end of its bracket.

    ``bound`` and ``lower`` name the end when the raiser knows it (``None`` otherwise).
    """

    def __init__(self, message: str, bound: float | None = None, lower: bool | None = None) -> None:
        super().__init__(message)
        self.bound = bound
        self.lower = lower

    def __reduce__(self) -> tuple[type[SearchAtBoundError], tuple[str, float | None, bool | None]]:
        return type(self), (str(self), self.bound, self.lower)


class NotConvergedError(BoucWenIdError):
    """An iteration that must converge did not: the steady-loop shootings (plain and along the input path).

    The parameters are then far from any loop the model can draw; it is not a bad parameter value as such.
    """


class BudgetExceededError(InvalidParameterError):
    """A call would exceed a work or memory budget (see :mod:`bouc_wen_id.budget`).

    The message gives the estimated size and the limit, and how to raise it
    (``bouc_wen_id.budget.set_budget(...)`` or a ``BOUC_WEN_ID_MAX_*`` environment variable).
    """


class TransientWarning(UserWarning):
    """Leading periods of a recording were still transient and were dropped (more settling periods)."""


class GapWarning(UserWarning):
    """Pieces of a record cut at its gaps were left out: each held fewer periods than an analysis needs
    (:func:`bouc_wen_id.split_at_gaps`); the message names their samples."""


class FileFormatError(BoucWenIdError):
    """A recording or result file cannot be read: a missing column, a bad header, an unknown version."""


class UnitMismatchError(FileFormatError):
    """Experiments joined into one data set state units of one quantity that no known scale relates (``mm``
    in one file, ``N`` in another; an unknown unit beside another): the message names both experiments and
    units, and how to fix it (:mod:`bouc_wen_id.units`).  A :class:`FileFormatError`: it is most often a
    wrong column name or a file of another rig."""


class TimeUnitError(UnitMismatchError, FrequencyMismatchError):
    """A time column that is not in seconds although nothing says so: its step is 1000 (or 10^6) times what
    a stated sample rate or frequency needs, so it "looks like ms" (or us) (:mod:`bouc_wen_id.timeunits`).
    Both a :class:`UnitMismatchError` and the :class:`FrequencyMismatchError` such data raised before."""


class UnitWarning(UserWarning):
    """Experiments joined into one data set stated different units of one quantity and were converted to the
    first one's (``m`` to ``mm``): new arrays, the result's notes repeat it."""


class TimeAxisError(InvalidParameterError):
    """The time column is not usable: not strictly increasing, or its step jitters beyond tolerance.

    An :class:`InvalidParameterError`: every time axis is checked by one function
    (:func:`bouc_wen_id.validation.check_time_axis`), for lab data and exact grids alike.
    """


class ClippingError(BoucWenIdError):
    """A channel is clipped or saturated: flat tops at its extremes (sensor or DAQ out of range)."""


class UndersampledError(BoucWenIdError):
    """Too few samples per period (< 16), or the excitation frequency is too close to Nyquist."""


class NotPeriodicError(BoucWenIdError):
    """The input is not a periodic (sine) excitation, so no period can be averaged."""


class IdentifiabilityWarning(UserWarning):
    """The data do not pin the parameters down (ill-conditioned Fisher, intervals wider than values)."""


class ConvergenceWarning(UserWarning):
    """The Levenberg-Marquardt refinement stopped at its iteration cap before converging."""


class DistortedInputWarning(UserWarning):
    """The recorded input is far from a pure sine (high total harmonic distortion)."""


class PoorFitWarning(UserWarning):
    """A fitted model does not describe the data it was fitted to: its own residuals refute it."""


# Feedforward compensation (issue 21, item 1).
class UnreachableReferenceError(InvalidParameterError):
    """A reference output the model cannot produce: beyond the hysteresis' saturation level ``w_sat`` (the
    inverse Bouc-Wen operator is defined only for ``-w_sat- < w < w_sat+``), or a linear part that cannot be
    inverted (a zero on the imaginary axis)."""
