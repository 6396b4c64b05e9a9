"""The adequacy test of the feedback fits (issue #20), as :func:`~bouc_wen_id.identify` and
:func:`~bouc_wen_id.fit_time_domain` have one.

* **Records** (:func:`~bouc_wen_id.fit_feedback`): the Ljung-Box whiteness test of the output-error residuals
  (:func:`~bouc_wen_id.timedomain.whiteness`, 20 lags per record). With the right structure and white
  measurement noise the residuals are white; a structure that misses a part of the dynamics leaves it in
  them, coloured by the system (coloured measurement noise is rejected too: the test says so, not which).
* **Averaged sine periods** (:func:`~bouc_wen_id.fit_feedback_sines`): the residual power against the
  averaged noise, as ``identify``'s test: ``statistic = sum_i ||ybar_i - y_i||^2 / v_i`` with ``v_i`` the
  noise variance of experiment i's averaged samples. With ``v_i`` estimated from the period-to-period
  spread on ``d_i`` degrees of freedom, ``statistic / dof`` is F(``dof``, ``sum d_i``) distributed
  (``dof = sum N_i - parameters``); with a known variance it is chi-square on ``dof``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from ..errors import InvalidParameterError
from ._fit import whiteness

FloatArray = NDArray[np.float64]

#: The level of the pass/fail verdict the result prints (the p-value is there for any other).
ADEQUACY_LEVEL = 0.05


@dataclass(frozen=True)
class FeedbackAdequacy:
    """The adequacy test of a feedback fit (module docstring): which test, its statistic, p-value, verdict."""

    test: str
    statistic: float
    dof: int
    p_value: float
    noise_dof: Optional[int] = None

    def rejects(self, level: float = ADEQUACY_LEVEL) -> bool:
        """True when the model is rejected at ``level`` (a p-value below it)."""
        return self.p_value < level

    @property
    def passed(self) -> bool:
        """Not rejected at :data:`ADEQUACY_LEVEL`."""
        return not self.rejects()

    def describe(self) -> str:
        noise = f" (noise from {self.noise_dof} dof)" if self.noise_dof else ""
        verdict = "pass" if self.passed else "FAIL"
        return (
            f"adequacy ({self.test}): {self.statistic:.4g} on {self.dof} dof{noise}, p = {self.p_value:.3g}: "
            f"{verdict} at {ADEQUACY_LEVEL:g}"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "test": self.test,
            "statistic": self.statistic,
            "dof": self.dof,
            "noise_dof": self.noise_dof,
            "p_value": self.p_value,
            "passed": self.passed,
        }


def record_adequacy(residuals: Sequence[FloatArray]) -> FeedbackAdequacy:
    """Ljung-Box whiteness of the records' residuals."""
    w = whiteness(residuals)
    return FeedbackAdequacy("residual whiteness, Ljung-Box", w.statistic, w.dof, w.p_value)


def check_noise(noise: Sequence[tuple[float, int]], n_experiments: int) -> list[tuple[float, int]]:
    """``noise`` as ``[(variance, dof), ...]``, one per experiment; bad entries are named."""
    if isinstance(noise, (str, bytes)) or not isinstance(noise, Sequence) or len(noise) != n_experiments:
        raise InvalidParameterError(
            f"noise must hold one (variance, dof) pair per experiment ({n_experiments}), got {noise!r}"
        )
    out = []
    for i, item in enumerate(noise):
        try:
            v, d = float(item[0]), item[1]
        except (TypeError, ValueError, IndexError):
            raise InvalidParameterError(f"noise[{i}] must be a (variance, dof) pair, got {item!r}") from None
        if not (math.isfinite(v) and v > 0):
            raise InvalidParameterError(f"noise[{i}]: the variance {v} must be finite and > 0")
        if isinstance(d, bool) or not isinstance(d, (int, np.integer)) or d < 1:
            raise InvalidParameterError(f"noise[{i}]: the degrees of freedom {d!r} must be an integer >= 1")
        out.append((v, int(d)))
    return out


def sine_adequacy(
    residuals: Sequence[FloatArray],
    n_params: int,
    noise: Optional[Sequence[tuple[float, int]]],
    noise_variance: Optional[float],
) -> Optional[FeedbackAdequacy]:
    """The residual power against the averaged noise (module docstring); None without a noise level."""
    from scipy.special import chdtrc, fdtrc  # type: ignore[import-untyped]

    dof = sum(r.size for r in residuals) - n_params
    if dof < 1:
        return None
    if noise is not None:
        statistic = float(sum(float(r @ r) / v for r, (v, _) in zip(residuals, noise)))
        noise_dof = sum(d for _, d in noise)
        p = float(fdtrc(dof, noise_dof, statistic / dof))
        return FeedbackAdequacy("residual power vs averaged noise, F", statistic, dof, p, noise_dof)
    if noise_variance is not None:
        statistic = float(sum(float(r @ r) for r in residuals)) / noise_variance
        p = float(chdtrc(dof, statistic))
        return FeedbackAdequacy("residual power vs known noise, chi-square", statistic, dof, p)
    return None
