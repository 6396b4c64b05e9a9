"""How a term's values move with the condition: the smoothness check of :func:`.across.diagnose_across`
(moved here from across.py, which re-exports it, so that :mod:`.across_clean` recomputes it on the values it
replaces without importing across.py)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

#: Highest polynomial degree in the condition tried by the smoothness check ("low order").
MAX_DEGREE = 2


def smoothness(
    conditions: ArrayLike, values: ArrayLike, ses: ArrayLike, max_degree: int = MAX_DEGREE
) -> tuple[float, ...]:
    """chi-square p-values of the weighted least-squares polynomials of degree 0 .. ``max_degree`` in the
    condition through ``values`` (weights ``1 / se^2``): a degree with dof ``K - degree - 1 >= 1`` only.
    A p above the level says the values move as that polynomial within their se."""
    from scipy.special import chdtrc  # type: ignore[import-untyped]

    c = np.asarray(conditions, dtype=np.float64)
    v = np.asarray(values, dtype=np.float64)
    s = np.asarray(ses, dtype=np.float64)
    if not (np.all(np.isfinite(v)) and np.all(np.isfinite(s)) and np.all(s > 0)):
        return ()
    span = float(np.ptp(c)) or 1.0
    z = (c - float(np.mean(c))) / span
    out = []
    for d in range(min(max_degree, c.size - 2) + 1):
        a = np.vander(z, d + 1) / s[:, None]
        coef, *_ = np.linalg.lstsq(a, v / s, rcond=None)
        chi2 = float(np.sum((a @ coef - v / s) ** 2))
        out.append(float(chdtrc(c.size - d - 1, chi2)))
    return tuple(out)


__all__ = ["MAX_DEGREE", "smoothness"]
