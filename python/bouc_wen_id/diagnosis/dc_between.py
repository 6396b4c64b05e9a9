"""The centre terms' DC evidence under a noise coloured at the DC in every experiment (centre_only.slow_dc:
pink, 1/f noise), judged against the DCs' spread between experiments (studies/pinkoff46).

A record's mean under 1/f noise varies about 3x more than any level measured inside the record says
(studies/pink45). The output offset's law (one value for all experiments) compared each experiment's DC with
that level: a real offset of 10x failed its law and an asymmetry, whose DC also moves with each loop, took
the DC (7 of 10 seeds, studies/pink46). Within :func:`dc_between` (one diagnosis of a set, when slow):

- the law test leaves each experiment's DC free (law.py), so a term's law is judged on the rest of the
  loop, and the offset's law, all DC, is not tested: against the DCs' own spread between experiments, the
  only honest yardstick, they cannot differ;
- a centre term (the offset, asymmetry) stands as a candidate only when the DCs it explains stand out of
  that spread (:func:`centre_stands_out`: for the offset, the t-test of the DCs' mean, data.common_centre,
  as centre_only._between judges the plain model's DCs), beside its F test, whose DC level is the
  in-record one. Without it, asymmetry's law judged on the rest of the loop let its F test name it on 2 of
  20 pink nulls (studies/pinkoff46).

Outside it (and for white records, never slow) nothing changes.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import replace

import numpy as np

from ..augmented import AugExperiment, AugFit, augmented_output
from ..errors import BudgetExceededError
from ..terms import Asymmetry, Offset
from .free_dc import FreeDC

#: The terms whose evidence on a steady loop is the loop centre (the DC of each experiment); centre_only
#: takes them from here (it imports the verdict's modules, so the definition lives on this side).
CENTRE_TERMS = frozenset({Offset.kind, Asymmetry.kind})

_SLOW: ContextVar[bool] = ContextVar("slow_dc", default=False)


@contextmanager
def dc_between(slow: bool) -> Iterator[None]:
    """Within: the DC judged between experiments when ``slow`` (the module's rules)."""
    token = _SLOW.set(slow)
    try:
        yield
    finally:
        _SLOW.reset(token)


def slow_dc_now() -> bool:
    """Whether the diagnosis under way judges the DC between experiments (:func:`dc_between`)."""
    return _SLOW.get()


def centre_stands_out(
    exps: Sequence[AugExperiment], fit: AugFit, term: str, level: float, substeps: int
) -> bool:
    """Whether ``term`` may stand on its DC evidence: True unless the DC is judged between experiments and
    ``term`` is a centre term (the output offset, asymmetry: centre_only.CENTRE_TERMS) whose DC in each
    experiment does not stand out of the DCs' spread between experiments.

    ``d_i``: the DC the model without the term leaves in experiment ``i``; ``c_i``: the DC the term adds
    there (the fit's output less that model's). The DCs' regression through the origin on the term's,
    ``d = b c``, is t-tested against its residual spread (m - 1 dof; two-sided at ``level``). For the
    offset (``c_i`` all equal) it is the t-test of the DCs' mean, data.common_centre, as
    centre_only._between judges the plain model's DCs. Experiments whose DC is already free (free_dc.py: a
    wandering baseline, judged by the common centre there) are left as before, as is a model the core
    cannot evaluate."""
    from scipy.special import stdtr  # type: ignore[import-untyped]

    if not (_SLOW.get() and term in CENTRE_TERMS and term in fit.params.terms):
        return True
    if len(exps) < 3 or any(isinstance(e, FreeDC) for e in exps):
        return True
    values = np.array(fit.params.values, dtype=np.float64)
    values[fit.params.terms.index(term)] = 0.0
    without = replace(fit.params, values=values)
    try:
        y0 = [augmented_output(e, without, i, substeps=substeps) for i, e in enumerate(exps)]
    except BudgetExceededError:
        raise
    except Exception:  # noqa: BLE001 - as the law test: not judged here
        return True
    d = np.array([float(np.mean(e.ybar - np.asarray(y))) for e, y in zip(exps, y0)])
    c = np.array([float(np.mean(np.asarray(y1) - np.asarray(y))) for y1, y in zip(fit.outputs, y0)])
    cc = float(c @ c)
    if not cc > 0:
        return False  # the term adds no DC: it has none to stand on here
    b = float(d @ c) / cc
    s2 = float(np.sum((d - b * c) ** 2)) / (d.size - 1)
    if not s2 > 0:
        return b != 0.0
    t = abs(b) / math.sqrt(s2 / cc)
    return bool(2.0 * stdtr(d.size - 1, -t) < level)


__all__ = ["dc_between", "centre_stands_out", "slow_dc_now"]
