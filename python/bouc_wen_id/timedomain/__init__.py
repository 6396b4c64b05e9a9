"""Time-domain identification (issue #20): records of any waveform, a bounded Levenberg-Marquardt, and the
model classes fitted to them by output error.

Generic pieces (reused by every model class):

* :class:`TimeRecord`, :func:`as_time_records`, :func:`check_memory` (``_records``): the data and its checks;
* :func:`levenberg_marquardt`, :class:`LMResult` (``_lm``): the bounded search over stacked residuals with
  an exact Jacobian.
"""

from __future__ import annotations

from ._lm import LMResult, StopReason, levenberg_marquardt
from ._records import MIN_SAMPLES, TimeRecord, as_time_records, check_memory

__all__ = [
    "LMResult",
    "StopReason",
    "levenberg_marquardt",
    "MIN_SAMPLES",
    "TimeRecord",
    "as_time_records",
    "check_memory",
]
