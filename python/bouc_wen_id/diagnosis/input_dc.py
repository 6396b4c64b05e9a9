"""A drive with a mean of its own (a preloaded actuator, a DC-biased coil) and a spring: whose offset it is.

The augmented model's terms acted on the input without its mean (``u = U cos``: the fits never saw the
input's DC), so a parallel spring's share of that mean, ``k x mean(u)``, landed on the output's DC, where the
offset term took it. Review 35: input ``u = U (cos + 0.2)``, stiffness on u k = 0.041,
no sensor offset, was "explained by: output offset y0 = 0.008776 ± 0.000126, parallel stiffness ... k =
0.04117": a sensor zero error 70 standard errors from 0 that does not exist (``y0 = k x 0.2 U``).

By its law a spring acts on the whole of its displacement, the mean included:

- on u, its share of the output's DC is ``k x u0`` with ``u0`` the measured input's mean: the stiffness
  on u sees it in the fits (``fitting.input_shape``), so an offset is named only for what is left, and the
  verdict says so beside it;
- on x, its share is ``k x G(0) x u0`` with ``G(0)`` untested (the experiments measure G at their own
  frequencies only): the recordings cannot tell a sensor offset from the preloaded spring, and the verdict
  says both, with the ``G(0)`` the spring reading needs.

:func:`qualify` adds that parenthesis after the offset in the headline; nothing else changes.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, Optional

from ..terms import Offset, Stiffness, StiffnessX
from .data import DiagExperiment

#: The input's mean counts as measured when it stands this many of its standard errors from 0...
MEASURED_SE = 5.0
#: ... and above this fraction of the input's amplitude (when its standard error is unknown, lab records:
#: :data:`UNKNOWN_SE_RELATIVE` instead).
MEASURED_RELATIVE = 1e-3
UNKNOWN_SE_RELATIVE = 1e-2
#: The experiments' drive means count as one level when they spread by less than this fraction of their mean.
SAME_MEAN = 0.2


def measured(e: DiagExperiment) -> bool:
    """Whether the experiment's input mean is measured: :data:`MEASURED_SE` of its standard errors from 0
    and above :data:`MEASURED_RELATIVE` of the amplitude (:data:`UNKNOWN_SE_RELATIVE` without an error)."""
    dc, se, amp = float(e.input_dc), float(e.input_dc_se), abs(float(e.amplitude))
    if not math.isfinite(se):
        return abs(dc) > UNKNOWN_SE_RELATIVE * amp
    return abs(dc) > MEASURED_RELATIVE * amp and abs(dc) > MEASURED_SE * se


def drive_mean(exps: Sequence[DiagExperiment]) -> Optional[float]:
    """The inputs' mean (units of u, averaged over the experiments) when some experiment's is
    :func:`measured`; None when every input is centred."""
    if not any(measured(e) for e in exps):
        return None
    return sum(float(e.input_dc) for e in exps) / len(exps)


def _se(t: Any) -> float:
    se = float(t.standard_error)
    return se if math.isfinite(se) else 0.0


def _on_u(off: Any, k: Any, u0: float) -> str:
    # The stiffness on u carries its share of the drive's mean in the fit (fitting.input_shape): y0 is the
    # rest, beyond it.
    share, sshare = float(k.value) * u0, abs(u0) * _se(k)
    return (
        f" (beyond the parallel stiffness's own share of the drive's mean u0 = {u0:.4g}, k × u0 = "
        f"{share:.4g} ± {sshare:.2g}, which the model carries: a sensor zero or another preload)"
    )


def _on_x(off: Any, k: Any, u0: float) -> str:
    y0, kv = float(off.value), float(k.value)
    g0 = y0 / (kv * u0) if kv * u0 != 0.0 else math.inf
    if not g0 > 0.0:
        # G's gains are reported positive (the sign convention of the identification) and a stable G's DC
        # gain has the sign of its low-frequency gain: a spring reading that needs G(0) < 0 is no reading
        # (the MR damper at 0 A needed G(0) = -919), so the offset is said alone
        return ""
    rel = math.hypot(_se(off) / y0 if y0 else 0.0, _se(k) / kv if kv else 0.0)
    need = f"G(0) = {g0:.3g} ± {abs(g0) * rel:.2g} [y]/[u]" if math.isfinite(g0) else "an unbounded G(0)"
    return (
        f" (or no offset at all: the stiffness on x acting on x's mean, k × G(0) × u0 with the drive's own "
        f"mean u0 = {u0:.4g}, gives this y0 if {need}; G at 0 is not tested, so these recordings cannot tell "
        "a sensor zero from a preloaded spring: a run with the drive's mean at another level would)"
    )


def qualify(verdict: str, named: Sequence[Any], exps: Sequence[DiagExperiment]) -> str:
    """``verdict`` with the offset's reading beside a named spring when the drive has a mean of its own (see
    the module docstring); unchanged otherwise."""
    off = next((t for t in named if t.term == Offset.kind), None)
    ku = next((t for t in named if t.term == Stiffness.kind), None)
    kx = next((t for t in named if t.term == StiffnessX.kind), None)
    if off is None or (ku is None and kx is None):
        return verdict
    u0 = drive_mean(exps)
    said = str(off)
    if u0 is None or said not in verdict:
        return verdict
    means = [float(e.input_dc) for e in exps]
    if ku is None and max(means) - min(means) > SAME_MEAN * abs(u0):
        # drives at different means: a spring on x would give each its own DC (k G(0) u0_i), which one
        # offset for all does not; "cannot tell them apart" would be false, and the fit did not test it
        return verdict
    add = _on_u(off, ku, u0) if ku is not None else _on_x(off, kx, u0)
    at = verdict.index(said) + len(said)
    return verdict[:at] + add + verdict[at:]
