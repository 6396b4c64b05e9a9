"""``diagnose_across`` applies diagnose's final check of the named set (diagnosis/across_final.py,
diagnosis/final_terms.py): a term named at an early joint step that the final joint model no longer needs is
dropped at every condition and said so."""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
from bouc_wen_id.diagnosis import across_final

sys.path.insert(0, str(Path(__file__).resolve().parent))
isolator: Any = importlib.import_module("test_diagnosis_final_terms")._isolator


def test_terms_named_early_and_unneeded_in_the_joint_model_are_dropped() -> None:
    """Review 38's isolator (the package's simulator: a spring and a damper on x, first-order G) at two
    conditions (seeds 1, 2). Before across40 the joint model kept viscous damping on u (c = -0.00024 +-
    0.0051) and named a sensor lag tau = 4.7e-19 +- 0.0082 s in an "explained" verdict."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = bw.diagnose_across([isolator(1), isolator(2)], [0.0, 1.0])
    assert a.status == "explained", a.verdict
    assert set(a.named) == {"stiffness", "viscous@x"}, a.verdict
    assert {t for t, _ in a.steps[-1].unneeded} == {"viscous", "sensor_lag"}, a.verdict
    assert all("viscous" not in f.params.terms and "sensor_lag" not in f.params.terms for f in a.final_fits)
    assert "not needed once" in a.verdict and "sensor lag (p adj" in a.verdict, a.verdict
    c = next(t for t in a.terms if t.term == "viscous@x")
    assert c.shared_fit is not None and c.shared_fit.shared, a.verdict
    assert a.steps[-1].to_dict()["unneeded"][0]["p_adjusted"] >= 0.05


def test_a_single_named_term_is_not_retested() -> None:
    fit = SimpleNamespace(params=SimpleNamespace(terms=("viscous",)), cost=1.0)
    g = SimpleNamespace(current=fit)
    steps = [SimpleNamespace(chosen="viscous", pair=(), trials=(), level=0.05, unneeded=())]
    assert across_final.check([g, g], steps, 0.05) is steps  # nothing refitted, nothing dropped
