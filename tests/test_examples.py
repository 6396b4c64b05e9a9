"""The scripts of ``examples/`` run as a user runs them, and say what they promise."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _run(script: str, *args: str, env: dict[str, str] | None = None) -> str:
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / script), *args],
        capture_output=True,
        text=True,
        timeout=900,
        env={**os.environ, **(env or {})},
    )
    assert done.returncode == 0, f"{script} failed:\n{done.stdout}\n{done.stderr}"
    return done.stdout


@pytest.mark.real_data
def test_mr_damper_example(real_data: Path) -> None:
    out = _run("mr_damper.py", env={"BOUC_WEN_ID_REAL_DATA": str(real_data)})
    assert "1 steady segment(s)" in out and "dropped" in out and "amplitude ramp" in out
    nrmse, linear = (float(v) for v in out.split("loop fit NRMSE ")[1].split(" for ")[0].split(" against "))
    # The hysteresis model explains the damper's force better than a spring + dashpot.
    assert 0 < nrmse < linear


def test_simulated_study_example() -> None:
    out = _run("simulated_study.py", "--seeds", "3")
    rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()[1:4]}
    for name in ("beta", "gamma", "mu"):
        truth, mean, sd, crb = (float(v) for v in rows[name])
        assert abs(mean - truth) < 5 * crb and 0 < sd < 5 * crb
    assert "seeds" in out.splitlines()[-1]


def test_lab_folder_cli_example(tmp_path: Path) -> None:
    out = _run("lab_folder_cli.py", str(tmp_path))
    assert "$ bouc-wen-id identify" in out
    result = json.loads((tmp_path / "report" / "result.json").read_text())
    assert len(result["experiments"]) == 3
    assert result["beta"] == pytest.approx(0.8, rel=0.05) and result["mu"] == pytest.approx(1.6, rel=0.05)
    segments = json.loads((tmp_path / "report" / "segments.json").read_text())
    assert all(s["kept"] and any(d["reason"] == "amplitude ramp" for d in s["dropped"]) for s in segments)
