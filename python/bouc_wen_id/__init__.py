"""bouc_wen_id: identify Wiener systems with Bouc-Wen hysteresis from sine experiments.

The numerics run in a Rust core (:mod:`bouc_wen_id._core`); :mod:`bouc_wen_id.reference` holds the NumPy
reference implementation of the same routines.  Start with :func:`simulate` and :func:`identify`.
"""

from __future__ import annotations

# budget is imported eagerly so that the BOUC_WEN_ID_MAX_* environment variables reach the core.
from . import budget, diagnosis, errors, io, reference, signal
from ._core import __version__
from .demo import demo_plan, demo_plant
from .diagnosis import Diagnosis, SavedDiagnosis, diagnose, load_diagnosis
from .errors import (
    BoucWenIdError,
    BudgetExceededError,
    ClippingError,
    ConvergenceWarning,
    DistortedInputWarning,
    FileFormatError,
    FrequencyMismatchError,
    IdentifiabilityWarning,
    ImproperTransferFunctionError,
    InsufficientDataError,
    InvalidParameterError,
    NoisyInputError,
    NonFiniteError,
    NotConvergedError,
    NotPeriodicError,
    PoorFitWarning,
    SearchAtBoundError,
    SingularNormalMatrixError,
    TimeAxisError,
    UndersampledError,
    UnstableSystemError,
    ZeroAmplitudeError,
)
from .gaps import split_at_gaps
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
    "diagnosis",
    "diagnose",
    "Diagnosis",
    "SavedDiagnosis",
    "load_diagnosis",
    "TransferFunction",
    "BoucWen",
    "WienerPlant",
    "SinePlan",
    "Recording",
    "Measurement",
    "split_at_gaps",
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
    "NoisyInputError",
    "ZeroAmplitudeError",
    "SingularNormalMatrixError",
    "SearchAtBoundError",
    "NotConvergedError",
    "FileFormatError",
    "TimeAxisError",
    "ClippingError",
    "UndersampledError",
    "NotPeriodicError",
    "IdentifiabilityWarning",
    "PoorFitWarning",
    "DistortedInputWarning",
    "ConvergenceWarning",
    "Adequacy",
    "CramerRao",
    "cramer_rao",
]

__all__ += ["budget", "BudgetExceededError"]

# Experiment planning (issue #11 part 3): the design that minimises a Cramer-Rao criterion within a budget.
from .planning import DetectionPlan, ExperimentPlan, PlannedExperiment, plan_detection, plan_experiment  # noqa: E402

__all__ += ["plan_experiment", "ExperimentPlan", "PlannedExperiment", "plan_detection", "DetectionPlan"]

# Issue #11 parts 1-2: G(s) from the points (scipy.optimize imported only when fitting); python-control
# interop lives in bouc_wen_id.interop and imports control lazily.
from . import interop  # noqa: E402
from .tfit import FrequencyPrediction, TransferFunctionFit, fit_transfer_function  # noqa: E402

__all__ += ["interop", "fit_transfer_function", "TransferFunctionFit", "FrequencyPrediction"]

# Feedforward hysteresis compensation (issue 21, item 1): the command that makes a model follow a reference.
from . import compensation  # noqa: E402
from .compensation import Compensation, LimitHit, compensate  # noqa: E402
from .errors import UnreachableReferenceError  # noqa: E402

__all__ += ["compensation", "compensate", "Compensation", "LimitHit", "UnreachableReferenceError"]
# Issue #20 items 1, 2 and 4: Bouc-Wen in feedback (the Noel-Schoukens benchmark's structure), fitted to
# records of any waveform or to averaged steady sine periods.
from .timedomain import FeedbackFit, FeedbackModel, fit_feedback, fit_feedback_sines  # noqa: E402

__all__ += ["fit_feedback", "fit_feedback_sines", "FeedbackModel", "FeedbackFit"]
# Issue #20 items 1 and 3 (time-domain identification): the Wiener cascade fitted to records of any waveform,
# and any identified model simulated on a record it was not fitted to.
from . import timedomain  # noqa: E402
from .timedomain import TimeDomainFit, TimeRecord, ValidationReport, fit_time_domain, validate  # noqa: E402

__all__ += ["timedomain", "fit_time_domain", "TimeDomainFit", "TimeRecord", "validate", "ValidationReport"]
# Issue #21 item 2, model export: the whole model as a python-control nlsys (control imported lazily), as
# self-contained C99 and as versioned JSON (bw.save_model / bw.load_model).
from . import export  # noqa: E402
from .export import load_model, model_from_json, model_to_json, save_model, to_c, to_nlsys  # noqa: E402

__all__ += ["export", "load_model", "save_model", "model_to_json", "model_from_json", "to_c", "to_nlsys"]

# Issue #21 item 3, parameters that follow an operating variable (current, temperature, pre-load): one joint
# fit over the levels, each parameter a polynomial in the variable (scipy imported when fitting).
from . import operating  # noqa: E402
from .operating import OperatingFit, fit_operating, select_degree  # noqa: E402

__all__ += ["operating", "OperatingFit", "fit_operating", "select_degree"]
# Issue 18, the diagnosis across conditions: one named structure for experiments at several conditions (coil
# currents, temperatures), its values free per condition, with how they move with the condition.
from .diagnosis.across import AcrossDiagnosis, diagnose_across  # noqa: E402

__all__ += ["diagnose_across", "AcrossDiagnosis"]
