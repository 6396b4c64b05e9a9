"""The constrained Levenberg-Marquardt stops on the boundary and says why (issue 19).

A model that does not fit pulls the joint fit beyond the Bouc-Wen condition beta >= |gamma|; the fit used to
crawl along beta = gamma to the 200-iteration cap (12 s for ten experiments). The active set ends it on the
face with a named reason. The misfit recordings come from the bench's independent generator
(``benches/generator.py``: exact G, its own RK4 of the hysteresis, its own noise), not from the library.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core, reference
from bouc_wen_id.reference import augmented as ref_augmented
from numpy.testing import assert_allclose

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
#: The bench's generator, a script beside the package (not an installed module).
gen: Any = importlib.import_module("generator")

#: Iterations the old projected LM spent on these cases (its cap); the active set needs a fraction.
OLD_CAP = 200


@pytest.mark.parametrize(("name", "place", "seed"), [("viscous", "u", 1), ("inertia", "x", 2)])
def test_a_misfit_folder_stops_on_beta_equal_gamma_and_says_so(name: str, place: str, seed: int) -> None:
    # Ten experiments (five frequencies x two levels) of a plant hiding a large mechanical term (300x the
    # averaged noise): the plain Wiener-Bouc-Wen model cannot draw these loops.
    case = gen.make_case("effect", name, place, 300.0, seed)
    assert len(case.recordings) == 10
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = bw.identify(case.recordings)
    messages = [str(w.message) for w in caught]
    boundary = [m for m in messages if "stopped on the boundary" in m]
    assert len(boundary) == 1, messages
    assert "beta = gamma" in boundary[0]
    assert res.converged is True
    assert not any(issubclass(w.category, bw.ConvergenceWarning) for w in caught)
    assert res.iterations < OLD_CAP // 2
    assert res.beta == pytest.approx(res.gamma, rel=1e-9)
    assert boundary[0] in res.warnings


def _misfit_loops(seed: int) -> tuple[list[Any], list[float], list[float]]:
    """Three steady loops plus a strong spring on the measured input (in phase with u, not with x) and noise:
    the plain model's fit runs into beta = gamma."""
    rng = np.random.default_rng(seed)
    ys, amps = [], []
    for a, ph in ((1.8, 1.1), (1.2, 2.5), (2.4, 0.4)):
        w = _core.steady_loop(a, 0.8, 0.2, 1.6, ph, 48, 4)[0]
        th = 2 * np.pi * np.arange(48) / 48
        ys.append(w + 1.5 * np.cos(th) + 0.01 * rng.standard_normal(48))
        amps.append(a)
    return ys, amps, [1e4, 2e4, 1e4]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_refine_stops_on_the_face_as_the_reference_does(seed: int) -> None:
    ys, amps, wts = _misfit_loops(seed)
    args = (ys, amps, wts, 0.7, 0.3, 1.7, [0.9, 1.2, 1.0], [1.05, 2.45, 0.4])
    got = _core.refine(*args, max_iter=OLD_CAP, substeps=3)
    want = reference.refine(*args, max_iter=OLD_CAP, substeps=3)
    # Both stop by a rule of their own (ftol or xtol: which one fires first is a matter of rounding).
    assert got[3] and want[3] and "max_iter" not in (got[6], want[6])
    assert list(got[7]) == list(want[7])
    assert "beta=gamma" in got[7]
    assert got[0][0] == pytest.approx(got[0][1], rel=1e-12)
    assert got[2] < OLD_CAP // 2
    assert got[1] == pytest.approx(want[1], rel=1e-8)
    assert_allclose(got[0], want[0], rtol=1e-6, atol=1e-8)


def test_an_interior_fit_names_no_face() -> None:
    rng = np.random.default_rng(5)
    ys = [_core.steady_loop(a, 0.8, 0.2, 1.6, ph, 48, 4)[0] for a, ph in ((1.8, 1.1), (1.2, 2.5))]
    ys = [y + 0.01 * rng.standard_normal(y.size) for y in ys]
    args = (ys, [2.0, 1.0], [1e4, 2e4], 0.7, 0.3, 1.7, [0.85, 1.25], [1.05, 2.45])
    for out in (
        _core.refine(*args, max_iter=50, substeps=3),
        reference.refine(*args, max_iter=50, substeps=3),
    ):
        assert out[3] and out[6] in ("ftol", "xtol") and list(out[7]) == []


def test_augmented_sensor_lag_stops_at_zero_as_the_reference_does() -> None:
    # Outputs that LEAD the model (shifted two samples early): the lag would go negative, so the fit holds
    # tau on its face tau = 0 and says so, in the core and in the oracle alike.
    rng = np.random.default_rng(8)
    terms = ["sensor_lag"]
    truth = np.array([0.8, 0.2, 1.6, 0.0])
    ys, amps, freqs, psis = [], [], [], []
    for i in range(3):
        a, om, psi = 1.0 + 0.5 * i, 2.0 + i, float(rng.uniform(0, 6))
        y = _core.augmented_output(64, a, om, psi, terms, truth, 0.9, 0.5 + 0.2 * i, 4)[0]
        ys.append(np.roll(y, -2) + 1e-3 * rng.standard_normal(64))
        amps.append(a)
        freqs.append(om)
        psis.append(psi)
    args = (ys, amps, freqs, psis, np.full(3, 1e6), terms, np.array([0.7, 0.25, 1.7, 0.01]))
    own = (np.full(3, 0.95), np.array([0.5, 0.7, 0.9]))
    got = _core.augmented_refine(*args, *own, substeps=3)
    want = ref_augmented.augmented_refine(*args, *own, substeps=3)
    assert got[5] and want[5] and "max_iter" not in (got[8], want[8])
    assert list(got[9]) == ["sensor_lag=0"]
    assert got[0][3] == 0.0
    # The oracle lands on the face to its own solver's roundoff: with NumPy 2.4's LAPACK its face step leaves
    # tau = 4e-27 (> 0, so its relative face test does not list it), with earlier ones exactly 0. Either way
    # it is the same stop: on the face to within 1e-20 s, listed when exactly on it.
    assert 0.0 <= want[0][3] <= 1e-20
    assert list(want[9]) == (["sensor_lag=0"] if want[0][3] == 0.0 else [])
    assert got[3] == pytest.approx(want[3], rel=1e-8)
    assert_allclose(got[0], want[0], rtol=1e-6, atol=1e-8)


def test_the_boundary_note_names_each_face() -> None:
    from bouc_wen_id.estimators import boundary_note

    assert boundary_note("ftol", ()) is None
    note = boundary_note("xtol", ("beta=gamma", "mu=lower", "play=upper", "sensor_lag=0"))
    assert note is not None
    for part in ("beta = gamma", "lower end of its bracket", "play at its upper limit", "sensor_lag at 0"):
        assert part in note
    assert "step became negligible" in note


def test_a_fit_held_at_mu_1_alone_is_said_a_valid_exponent() -> None:
    # Review 38 (7a): a true mu = 1 piezo's plain fit ended on mu's lower end and was told "the data pull the
    # model beyond what it can draw, so its intervals do not hold"; mu = 1 is a valid value there.
    import math

    from bouc_wen_id.estimators import boundary_note

    note = boundary_note("ftol", ("mu=lower",), "the plain fit", 1.0) or ""
    assert "valid exponent" in note and "one-sided" in note and "do not hold" not in note
    assert note.startswith("the plain fit ended with mu = 1")
    # Another face beside it, a lower end other than 1, or no mu given: the general warning as before.
    for active, mu in ((("mu=lower", "beta=gamma"), 1.0), (("mu=lower",), 1.5), (("mu=lower",), math.nan)):
        assert "do not hold" in (boundary_note("ftol", active, "the fit", mu) or "")
