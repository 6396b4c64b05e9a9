"""The conversion of ``studies/mr_place.py``: a term on x as the rod sees it.

The study reads a dashpot (or spring) across the hysteretic element, fitted with a free |G_i| per file, as a
dashpot on the measured rod velocity of ``c |G_i|`` per file (docs/mr-damper-left.md, section 6). Checked on
the library's own model: one experiment with a dashpot on x of value c and gain g draws the same output as
the same element with a dashpot on u of value c |g|, and the study's ``on_rod`` returns that u-value in
physical units.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType, SimpleNamespace

import numpy as np
import pytest
from bouc_wen_id.augmented import AugExperiment, AugParams, augmented_output
from bouc_wen_id.diagnosis.fitting import Scale, physical

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


study = _load("mr_place")


def _fit(par: AugParams) -> SimpleNamespace:
    return SimpleNamespace(params=par, standard_error=lambda term: 0.0)


@pytest.mark.parametrize("gain", [0.7, 3.0])
def test_a_dashpot_on_x_is_a_dashpot_on_the_rod_scaled_by_the_gain(gain: float) -> None:
    """A sine input, phase 0: ``viscous@x`` = c with gain g and ``viscous`` = c |g| draw the same loop (to
    the simulator's accuracy), and ``on_rod`` turns the first into the second's physical value for two
    different data scales; with two files of different gains it returns one value per file."""
    c = 0.05
    e = AugExperiment(np.zeros(256), 1.0, 2.0 * math.pi, 0.0, 1.0)
    on_x = AugParams(0.6, 0.4, 1.5, ("viscous@x",), np.array([c]), np.array([gain]), np.array([0.0]))
    on_u = AugParams(0.6, 0.4, 1.5, ("viscous",), np.array([c * gain]), np.array([gain]), np.array([0.0]))
    y_x = augmented_output(e, on_x, 0, substeps=16, backend="numpy")
    y_u = augmented_output(e, on_u, 0, substeps=16, backend="numpy")
    assert np.max(np.abs(y_x - y_u)) < 1e-6 * np.ptp(y_x)
    for sc in (Scale(250.0, 12.5), Scale(3.0, 0.5)):
        lv = SimpleNamespace(scale=sc)
        rod = study.on_rod(lv, _fit(on_x))
        assert set(rod) == {"viscous@x"}
        want = physical(_fit(on_u), sc, "viscous")[0]  # type: ignore[arg-type]
        assert rod["viscous@x"] == pytest.approx([want], rel=1e-12)
    two = AugParams(0.6, 0.4, 1.5, ("viscous@x",), np.array([c]), np.array([gain, -2 * gain]), np.zeros(2))
    rod2 = study.on_rod(SimpleNamespace(scale=Scale(250.0, 12.5)), _fit(two))["viscous@x"]
    assert rod2[1] == pytest.approx(2 * rod2[0], rel=1e-12)  # |G_i|: the sign of the gain does not enter
