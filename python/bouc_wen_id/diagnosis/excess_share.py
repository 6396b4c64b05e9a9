"""The share of the excess a term removes: one convention for the forward selection and the pair step.

A term is named only when it removes a material share (select.MATERIAL_SHARE) of the excess the model
before it leaves: its drop in the fit's cost over that cost's excess over its degrees of freedom. When the
cost shows no excess (it is below its dof) while the adequacy test still fails, the two modules read
"no excess" in opposite ways: the forward selection gave every term a share of 1 (a term that removes cost
explains all there is), the pair step 0. Review 43 saw the first on a negative-damping device under AR(1)
noise: the fits weigh every harmonic with the noise's largest level (adequacy_chi2.py), the cost sat below
its dof, every candidate read share 1, and the share gated nothing: a term whose drop was of the noise's
own size passed the material-share test as if it explained the whole misfit.

The convention here: the excess is the one the adequacy test reads. Where the cost shows an excess, it is
the cost's (as before). Where it does not, and the model is not adequate, the share is read on the adequacy
statistic (the residual weighed harmonic by harmonic by the noise's own level, adequacy_chi2.py): what the
term removes of that statistic's excess over the same dof. A term that fixes what the adequacy test sees
keeps its share; one that lowers the cost by a noise-level amount, leaving the statistic's excess, does not.
Where neither shows an excess the share is 0: nothing to explain (a drop there is noise). The targeted
step (select.py: the plain model passed the global test, its candidates tested at half the level) asks no
share: its term, where the cost shows no excess, explains all there is (1), as before.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Optional


def share(
    before: float,
    after: float,
    dof: float,
    read: Optional[tuple[float, float]] = None,
    floor: float = 0.0,
    targeted: bool = False,
) -> float:
    """The share of the excess that a term removes (module docstring), capped at 1.

    Parameters
    ----------
    before, after : float
        The fit's cost without and with the term.
    dof : float
        The degrees of freedom of the model without it.
    read : (float, float), optional
        The adequacy statistic (adequacy_chi2.py) without and with the term, given only where the model
        without it fails its adequacy test: read where the cost shows no excess.
    floor : float
        The least excess counted (pairs.py: a partner refused alone leaves at least the chi-square's spread).
    targeted : bool
        The targeted step: 1 where the cost shows no excess.
    """
    excess = max(before - dof, floor)
    if excess > 0:
        return min((before - after) / excess, 1.0)
    if targeted:
        return 1.0
    if read is not None and all(math.isfinite(a) for a in read) and read[0] > dof:
        return min((read[0] - read[1]) / (read[0] - dof), 1.0)
    return 0.0


def reader(
    statistic: Optional[Callable[[Any], float]], base: Any, fails: bool
) -> Callable[[Any], Optional[tuple[float, float]]]:
    """``fit -> (statistic(base), statistic(fit))``, :func:`share`'s ``read`` for the fits of a step from
    ``base`` (the base's statistic computed once), or ``fit -> None`` when ``statistic`` is None or the base
    does not need it (``fails``: its cost shows no excess while it fails the adequacy test; a refitted base
    that passes has nothing to explain)."""
    if statistic is None or not fails:
        return lambda fit: None
    a0 = statistic(base)
    return lambda fit: (a0, statistic(fit))


__all__ = ["reader", "share"]
