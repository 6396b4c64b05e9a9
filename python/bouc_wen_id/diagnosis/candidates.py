"""The candidates a selection step tests on the averaged period: its Bonferroni family.

:func:`.run.diagnose` tests every candidate it was given, less the distortion term when every input is a pure
sine (the term scales the inputs' own harmonics: on pure sines it is the plain model), and the selection
steps test those left less the degradation terms (tested on period blocks, in drift space). The planner
(planning/_power.py) sizes the targeted step's level from the same list, so the two cannot drift apart.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..terms import DIAGNOSIS_CANDIDATES, Distortion
from .drift import DRIFT_TERMS


def step_candidates(candidates: Sequence[str] = DIAGNOSIS_CANDIDATES, *, pure_sines: bool) -> tuple[str, ...]:
    """The candidates a selection step tests among ``candidates``; ``pure_sines``: no input has a harmonic
    above its noise floor (then the distortion term is not tested)."""
    return tuple(c for c in candidates if c not in DRIFT_TERMS and not (pure_sines and c == Distortion.kind))


__all__ = ["step_candidates"]
