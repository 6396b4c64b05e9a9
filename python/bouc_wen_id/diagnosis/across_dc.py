"""diagnose's rules on the DC across conditions: the centre terms judged between experiments under a noise
coloured at the DC (dc_between.py), and an "adequate" headline whose DC was taken out (dc_untested.py)
(session 47, across47).

- Under a noise coloured at the DC in every experiment of a condition (centre_only.slow_dc: pink, 1/f
  noise), diagnose judges the centre terms' DC between experiments (:func:`.dc_between.dc_between`): the
  law test leaves each experiment's DC free (the offset's law, all DC, not tested) and a centre term stands
  only when the DCs it explains stand out of their spread (:func:`.dc_between.centre_stands_out`).
  ``diagnose_across`` ran neither; here each condition's trial and law test run under its own condition's
  rule (:func:`between`, :func:`stands_out`).
- When a condition's zero wandered or drifted and its DC was taken out (dc_untested.why), diagnose's
  "adequate" headline says an output offset could not be tested; ``diagnose_across``'s said it only in a
  detail (tests/test_across_dc47.py). :func:`untested` puts diagnose's caveat in its headline, with the
  conditions where it holds.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any, TypeVar

from . import dc_untested
from .centre_only import slow_dc
from .dc_between import centre_stands_out, dc_between

_A = TypeVar("_A", bound=Any)


def slow(group: Any) -> bool:
    """Whether ``group``'s (a condition's) DC is judged between its experiments (centre_only.slow_dc)."""
    return bool(slow_dc(group.exps)) if group.exps else False


@contextmanager
def between(group: Any) -> Iterator[None]:
    """Within: the condition's DC judged as diagnose would judge it (:func:`.dc_between.dc_between`)."""
    with dc_between(bool(getattr(group, "slow_dc", False))):
        yield


def stands_out(group: Any, fit: Any, term: str, level: float) -> bool:
    """:func:`.dc_between.centre_stands_out` at ``group``'s condition, under its rule."""
    with between(group):
        return centre_stands_out(group.sx, fit, term, level, group.substeps)


def untested(out: _A, groups: Sequence[Any]) -> _A:
    """``out`` with diagnose's caveat in its "adequate" headline where a condition's DC was taken out
    (dc_untested.headlined, the conditions said); unchanged otherwise."""
    causes = [(g.label, g.centres, dc_untested.why(g.centres)) for g in groups]
    hit = [(label, wander, cause) for label, wander, cause in causes if cause]
    if not hit:
        return out
    first = hit[0][2]  # the conditions with the first one's cause (another's is said in the details)
    where = ", ".join(label for label, _, cause in hit if cause == first)
    return dc_untested.headlined(out, hit[0][1], f" at {where}")


__all__ = ["between", "slow", "stands_out", "untested"]
