"""The tools of ``studies/mr_what_is_left.py`` on data whose answer is known.

The study's tables (docs/mr-damper-left.md) rest on three measurements of its own: the floor of the averaged
period (split halves, averaging noise, harmonics cut), the residual's localisation over the cycle, and a fit
with the Bouc-Wen condition beta >= |gamma| relaxed. Each is checked here on synthetic data: a record whose
noise is known, a residual placed in one zone of the cycle, and a loop drawn with gamma > beta.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.augmented import AugExperiment, AugParams, augmented_output, fit_augmented

STUDIES = Path(__file__).resolve().parents[1] / "studies"


def _load(name: str) -> ModuleType:
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, STUDIES / f"{name}.py")
    assert spec is not None and spec.loader is not None, f"cannot load studies/{name}.py"
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


study = _load("mr_what_is_left")


@pytest.mark.parametrize("sigma", [0.5, 4.0])
def test_floor_is_the_averaging_noise_on_a_record_with_known_noise(sigma: float) -> None:
    """A smooth periodic loop plus white noise of known sd: both floor estimates match
    sqrt(P (2K + 1) sigma^2 / n) / |ybar - mean| (the averaged period's own error), and nothing is cut."""
    rng = np.random.default_rng(1234)
    f, dt, periods = 2.0, 1.0 / 400.0, 12
    t = np.arange(int(periods / f / dt)) * dt
    th = 2.0 * math.pi * f * t
    u = 10.0 * np.cos(th)
    clean = 100.0 * np.tanh(2.0 * np.sin(th + 0.4)) + 15.0 * np.cos(th) + 5.0
    m = bw.Measurement(t, u, clean + sigma * rng.standard_normal(t.size), nominal_frequency=2.0 * math.pi * f)
    fl = study.floor_of(m)
    ap = bw.average_measurement(m)[0]
    n = ap.stop - ap.start
    p = ap.ybar.size
    expected = math.sqrt(p * (2 * ap.harmonics + 1) * sigma**2 / n) / float(
        np.linalg.norm(ap.ybar - ap.ybar.mean())
    )
    assert 0.6 * expected < fl["split_half"] < 1.6 * expected
    assert 0.8 * expected < fl["noise"] < 1.25 * expected
    assert fl["cut"] < 0.5 * expected  # what is cut stays below the noise
    assert fl["floor"] == pytest.approx(math.hypot(max(fl["split_half"], fl["noise"]), fl["cut"]), rel=1e-12)


def test_localise_puts_a_residual_after_the_reversal_in_its_zone() -> None:
    """A residual bump 5 degrees after each reversal of the input: concentrated in the first zone, none in
    the mid-stroke; a constant residual is all DC and evenly spread."""
    p = 360
    half = math.pi / p  # the grid half a degree off the zones' edges
    z = 2.0 * math.pi * np.arange(p) / p + half
    model = np.sin(z)
    after = np.degrees(np.mod(z, math.pi))
    bump = np.exp(-(((after - 5.0) / 3.0) ** 2))
    e = AugExperiment(model + 0.1 * bump, 1.0, 1.0, half, 1.0)
    r = study.localise(e, model)
    assert r["zones"][0] > 5.0
    assert r["zones"][2] < 1e-3
    assert sum(c * (hi - lo) / 180.0 for c, (lo, hi) in zip(r["zones"], study.ZONES)) == pytest.approx(1.0)
    flat = study.localise(AugExperiment(model + 0.05, 1.0, 1.0, half, 1.0), model)
    assert flat["dc"] == pytest.approx(1.0)
    assert flat["zones"] == pytest.approx([1.0] * len(study.ZONES), rel=1e-6)


def test_relaxed_fit_finds_a_softer_unloading_branch_the_constrained_fit_cannot_draw() -> None:
    """Loops drawn by the NumPy reference with gamma = 3 beta (unloading softer than the initial slope,
    outside Bouc-Wen's beta >= |gamma|), small noise: the library's fit stops on beta = gamma; the
    relaxed fit of the study recovers beta and gamma and brings the cost to the noise."""
    rng = np.random.default_rng(7)
    truth = AugParams(0.3, 0.9, 1.6, (), np.zeros(0), np.array([2.5, 4.0]), np.array([0.2, -0.3]))
    sd, n_periods = 0.01, 10
    exps = []
    for i, (amp, freq) in enumerate([(1.0, 1.0), (0.8, 3.0)]):
        e0 = AugExperiment(np.zeros(128), amp, freq, 0.0, n_periods / sd**2)
        y = augmented_output(e0, truth, i, substeps=16, backend="numpy")
        exps.append(
            AugExperiment(
                y + sd / math.sqrt(n_periods) * rng.standard_normal(y.size), amp, freq, 0.0, e0.weight
            )
        )
    start = AugParams(0.6, 0.6, 1.6, (), np.zeros(0), truth.gains * 1.05, truth.phases + 0.05)
    constrained = fit_augmented(exps, start, substeps=16)
    assert "beta=gamma" in constrained.active
    par, cost = study.relaxed_fit(exps, constrained.params, 16)
    assert par.gamma > 2.0 * par.beta
    assert par.beta == pytest.approx(0.3, rel=0.05)
    assert par.gamma == pytest.approx(0.9, rel=0.05)
    dof = sum(e.ybar.size for e in exps) - 7
    assert cost < 1.5 * dof
    assert constrained.cost > 3.0 * cost
