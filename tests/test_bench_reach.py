"""How far an absorbed outside effect is from detectable (benches/diagnosis.py: ``global_power``,
``absorbed_rates``): the power of the plain model's global test at what the plain model leaves, and the
outside rows' "adequate" cases that the test could not see half the time, reported beside the target."""

from __future__ import annotations

import importlib
import math
import statistics
import sys
from pathlib import Path
from typing import Any

from scipy.stats import f as f_dist  # type: ignore[import-untyped]

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
bench: Any = importlib.import_module("diagnosis")


def test_the_global_power_runs_from_the_level_through_one_half_at_the_global_limit() -> None:
    """At no effect the test rejects at its level; at the bench's global limit (unabsorbed's ``lam = dof
    (F_crit - 1)``) about half the time; more with more left unabsorbed."""
    level = 0.025
    for dof, noise_dof in ((1257, 12000), (120, 600)):
        lam_limit = dof * (float(f_dist.isf(level, dof, noise_dof)) - 1.0)
        assert bench.global_power(0.0, dof, noise_dof, level) == level
        powers = [bench.global_power(k * lam_limit, dof, noise_dof, level) for k in (0.25, 0.5, 1.0, 2.0)]
        assert all(a < b for a, b in zip(powers, powers[1:]))
        assert level < powers[0] and powers[-1] < 1.0
        assert abs(powers[2] - 0.5) < 0.05
    assert math.isnan(bench.global_power(5.0, 0, 100, level))


def _row(status: str, unabs: float, **kw: Any) -> dict[str, Any]:
    glob = 0.285
    row = {
        "kind": "outside",
        "scored_as": "outside",
        "term": "iwan",
        "place": "",
        "size": 10.0,
        "status": status,
        "detected": status != "adequate",
        "unexplained": status == "unexplained",
        "family": False,
        "wrong": False,
        "unabsorbed": unabs,
        "det_limit": 0.089,
        "global_limit": glob,
        "below_det": unabs < 0.089,
        "below_global": unabs < glob,
        "global_power": 0.5 * unabs / glob if unabs < glob else 0.9,
    }
    row.update(kw)
    return row


def test_an_outside_row_reports_its_absorbed_adequate_cases_beside_its_unchanged_target() -> None:
    """Of four cases: an "adequate" below the global test's 50 % point (absorbed), an "adequate" above it
    (a miss), "unexplained", and a wrong name below the point (still wrong). The target's rate keeps its
    definition; the absorbed one is counted only in the new column."""
    rows = [
        _row("adequate", 0.17),
        _row("adequate", 0.40),
        _row("unexplained", 0.20),
        _row("explained", 0.18, wrong=True),
    ]
    (line,) = bench.summarise(rows)
    assert line["honest"] == 0.25
    assert line["adequate_absorbed"] == 0.25
    assert line["honest_absorbed"] == 0.5
    assert line["global_power"] == statistics.median(r["global_power"] for r in rows)
    assert line["meets"] is False


def test_rows_that_are_not_outside_or_not_measured_get_no_absorbed_rates() -> None:
    """A library row, and an outside row where one case's unabsorbed part was not measured, report NaN."""
    lib = [_row("adequate", 0.17, kind="library", scored_as="library", term="viscous")]
    (line,) = bench.summarise(lib)
    assert math.isnan(line["adequate_absorbed"]) and math.isnan(line["honest_absorbed"])
    half = [_row("adequate", 0.17), {**_row("unexplained", 0.2), "below_global": None}]
    (line,) = bench.summarise(half)
    assert math.isnan(line["honest_absorbed"])


def test_the_progress_line_says_how_far_a_case_is_from_the_global_test() -> None:
    """Per case, on stderr: the status, the seed, and where measured the unabsorbed part against both
    points and the global test's power (so a missed case's distance from detectable is read per case)."""
    r = _row("adequate", 0.17, seed=58003)
    line = bench._progress(r)
    assert line.startswith("adequate (seed 58003)")
    assert "unabsorbed 0.170 sd" in line and f"power {r['global_power']:.2f}" in line
    assert bench._progress({"error": "boom", "seed": 1}) == "boom (seed 1)"


def test_a_diagnosis_own_test_is_read_from_its_experiments_and_alpha() -> None:
    """``unabsorbed_power`` reads the samples, dof, noise dof and level (alpha / 2) of the diagnosis: at the
    RMS of its own global limit (``unabsorbed``'s formula) the power is about one half."""
    from types import SimpleNamespace

    import numpy as np

    exps = [SimpleNamespace(ybar=np.zeros(128), noise_dof=1200) for _ in range(10)]
    d = SimpleNamespace(experiments=exps, settings={"alpha": 0.05})
    n, dof, noise_dof = 1280, 1280 - (3 + 20), 12000
    glob = math.sqrt(dof * (float(f_dist.isf(0.025, dof, noise_dof)) - 1.0) / n)
    assert bench.unabsorbed_power(d, glob) == bench.global_power(n * glob**2, dof, noise_dof, 0.025)
    assert abs(bench.unabsorbed_power(d, glob) - 0.5) < 0.05
    assert bench.unabsorbed_power(d, 0.5 * glob) < 0.5 < bench.unabsorbed_power(d, 1.5 * glob)
