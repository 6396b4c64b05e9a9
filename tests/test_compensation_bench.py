"""Issue 21's bench on an augmented plant with an IDENTIFIED model (benches/compensation.py).

The plant is the bench's own simulator (spline input, ``lsim`` for G and the lag, RK4 in the path variable
for the hysteresis: not the library's integrator); the model is identified from its noisy sine experiments
by the augmented fit with the plant's terms given, and the compensator built on it must cut the tracking
error well below the uncompensated and the inverse-linear baselines.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
#: The bench, a script beside the package (not an installed module).
bench: Any = importlib.import_module("compensation")


@pytest.fixture(scope="module")
def augmented() -> tuple[Any, bw.WienerPlant]:
    case = next(c for c in bench.cases() if c.plant.terms)
    return case, bench.identified(case, 3, 4)


def test_the_augmented_fit_recovers_the_terms_from_noisy_sines(augmented: tuple[Any, bw.WienerPlant]) -> None:
    case, model = augmented
    assert isinstance(model, bw.WienerPlant)
    true = {t.kind: t.value for t in case.plant.terms}
    got = {t.kind: t.value for t in model.terms}
    assert set(got) == set(true)
    for kind, value in true.items():
        assert got[kind] == pytest.approx(value, rel=0.05), kind
    h, ht = model.hysteresis, case.plant.hysteresis
    assert (h.beta, h.gamma, h.mu) == pytest.approx((ht.beta, ht.gamma, ht.mu), rel=0.05)
    # The plain identification cannot serve: it refuses these data (mu driven to 1 by the viscous term).
    with pytest.raises(bw.BoucWenIdError):
        bw.identify(bench.recordings(case, 3, 4))


def test_the_identified_augmented_model_compensates_at_least_3x(
    augmented: tuple[Any, bw.WienerPlant],
) -> None:
    case, model = augmented
    t, y_ref = bench.references(case, 0.3, 3)["sine"]
    comp = bw.compensate(model, y_ref, t)
    ident = bench.error(case.plant, t, comp.u, y_ref)
    base = bench.baselines(case.plant, t, y_ref)
    none = bench.error(case.plant, t, base["none"], y_ref)
    linear = bench.error(case.plant, t, base["inverse linear"], y_ref)
    assert none / ident >= 3.0 and linear / ident >= 3.0, (none, linear, ident)
    # Power: the same model without its terms does far worse on this plant.
    bare = bw.WienerPlant(model.linear, model.hysteresis)
    worse = bench.error(case.plant, t, bw.compensate(bare, y_ref, t).u, y_ref)
    assert worse > 3.0 * ident, (worse, ident)
    assert np.isfinite(comp.u).all()
