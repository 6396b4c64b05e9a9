"""``validate``: an identified model simulated on a record it was not fitted to (issue #20, item 3).

Any model the library identifies is turned into something that simulates a sampled input:

* a :class:`~bouc_wen_id.model.WienerPlant`, plain or with terms (the augmented model: the simulator
  supports every library term on a sampled input, :func:`~bouc_wen_id.simulate_input` ``output=True``);
* a :class:`~bouc_wen_id.timedomain.TimeDomainFit` (its ``plant``);
* an :class:`~bouc_wen_id.IdentificationResult` of the sine path: its points carry no parametric G, so
  :meth:`~bouc_wen_id.IdentificationResult.fit_transfer_function` supplies one (order selected by AICc);
* :class:`FeedbackModel` and :class:`FeedbackFit` (Bouc-Wen in feedback), and any object with a
  ``simulate_record(t, u) -> y`` method (other model classes),
  or a ``plant`` attribute holding a ``WienerPlant``.

The report gives the RMSE in the units of ``y``, the NRMSE ``||y - y_sim|| / ||y - mean(y)||`` (0 a perfect
simulation, 1 no better than the mean), the largest error, and a residual plot.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._backend import Backend
from .._text import Summarised
from ..errors import IdentifiabilityWarning, InvalidParameterError
from ..model import BoucWen, WienerPlant
from ..validation import count, nonnegative_number
from ._records import TimeRecord, lead_in_samples

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["ValidationReport", "validate", "simulator_plant"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ValidationReport(Summarised):
    """A model's simulation of one record against the measured output.

    Attributes
    ----------
    t, y, y_sim, residuals : ndarray
        The record's time and output, the simulated output, and ``y - y_sim``.
    rmse : float
        Root mean square of the residuals after the lead-in (units of y).
    nrmse : float
        ``||y - y_sim|| / ||y - mean(y)||`` after the lead-in.
    max_error : float
        Largest absolute residual after the lead-in.
    lead_in : int
        Samples left out at the start.
    model : str
        What was simulated.
    """

    t: FloatArray = field(repr=False)
    y: FloatArray = field(repr=False)
    y_sim: FloatArray = field(repr=False)
    residuals: FloatArray = field(repr=False)
    rmse: float
    nrmse: float
    max_error: float
    lead_in: int
    model: str
    units: str = ""

    def summary(self) -> str:
        u = f" {self.units}" if self.units else ""
        return (
            f"ValidationReport: {self.model} on {self.t.size} samples (lead-in {self.lead_in})\n"
            f"  RMSE = {self.rmse:.4g}{u}, NRMSE = {self.nrmse:.4g}, max |error| = {self.max_error:.4g}{u}"
        )

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "samples": int(self.t.size),
            "lead_in": self.lead_in,
            "rmse": self.rmse,
            "nrmse": self.nrmse,
            "max_error": self.max_error,
            "units": self.units,
        }

    def plot(self, axes: Optional[tuple[Axes, Axes]] = None) -> Figure:
        """Measured and simulated output (top) and the residual (bottom) against time."""
        import matplotlib.pyplot as plt

        if axes is None:
            fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
        else:
            top, bottom = axes
            fig = top.figure  # type: ignore[assignment]
        top.plot(self.t, self.y, lw=0.8, label="measured")
        top.plot(self.t, self.y_sim, lw=0.8, label="simulated")
        top.set_ylabel(f"y{f' [{self.units}]' if self.units else ''}")
        top.legend(loc="upper right")
        top.set_title(f"{self.model}: NRMSE {self.nrmse:.3g}, RMSE {self.rmse:.3g}")
        bottom.plot(self.t, self.residuals, lw=0.8, color="C3")
        if self.lead_in:
            bottom.axvspan(self.t[0], self.t[self.lead_in], color="0.9", label="lead-in")
        bottom.set_xlabel("t [s]")
        bottom.set_ylabel("y - y_sim")
        return fig


def simulator_plant(model: object) -> tuple[WienerPlant, str]:
    """The :class:`WienerPlant` that simulates ``model`` (module docstring), and a label.

    Raises
    ------
    InvalidParameterError
        A model of a kind that cannot be simulated on a sampled input.
    """
    from ..result import IdentificationResult

    if isinstance(model, WienerPlant):
        return model, "Wiener plant" + (" with terms" if model.terms else "")
    plant = getattr(model, "plant", None)
    if isinstance(plant, WienerPlant):
        return plant, type(model).__name__
    if isinstance(model, IdentificationResult):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            tf = model.fit_transfer_function()
        label = f"identify result with G fitted by fit_transfer_function (m={tf.m}, n={tf.n})"
        return WienerPlant(tf.transfer_function, BoucWen(model.beta, model.gamma, model.mu)), label
    raise InvalidParameterError(
        f"cannot simulate a {type(model).__name__}: give a WienerPlant, a TimeDomainFit, an "
        "IdentificationResult or an object with a simulate_record(t, u) method"
    )


def validate(
    model: object,
    t: ArrayLike,
    u: ArrayLike,
    y: ArrayLike,
    *,
    lead_in: Optional[float] = None,
    substeps: int = 4,
    units: str = "",
    backend: Backend = "rust",
) -> ValidationReport:
    """Simulate ``model`` on the record ``(t, u, y)`` from rest at ``t[0]`` and compare with ``y``.

    Parameters
    ----------
    model : WienerPlant, TimeDomainFit, IdentificationResult, ...
        See the module docstring.
    t, u, y : array_like
        A record the model was not fitted to (checked as :class:`TimeRecord`).
    lead_in : float, optional
        Seconds at the start left out of the figures (the record does not start from rest).
    substeps : int
        RK4 steps per sample interval.
    units : str
        Units of ``y`` for the report.

    Raises
    ------
    InvalidParameterError, NonFiniteError, TimeAxisError, InsufficientDataError
        A model that cannot be simulated, or a bad record.
    """
    rec = TimeRecord(t, u, y)
    substeps = count("substeps", substeps, 1)
    lead_s = None if lead_in is None else nonnegative_number("lead_in", lead_in)
    k = lead_in_samples(rec, lead_s)
    if rec.y.size - k < 2:
        raise InvalidParameterError(f"the lead-in leaves {rec.y.size - k} samples; shorten it")
    custom = getattr(model, "simulate_record", None)
    if callable(custom) and not isinstance(model, WienerPlant):
        y_sim = np.asarray(custom(rec.t, rec.u), dtype=np.float64)
        label = type(model).__name__
    else:
        from ..simulation import simulate_input

        plant, label = simulator_plant(model)
        _, _, y_sim = simulate_input(plant, rec.t, rec.u, substeps=substeps, backend=backend, output=True)
    if y_sim.shape != rec.y.shape:
        raise InvalidParameterError(
            f"the model simulated {y_sim.shape} samples for a record of {rec.y.shape}"
        )
    res = rec.y - y_sim
    tail, ytail = res[k:], rec.y[k:]
    spread = float(np.linalg.norm(ytail - ytail.mean()))
    for arr in (res, y_sim):
        arr.setflags(write=False)
    return ValidationReport(
        t=rec.t,
        y=rec.y,
        y_sim=y_sim,
        residuals=res,
        rmse=float(np.sqrt(np.mean(tail**2))),
        nrmse=float(np.linalg.norm(tail) / spread) if spread > 0 else float("inf"),
        max_error=float(np.max(np.abs(tail))),
        lead_in=k,
        model=label,
        units=str(units),
    )
