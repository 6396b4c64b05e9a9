"""bouc_wen_id: identify Wiener systems with Bouc-Wen hysteresis from sine experiments.

The numerics run in a Rust core (:mod:`bouc_wen_id._core`); :mod:`bouc_wen_id.reference` holds the NumPy
reference implementation of the same routines.  Start with :func:`simulate` and :func:`identify`.
"""

from __future__ import annotations

from . import errors, io, reference, signal
from ._core import __version__
from .demo import demo_plan, demo_plant
from .errors import (
    BoucWenIdError,
    ClippingError,
    ConvergenceError,
    ConvergenceWarning,
    DistortedInputWarning,
    FileFormatError,
    FrequencyMismatchError,
    IdentifiabilityWarning,
    ImproperTransferFunctionError,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    NotPeriodicError,
    SearchAtBoundError,
    SingularNormalMatrixError,
    TimeAxisError,
    UndersampledError,
    UnstableSystemError,
    ZeroAmplitudeError,
)
from .identification import identify
from .io import load, load_recordings, save, save_recordings
from .measurement import Measurement
from .model import BoucWen, Recording, SinePlan, TransferFunction, WienerPlant
from .result import Adequacy, ExperimentEstimate, IdentificationResult, Truth
from .signal import AveragedPeriod, SineFit, analyse_sine, average_measurement, find_steady_segments
from .simulation import simulate, simulate_input
from .uncertainty import CramerRao, cramer_rao

__all__ = [
    "__version__",
    "errors",
    "io",
    "reference",
    "signal",
    "TransferFunction",
    "BoucWen",
    "WienerPlant",
    "SinePlan",
    "Recording",
    "Measurement",
    "simulate",
    "simulate_input",
    "identify",
    "IdentificationResult",
    "ExperimentEstimate",
    "Truth",
    "load",
    "save",
    "load_recordings",
    "save_recordings",
    "analyse_sine",
    "find_steady_segments",
    "average_measurement",
    "SineFit",
    "AveragedPeriod",
    "demo_plant",
    "demo_plan",
    "BoucWenIdError",
    "InvalidParameterError",
    "NonFiniteError",
    "UnstableSystemError",
    "ImproperTransferFunctionError",
    "InsufficientDataError",
    "FrequencyMismatchError",
    "ZeroAmplitudeError",
    "SingularNormalMatrixError",
    "SearchAtBoundError",
    "ConvergenceError",
    "FileFormatError",
    "TimeAxisError",
    "ClippingError",
    "UndersampledError",
    "NotPeriodicError",
    "IdentifiabilityWarning",
    "DistortedInputWarning",
    "ConvergenceWarning",
    "Adequacy",
    "CramerRao",
    "cramer_rao",
]
