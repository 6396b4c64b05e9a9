"""bouc_wen_id: identify Wiener systems with Bouc-Wen hysteresis from sine experiments.

The numerics run in a Rust core (:mod:`bouc_wen_id._core`); :mod:`bouc_wen_id.reference` holds the NumPy
reference implementation of the same routines.  Start with :func:`simulate` and :func:`identify`.
"""

from __future__ import annotations

from . import errors, reference
from ._core import __version__
from .demo import demo_plan, demo_plant
from .errors import (
    BoucWenIdError,
    FileFormatError,
    FrequencyMismatchError,
    IdentifiabilityWarning,
    ImproperTransferFunctionError,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    SearchAtBoundError,
    SingularNormalMatrixError,
    UnstableSystemError,
    ZeroAmplitudeError,
)
from .identification import Adequacy, ExperimentEstimate, IdentificationResult, Truth, identify
from .io import load_recordings, save_recordings
from .model import BoucWen, Recording, SinePlan, TransferFunction, WienerPlant
from .simulation import simulate
from .uncertainty import CramerRao, cramer_rao

__all__ = [
    "__version__",
    "errors",
    "reference",
    "TransferFunction",
    "BoucWen",
    "WienerPlant",
    "SinePlan",
    "Recording",
    "simulate",
    "identify",
    "IdentificationResult",
    "ExperimentEstimate",
    "Truth",
    "load_recordings",
    "save_recordings",
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
    "FileFormatError",
    "IdentifiabilityWarning",
    "Adequacy",
    "CramerRao",
    "cramer_rao",
]
