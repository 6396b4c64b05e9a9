"""Time-domain identification (issue #20): records of any waveform, a bounded Levenberg-Marquardt, the model
classes fitted to them by output error, and the validation of any identified model on a fresh record.

Generic pieces (reused by every model class):

* :class:`TimeRecord`, :func:`as_time_records`, :func:`check_memory` (``_records``): the data and its checks;
* :func:`levenberg_marquardt`, :class:`LMResult` (``_lm``): the bounded search over stacked residuals with
  an exact Jacobian.

Model classes:

* the Wiener cascade (``_wiener``, ``_fit``): :func:`fit_time_domain` -> :class:`TimeDomainFit`, and
  :func:`cramer_rao_bound` for a time-domain design.

Validation (``_validate``): :func:`validate` -> :class:`ValidationReport`.
"""

from __future__ import annotations

from ._fit import TimeDomainFit, Whiteness, cramer_rao_bound, fit_time_domain, whiteness
from ._lm import LMResult, StopReason, free_covariance, levenberg_marquardt
from ._records import MIN_SAMPLES, TimeRecord, as_time_records, check_memory, lead_in_samples
from ._validate import ValidationReport, simulator_plant, validate
from ._wiener import Structure, memory

__all__ = [
    "LMResult",
    "StopReason",
    "free_covariance",
    "levenberg_marquardt",
    "MIN_SAMPLES",
    "TimeRecord",
    "as_time_records",
    "check_memory",
    "lead_in_samples",
    "TimeDomainFit",
    "Whiteness",
    "cramer_rao_bound",
    "fit_time_domain",
    "whiteness",
    "Structure",
    "memory",
    "ValidationReport",
    "simulator_plant",
    "validate",
]

# Bouc-Wen in feedback (issue #20, the benchmark's structure): model, fit, band-limited input reconstruction.
from ._feedback import FEEDBACK_PARAMETERS, FeedbackFit, FeedbackModel, fit_feedback, upsample_input  # noqa: E402
from ._feedback_sines import SineExperiment, fit_feedback_sines, steady_period  # noqa: E402

__all__ += ["FEEDBACK_PARAMETERS", "FeedbackFit", "FeedbackModel", "fit_feedback", "upsample_input"]
__all__ += ["SineExperiment", "fit_feedback_sines", "steady_period"]

# The feedback fits' adequacy test (issue #20).
from ._feedback_adequacy import FeedbackAdequacy  # noqa: E402

__all__ += ["FeedbackAdequacy"]
