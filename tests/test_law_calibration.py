"""The tools of ``studies/law_calibration.py`` (the law test's calibration under the truth)."""

from __future__ import annotations

import argparse
import importlib
import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _study() -> ModuleType:
    spec = importlib.util.spec_from_file_location("law_calibration", ROOT / "studies" / "law_calibration.py")
    assert spec is not None and spec.loader is not None, "cannot load studies/law_calibration.py"
    mod = importlib.util.module_from_spec(spec)
    sys.modules["law_calibration"] = mod
    spec.loader.exec_module(mod)
    return mod


def test_summary_shares_and_ks_on_known_p_values() -> None:
    """Shares below each level, the NaN count and the KS p: uniform p pass KS, p piled near 0 fail it."""
    study = _study()
    rng = np.random.default_rng(5)
    uniform = [
        {"term": "a", "place": "", "size": 10.0, "element_p": float(p), "law_p": float(p)}
        for p in rng.random(400)
    ]
    low = [
        {"term": "b", "place": "x", "size": 30.0, "element_p": float(p), "law_p": float(p)}
        for p in 0.2 * rng.random(100)
    ]
    nan = [{"term": "b", "place": "x", "size": 30.0, "element_p": math.nan, "law_p": math.nan}]
    lines = {ln["row"]: ln for ln in study.summary(uniform + low + nan)}
    a, b, pooled = lines["a"], lines["b@x"], lines["all rows"]
    ua = np.array([r["element_p"] for r in uniform])
    ub = np.array([r["element_p"] for r in low])
    assert a["n"] == 400 and a["nan"] == 0 and a["<0.05"] == float(np.mean(ua < 0.05))
    assert a["ks_p"] > 0.01
    assert b["n"] == 100 and b["nan"] == 1 and b["<0.1"] == float(np.mean(ub < 0.1))
    assert b["ks_p"] < 1e-6 and b["ks_law"] < 1e-6 and b["min"] == float(ub.min())
    assert pooled["n"] == 500 and pooled["nan"] == 1


def test_jobs_are_the_benchs_library_rows_without_drift_terms() -> None:
    """The study's cases are benches/diagnosis.py's library rows, their seeds; drift terms left out."""
    study = _study()
    bench = importlib.import_module("diagnosis")  # benches/diagnosis.py, on the path the study set

    args = argparse.Namespace(cases=2, seed=0, sizes="10,30", only="")
    jobs = study.jobs_of(args)
    bench_jobs = set(bench.new_jobs(argparse.Namespace(quick=False, cases=2, null=0, seed=0)))
    assert jobs and all(j in bench_jobs for j in jobs)
    names = {j[1] for j in jobs}
    assert "degradation" not in names and "stiffness_degradation" not in names
    assert {"series_dashpot", "sensor_lag", "viscous"} <= names
    assert all(j[3] in (10.0, 30.0) for j in jobs)
    only = study.jobs_of(argparse.Namespace(cases=3, seed=0, sizes="30", only="series_dashpot"))
    assert [(j[1], j[3]) for j in only] == [("series_dashpot", 30.0)] * 3
