"""The diagnosis of missing physics: where the model misses, which term it left out, and the proof.

``diagnose(experiments)`` fits the plain Wiener-Bouc-Wen model and the library's candidate terms jointly,
names a term only when it passes a nested test at a controlled false-alarm rate, explains a material share
of the misfit and improves the fit on held-out experiments, and says "unexplained" (and where) otherwise.
Modules, one job each: ``data`` (experiments with their DC and period record), ``locate`` (where),
``fitting`` (the augmented fits in scaled units), ``select`` (forward selection, held-out), ``result``
(the Diagnosis value), ``run`` (the orchestration), ``report`` (figures and the HTML page), ``structure``
(Bouc-Wen in feedback, a structural rival of the cascade), ``stability`` (a term that comes and goes
under preprocessing variants is an alternative, not a finding: ``diagnose_stable``), ``speed`` (switches
of the speed-ups, for the speed bench's before/after).
"""

from __future__ import annotations

from .data import DiagExperiment, prepare
from .locate import Localisation, locate
from .result import Diagnosis, NamedTerm
from .run import diagnose
from .saved import SavedDiagnosis, load_diagnosis
from .stability import Stability, diagnose_stable

__all__ = [
    "diagnose",
    "diagnose_stable",
    "Stability",
    "Diagnosis",
    "SavedDiagnosis",
    "load_diagnosis",
    "NamedTerm",
    "Localisation",
    "DiagExperiment",
    "locate",
    "prepare",
]
