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

A model holds only in the units it was fitted in (``WienerPlant.units``, set by the fits and kept by
``save_model``/``load_model``).  A record in other units of the same quantities (``m``/``kN`` for a model in
``mm``/``N``) is converted to the model's with a :class:`~bouc_wen_id.errors.UnitWarning`; one in units no
scale relates to the model's is a :class:`~bouc_wen_id.errors.UnitMismatchError`
(:func:`bouc_wen_id.units.against_model`); the report's notes say what was done or could not be checked.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Optional

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._backend import Backend
from .._text import Summarised
from ..errors import IdentifiabilityWarning, InvalidParameterError
from ..model import BoucWen, WienerPlant
from ..units import against_model, label_of, units_of
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
    units : str
        The unit of ``y`` (the model's, when it states one).
    notes : tuple of str
        Units converted to the model's, or that could not be checked against it.
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
    notes: tuple[str, ...] = ()

    def summary(self) -> str:
        u = f" {self.units}" if self.units else ""
        return (
            f"ValidationReport: {self.model} on {self.t.size} samples (lead-in {self.lead_in})\n"
            f"  RMSE = {self.rmse:.4g}{u}, NRMSE = {self.nrmse:.4g}, max |error| = {self.max_error:.4g}{u}"
        ) + "".join(f"\n  note: {n}" for n in self.notes)

    def to_dict(self) -> dict[str, Any]:
        return {
            "model": self.model,
            "samples": int(self.t.size),
            "lead_in": self.lead_in,
            "rmse": self.rmse,
            "nrmse": self.nrmse,
            "max_error": self.max_error,
            "units": self.units,
            "notes": list(self.notes),
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
        plant = WienerPlant(
            tf.transfer_function,
            BoucWen(model.beta, model.gamma, model.mu),
            units=getattr(model, "units", {}),
        )
        return plant, label
    raise InvalidParameterError(
        f"cannot simulate a {type(model).__name__}: give a WienerPlant, a TimeDomainFit, an "
        "IdentificationResult or an object with a simulate_record(t, u) method"
    )


def validate(
    model: object,
    t: Any,
    u: Optional[ArrayLike] = None,
    y: Optional[ArrayLike] = None,
    *,
    lead_in: Optional[float] = None,
    substeps: int = 4,
    units: str = "",
    data_units: Optional[Mapping[str, str]] = None,
    name: str = "",
    backend: Backend = "rust",
) -> ValidationReport:
    """Simulate ``model`` on the record ``(t, u, y)`` from rest at ``t[0]`` and compare with ``y``.

    Parameters
    ----------
    model : WienerPlant, TimeDomainFit, IdentificationResult, ...
        See the module docstring.
    t, u, y : array_like
        A record the model was not fitted to (checked as :class:`TimeRecord`); or ``t`` a
        :class:`~bouc_wen_id.Measurement` or :class:`~bouc_wen_id.Recording` (``u``, ``y`` left out), whose
        units and name are then used.
    lead_in : float, optional
        Seconds at the start left out of the figures (the record does not start from rest).
    substeps : int
        RK4 steps per sample interval.
    units : str
        Units of ``y`` of the record: the report's label, and checked against the model's y unit (when
        ``data_units`` does not state it).
    data_units : mapping, optional
        Units of the record's ``u`` and ``y`` (``{"u": "m", "y": "kN"}``): converted to the model's with a
        :class:`~bouc_wen_id.errors.UnitWarning`, refused when no scale relates them (module docstring).
    name : str
        The record's name in messages (default: the item's name, or "the record").

    Raises
    ------
    UnitMismatchError
        The record's units and the model's measure different things (``N`` for the model's ``mm``).
    InvalidParameterError, NonFiniteError, TimeAxisError, InsufficientDataError
        A model that cannot be simulated, or a bad record.
    """
    if u is None and y is None and all(hasattr(t, k) for k in ("t", "u", "y")):
        item = t
        t, u, y = item.t, item.u, item.y
        data_units = units_of(item) if data_units is None else data_units
        name = name or label_of(item, 0)
    if u is None or y is None:
        raise InvalidParameterError("validate needs t, u and y (or a Measurement or Recording as t)")
    given = dict(data_units or {})
    if units and "y" not in given:
        given["y"] = str(units)
    against = against_model(model, given, name or "the record", stacklevel=3)
    rec = TimeRecord(t, u, y)
    if against.factors:
        rec = TimeRecord(rec.t, rec.u * against.factors.get("u", 1.0), rec.y * against.factors.get("y", 1.0))
    units = against.units.get("y", str(units))
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
        notes=against.notes,
    )
