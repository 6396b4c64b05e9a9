"""python-control interop: the identified points as a ``control.FRD``, transfer functions both ways.

``control`` (the Python Control Systems Library) is optional: ``pip install "bouc_wen_id[control]"``.  It
is imported only when one of these functions is called, and its absence is an :class:`ImportError` that
says how to install it.

Sign convention: the library reports ``G(j omega) = |G| exp(-j phi)`` with the paper's phase
``phi = -angle G``; the complex numbers handed to ``control`` are the ordinary complex frequency response
``G(j omega)`` (so ``control``'s phase is ``-phi``).

Reference: R. M. Murray et al., *python-control*, https://python-control.readthedocs.io (FRD, tf, pade).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Optional

import numpy as np

from . import _optional
from .errors import InvalidParameterError
from .validation import count

if TYPE_CHECKING:  # pragma: no cover - typing only
    from .model import TransferFunction
    from .result import IdentificationResult

__all__ = ["to_frd", "to_control", "tf_coefficients"]

#: Highest Pade order accepted: beyond it ``control.pade``'s coefficients lose every digit.
MAX_PADE_ORDER = 10


def _control() -> Any:
    return _optional.require("control", "python-control interop")


def to_frd(result: IdentificationResult) -> Any:
    """The identified points as a ``control.FRD``.

    Parameters
    ----------
    result : IdentificationResult
        Its experiments' frequencies (rad/s) and ``G(j omega_i) = |G_i| exp(-j phi_i)`` (alpha-normalised).

    Returns
    -------
    control.FRD
        Sorted by frequency, response ``G(j omega)`` as complex numbers (python-control's phase is
        ``-phi``).  Two experiments at one frequency are refused (an FRD holds one value per frequency).
    """
    control = _control()
    w = result.frequencies
    g = result.frequency_response
    order = np.argsort(w)
    w, g = w[order], g[order]
    if np.any(np.diff(w) == 0.0):
        raise InvalidParameterError("two experiments share a frequency; an FRD holds one point per frequency")
    return control.FRD(g, w)


def to_control(tf: TransferFunction, pade_order: Optional[int] = None) -> Any:
    """``tf`` as a ``control.TransferFunction`` (continuous time).

    Parameters
    ----------
    tf : TransferFunction
        ``exp(-delay s) num/den``.
    pade_order : int, optional
        Order of the Pade approximation of the delay (``control.pade``), multiplied in.  Required when
        ``tf.delay > 0``: a rational system cannot hold a delay, and dropping it silently would change the
        phase.  To keep the delay apart instead, convert ``TransferFunction(tf.num, tf.den)`` and carry
        ``tf.delay`` yourself.

    Raises
    ------
    InvalidParameterError
        ``delay > 0`` without ``pade_order``, or a ``pade_order`` outside 1..10.
    """
    control = _control()
    rational = control.tf(np.asarray(tf.num, dtype=float), np.asarray(tf.den, dtype=float))
    if tf.delay == 0.0:
        return rational
    if pade_order is None:
        raise InvalidParameterError(
            f"the transfer function has a delay of {tf.delay:g} s, which python-control cannot hold "
            "exactly: pass pade_order=n for a Pade approximation, or convert "
            "TransferFunction(tf.num, tf.den) and keep the delay apart"
        )
    num, den = control.pade(tf.delay, count("pade_order", pade_order, 1, MAX_PADE_ORDER))
    return rational * control.tf(num, den)


def tf_coefficients(sys: Any) -> tuple[np.ndarray, np.ndarray]:
    """``(num, den)`` (highest power first) of a SISO, continuous-time ``control`` system (tf or ss).

    :meth:`TransferFunction.from_control <bouc_wen_id.model.TransferFunction.from_control>` builds the
    library's transfer function from them (and checks it is proper and stable).

    Raises
    ------
    InvalidParameterError
        Not a control LTI system (or an FRD), not SISO, or discrete time.
    """
    control = _control()
    if not isinstance(sys, control.LTI) or isinstance(sys, control.FRD):
        raise InvalidParameterError(
            f"from_control needs a control.TransferFunction or StateSpace, got {type(sys).__name__}"
        )
    if sys.ninputs != 1 or sys.noutputs != 1:
        raise InvalidParameterError(f"only SISO systems convert, got {sys.noutputs}x{sys.ninputs}")
    if sys.dt not in (0, None):
        raise InvalidParameterError(f"only continuous-time systems convert, got dt = {sys.dt}")
    num, den = control.tfdata(sys)
    return np.asarray(num[0][0], dtype=float), np.asarray(den[0][0], dtype=float)
