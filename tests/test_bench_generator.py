"""The diagnosis bench's own generator (benches/generator.py) against the library's simulator.

The bench's verdicts are measured on recordings made another way than the library (exact G, its own RK4 of
the hysteresis); on a plain Wiener-Bouc-Wen plant, with no effect hidden, both must give the same steady
loop to integration accuracy, through G shapes that differ (a resonant G with a delay, a first-order G).
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
#: The bench's generator, a script beside the package (not an installed module).
gen: Any = importlib.import_module("generator")

#: Integration accuracy asked of the two simulators' steady loops: a tenth of the averaged noise sd the
#: bench sizes its effects in (the loop saturates at 1; the noise sd is 1 % of that).
TOL = 0.1 * gen.NOISE_SD / np.sqrt(gen.PERIODS)
#: Steady periods compared (after the generator's settle periods): enough for a steady loop, short to run.
KEEP = 3
TOTAL = (gen.SETTLE + KEEP) * gen.P


def _library(p: Any, terms: tuple[Any, ...] = ()) -> Any:
    plant = bw.WienerPlant(
        bw.TransferFunction(p.num, p.den, delay=p.delay),
        bw.BoucWen(beta=p.beta, gamma=p.gamma, mu=p.mu),
        terms=terms,
    )
    plan = bw.SinePlan(
        p.omegas,
        p.amplitudes,
        settle_periods=gen.SETTLE,
        periods=KEEP,
        samples_per_period=gen.P,
        substeps=16,
        noise_sd=0.0,
        seed=0,
    )
    return bw.simulate(plant, plan)


@pytest.mark.parametrize("seed, shape", [(1, "resonant"), (4, "first")])
def test_generator_and_library_give_the_same_steady_loop(seed: int, shape: str) -> None:
    p = gen.make_plant(seed, shape)
    assert shape == "first" or p.delay > 0.0  # the resonant case carries a delay
    y = gen.run(p, gen.Effect(), total=TOTAL)[0]
    recs = _library(p)
    steady = slice(gen.SETTLE * gen.P, None)
    y_lib = np.stack([np.asarray(r.y) for r in recs])
    # The same latent x (exact here, the library's RK4 with its delay line there) ...
    x_gen = np.stack([gen.latent(p, np.asarray(r.t), i)[0] for i, r in enumerate(recs)])
    x_lib = np.stack([np.asarray(r.x) for r in recs])
    assert np.max(np.abs(x_gen[:, steady] - x_lib[:, steady])) < 1e-3 * np.max(np.abs(x_lib))
    # ... and the same steady loop: saturated near 1, equal to well below the averaged noise sd.
    assert 0.9 < np.max(np.abs(y_lib)) <= 1.0 + 1e-9
    assert np.max(np.abs(y[:, steady] - y_lib[:, steady])) < TOL


def test_a_linear_effect_is_sized_in_averaged_noise_sd() -> None:
    # A dashpot across the hysteretic element adds c xdot: its size is c RMS(xdot) over the averaged
    # periods, in averaged noise sd, computed here from the exact latent x instead of two simulations.
    p = gen.make_plant(2, "resonant")
    value, got = gen.calibrate(p, "viscous", "x", 10.0)
    n = (gen.SETTLE + gen.PERIODS) * gen.P
    xdot = []
    for i, om in enumerate(p.omegas):
        t = np.arange(n) * (2 * np.pi / om / gen.P)
        xdot.append(gen.latent(p, t, i)[1][gen.SETTLE * gen.P :])
    size = value * np.sqrt(np.mean(np.square(xdot))) / (gen.NOISE_SD / np.sqrt(gen.PERIODS))
    assert got == 10.0 and value > 0.0 and abs(size - 10.0) < 1e-6


@pytest.mark.parametrize(
    "name, term",
    [
        ("viscous", bw.terms.Viscous(0.01)),
        ("coulomb", bw.terms.Coulomb(0.05)),
        ("asymmetry", bw.terms.Asymmetry(0.3)),
        ("play", bw.terms.Play(0.1)),
        ("sensor_lag", bw.terms.SensorLag(0.003)),
        ("series_dashpot", bw.terms.SeriesDashpot(3.0)),
    ],
)
def test_generator_and_library_agree_on_the_library_terms(name: str, term: Any) -> None:
    # The generator's own integration of each library term (on u) gives the library's steady loop: the
    # conventions (sign, smoothing, play from rest, the lag) are the same, the integrators are not.
    p = gen.make_plant(1, "resonant")
    value = float(getattr(term, term.symbol))
    y = gen.run(p, gen.Effect(name, "u", np.array([value])), total=TOTAL)[0]
    y_lib = np.stack([np.asarray(r.y) for r in _library(p, (term,))])
    plain = np.stack([np.asarray(r.y) for r in _library(p)])
    steady = slice(gen.SETTLE * gen.P, None)
    effect = np.max(np.abs(y[:, steady] - plain[:, steady]))
    assert effect > 1e-2  # the term is visible ...
    assert np.max(np.abs(y[:, steady] - y_lib[:, steady])) < TOL  # ... and the same in both
