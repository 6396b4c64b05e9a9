"""The adequacy test's statistic under a coloured noise: each harmonic weighed by its own level (session 39).

The fits weigh every sample of an experiment's averaged period with one variance, ``noise_var``; when the
noise is measurably coloured (data.noise_colour) that is the level of the band where it is largest (the DC or
the low harmonics of a red noise). For the fits this is a weighted least squares with a wrong but fixed
weight: still consistent, less efficient. For the adequacy test it is not: the residual at the higher
harmonics, where an AR(1) of phi = 0.8 is 3 to 12 times below that level, was divided by it, and the plain
model's chi2/dof sat at 0.1-0.2 with p = 1 on every null and every case with a term left out (reviews 38).

So the statistic the adequacy test reads is the residual of each experiment's averaged period harmonic by
harmonic, ``chi2 = sum_e N_e sum_k m_k P |R_k|^2 / sigma_k^2`` (``R_k = rfft(r)_k / P``, ``m_k`` 2 for the
two-sided harmonics, 1 for the DC and the Nyquist one: Parseval's weights, so with one level it is the fit's
own cost to rounding), with ``sigma_k^2`` the experiment's ``adequacy_var`` (its level at each harmonic
0..P/2, data.harmonic_levels). Its degrees of freedom are the fit's: the weights change the scale of each
harmonic, not how many the model spends. An experiment whose noise is white keeps the fit's weight, so a
white-noise diagnosis is unchanged. An experiment whose DC is free (its period means or its zero's drift taken
out: free_dc.py) has no weight on its residual's DC, as in the fit; with the free DCs about a common one
that leaves one degree of freedom uncounted (conservative).

The F tests of the candidate terms stay on the fit's own cost: a term's F is the drop in the cost the fit
minimises over that same cost per degree of freedom, so the single weight cancels from it; weighing the drop
harmonic by harmonic would test a statistic the fit did not minimise (a drop that may be negative).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Optional

import numpy as np
from numpy.typing import NDArray

from .data import DiagExperiment

FloatArray = NDArray[np.float64]


def relative_weights(exps: Sequence[DiagExperiment]) -> list[Optional[FloatArray]]:
    """``noise_var / sigma_k^2`` at harmonics 0..P/2 of each experiment whose noise is coloured (None when
    white or when the levels do not cover its period); the DC's weight 0 when the period means or the zero's
    drift were taken out (the fit's free DC, free_dc.py)."""
    out: list[Optional[FloatArray]] = []
    for e in exps:
        lv = e.adequacy_var
        ok = lv.size == e.samples_per_period // 2 + 1 and e.noise_var > 0
        w = e.noise_var / lv if ok and bool(np.all(lv > 0) and np.all(np.isfinite(lv[1:]))) else None
        if w is None and e.baseline_removed:
            w = np.ones(
                e.samples_per_period // 2 + 1
            )  # white, its DC free: the fit's cost harmonic by harmonic
        if w is not None and e.baseline_removed:
            w[0] = 0.0  # its DC set, not measured (baseline.py, zero_drift.py): no weight, as in the fit
        out.append(w)
    if not any(e.adequacy_var.size for e in exps):  # no coloured noise: the fit's own cost, as before
        return [None] * len(exps)
    return out


def statistic(
    weights: Sequence[Optional[FloatArray]], sx: Sequence[Any], outputs: Sequence[Any], cost: float
) -> float:
    """The adequacy chi-square of a fit with outputs ``outputs`` to ``sx`` (the module docstring): ``cost``
    (the fit's own) when every experiment's noise is white or ``weights`` do not match them."""
    if not any(w is not None for w in weights) or len(weights) != len(sx) or len(outputs) != len(sx):
        return cost
    total = 0.0
    for w, a, y in zip(weights, sx, outputs):
        r = np.asarray(a.ybar, dtype=np.float64) - np.asarray(y, dtype=np.float64)
        if w is None or w.size != r.size // 2 + 1:
            total += float(a.weight) * float(r @ r)
            continue
        c = np.fft.rfft(r) / r.size
        m = np.full(c.size, 2.0)
        m[0] = 1.0
        if r.size % 2 == 0:
            m[-1] = 1.0
        total += float(a.weight) * r.size * float(np.sum(m * np.abs(c) ** 2 * w))
    return total


__all__ = ["relative_weights", "statistic"]
