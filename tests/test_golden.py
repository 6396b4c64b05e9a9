"""Golden outputs: the demo fit, frozen in ``tests/data/golden_demo.json``, from both backends.

The fixture holds what ``identify`` returned for a small noisy demo design (two frequencies, P = 64) with
each method when it was written; any change of a number shows here, whichever backend made it.  After an
intended change of the numerics, regenerate it with ``python tests/test_golden.py`` and say why in the
commit.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id._backend import Backend
from bouc_wen_id.demo import design_amplitudes
from bouc_wen_id.identification import Method
from numpy.testing import assert_allclose

GOLDEN = Path(__file__).with_name("data") / "golden_demo.json"
METHODS: tuple[Method, ...] = ("paper", "profile", "refined")
#: Tolerances against the fixture.  Rust: the same code on another machine differs by the last bits of
#: libm (sin, cos, pow), which the separable search and the LM amplify to about 1e-10.  NumPy: the parity
#: tolerances of the reference (the golden-section bracket 1e-8 and the profile's phase grid refinement).
RTOL = {"rust": 1e-9, "numpy": 1e-7}


def demo_recordings() -> list[bw.Recording]:
    plant = bw.demo_plant()
    freqs = (2.0, 5.0)
    plan = bw.SinePlan(
        freqs,
        design_amplitudes(plant, freqs),
        settle_periods=10,
        periods=3,
        samples_per_period=64,
        substeps=2,
        noise_sd=0.01,
        seed=7,
    )
    return bw.simulate(plant, plan)


def fit(method: Method, backend: Backend) -> dict[str, Any]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", bw.IdentifiabilityWarning)
        res = bw.identify(demo_recordings(), method=method, backend=backend)
    out: dict[str, Any] = {
        "beta": res.beta,
        "gamma": res.gamma,
        "mu": res.mu,
        "gains": res.gains.tolist(),
        "phases": res.phases.tolist(),
        "cost": res.cost,
        "iterations": res.iterations,
        "converged": res.converged,
    }
    if res.standard_errors is not None:
        out["standard_errors"] = res.standard_errors
    return out


@pytest.fixture(scope="module")
def golden() -> dict[str, Any]:
    data: dict[str, Any] = json.loads(GOLDEN.read_text(encoding="utf-8"))
    return data


@pytest.mark.parametrize("backend", ["rust", "numpy"])
@pytest.mark.parametrize("method", METHODS)
def test_demo_fit_matches_the_golden_fixture(
    golden: dict[str, Any], method: Method, backend: Backend
) -> None:
    want, got = golden[method], fit(method, backend)
    rtol = RTOL[backend]
    for name in ("beta", "gamma", "mu", "cost"):
        assert got[name] == pytest.approx(want[name], rel=rtol), name
    assert_allclose(got["gains"], want["gains"], rtol=rtol)
    assert_allclose(got["phases"], want["phases"], rtol=0, atol=rtol)
    assert got["iterations"] == want["iterations"] and got["converged"] == want["converged"]
    if "standard_errors" in want:
        for name, se in want["standard_errors"].items():
            # Second derivatives at the estimate: one order less agreement than the estimate itself.
            assert got["standard_errors"][name] == pytest.approx(se, rel=10 * rtol), name


def test_golden_fixture_is_a_real_fit(golden: dict[str, Any]) -> None:
    """The frozen numbers are a sensible identification of the demo plant, not placeholders."""
    assert set(golden) >= set(METHODS)
    for method in METHODS:
        assert abs(golden[method]["mu"] - 1.6) < 0.1 and abs(golden[method]["beta"] - 0.8) < 0.1
    assert np.all(np.asarray(golden["refined"]["gains"]) > 0)


if __name__ == "__main__":
    GOLDEN.parent.mkdir(exist_ok=True)
    frozen = {m: fit(m, "rust") for m in METHODS}
    GOLDEN.write_text(json.dumps(frozen, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    print(f"wrote {GOLDEN}")
