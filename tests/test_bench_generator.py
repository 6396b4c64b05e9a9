"""The diagnosis bench's own generator (benches/generator.py) against the library's simulator.

The bench's verdicts are measured on recordings made another way than the library (exact G, its own RK4 of
the hysteresis); on a plain Wiener-Bouc-Wen plant, with no effect hidden, both must give the same steady
loop to integration accuracy, through G shapes that differ (a resonant G with a delay, a first-order G).
"""

from __future__ import annotations

import importlib
import json
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
    if name == "coulomb":  # the plant's own drawn smoothing width, carried by the library's term
        term = bw.terms.Coulomb(term.f, smoothing=gen.coulomb_width(p.seed))
    value = float(getattr(term, term.symbol))
    y = gen.run(p, gen.Effect(name, "u", np.array([value])), total=TOTAL)[0]
    y_lib = np.stack([np.asarray(r.y) for r in _library(p, (term,))])
    plain = np.stack([np.asarray(r.y) for r in _library(p)])
    steady = slice(gen.SETTLE * gen.P, None)
    effect = np.max(np.abs(y[:, steady] - plain[:, steady]))
    assert effect > 1e-2  # the term is visible ...
    assert np.max(np.abs(y[:, steady] - y_lib[:, steady])) < TOL  # ... and the same in both


def test_the_coulomb_width_is_drawn_per_seed_over_its_range() -> None:
    # The bench must not meet only the library's default 1 % width: widths spread log-uniformly over the
    # range, the same for a seed every time, and both sides of 1 % occur.
    widths = np.array([gen.coulomb_width(seed) for seed in range(200)])
    lo, hi = gen.COULOMB_EPS_RANGE
    assert np.all((widths >= lo) & (widths <= hi))
    assert gen.coulomb_width(7) == gen.coulomb_width(7)
    below = np.mean(widths < bw.terms.Coulomb(1.0).smoothing)
    expected = np.log(0.01 / lo) / np.log(hi / lo)
    assert abs(below - expected) < 0.12  # binomial sd at n = 200 is < 0.036
    assert np.ptp(np.log(widths)) > 0.8 * np.log(hi / lo)


#: Every effect the generator hides (the feedback structure has its own integrator, tested apart).
EFFECTS = [
    *[(name, place) for name in gen.MECHANICAL for place in gen.PLACES],
    *[(name, "") for name in (*gen.LIBRARY_OTHER, *gen.BABER_NOORI, *gen.OUTSIDE, *gen.IWAN, *gen.FAMILY)],
]
SHORT = (2 + 1) * gen.P  # a short record: the loops' arithmetic, not the steady loop, is compared here


@pytest.fixture
def numpy_loops() -> Any:
    """The generator's NumPy loops (the definition), whatever the environment; restored afterwards."""
    was = gen._jit is not None
    gen.use_numba(False)
    yield gen
    gen.use_numba(was)


def test_runs_of_one_plant_share_its_plain_hysteresis_bit_for_bit(numpy_loops: Any) -> None:
    # make_case reuses calibrate's plain hysteresis for the effects outside it (added to, or filtering, w):
    # the same bits as a run from scratch, for every effect, on the NumPy loops.
    p = gen.make_plant(3, "resonant", low_amplitude=True)
    shared = gen.base(p, SHORT)
    plain = gen.run(p, gen.Effect(), shared=shared)
    assert shared.wf is not None and np.array_equal(plain, gen.run(p, gen.Effect(), total=SHORT))
    for name, place in EFFECTS:
        eff = gen.Effect(name, place, np.array([0.02, 0.05]))
        y = gen.run(p, eff, shared=shared)
        assert np.array_equal(y, gen.run(p, eff, total=SHORT)), name
        assert np.max(np.abs(y - plain)) > 1e-4, name  # the effect is there


def test_make_case_returns_the_calibrated_run() -> None:
    # The recordings' noise-free part is the run at the calibrated value (reused from calibrate's last
    # contribution, not re-run): noisy y minus it is the seeded noise, with the noise sd asked.
    case = gen.make_case("library", "asymmetry", "", 10.0, 106)
    p = gen.make_plant(106)
    y = gen.run(p, gen.Effect("asymmetry", "", np.array([case.value])))[0]
    noise = np.stack([np.asarray(r.y) for r in case.recordings]) - y
    rng = np.random.default_rng([106, 7])
    expected = np.stack([rng.normal(0.0, gen.NOISE_SD, y.shape[1]) for _ in range(y.shape[0])])
    assert np.allclose(noise, expected, rtol=0.0, atol=1e-12)
    assert abs(case.achieved - 10.0) < 0.1


def _compiled() -> Any:
    if not gen.use_numba(True):
        pytest.skip("numba is not installed (the bench extra): the compiled loops cannot be compared")
    return gen


@pytest.mark.parametrize("name, place", EFFECTS)
def test_compiled_loops_agree_with_the_numpy_loops(name: str, place: str) -> None:
    # The compiled loops are the NumPy loops element by element, the same arithmetic in the same order:
    # equal to 1e-12 relative (only the libm's pow/exp/tanh may differ by an ulp).
    was = gen._jit is not None
    try:
        g = _compiled()
        p = gen.make_plant(5, "first" if name in ("play", "dahl") else "resonant", low_amplitude=True)
        eff = gen.Effect(name, place, np.array([0.01, 0.04]) * (10.0 if name == "pinching" else 1.0))
        fast = g.run(p, eff, total=SHORT)
        g.use_numba(False)
        ref = g.run(p, eff, total=SHORT)
        assert np.max(np.abs(fast - ref)) <= 1e-12 * np.max(np.abs(ref))
    finally:
        gen.use_numba(was)


def test_compiled_feedback_agrees_with_the_numpy_feedback() -> None:
    was = gen._jit is not None
    try:
        g = _compiled()
        p = gen.make_plant(6, "resonant")
        fast, amp = g.feedback_outputs(p, total=SHORT)
        g.use_numba(False)
        ref, amp_ref = g.feedback_outputs(p, total=SHORT)
        assert np.array_equal(amp, amp_ref) and np.max(np.abs(ref)) > 0.5
        assert np.max(np.abs(fast - ref)) <= 1e-12 * np.max(np.abs(ref))
    finally:
        gen.use_numba(was)


def test_a_cached_case_is_the_case_made(tmp_path: Path) -> None:
    # benches/diagnosis.py --cache DIR: the first call makes and stores the case, the second reads it back
    # (the same arrays, values and metadata); a damaged entry is made again; a new version is a new key.
    made = gen.cached_case("null", None, "", 0.0, 116, tmp_path)
    assert len(list(tmp_path.glob("*.npz"))) == 1 and len(list(tmp_path.glob("*.json"))) == 1
    read = gen.cached_case("null", None, "", 0.0, 116, tmp_path)
    assert (read.kind, read.name, read.seed, read.shape, read.value) == (
        made.kind,
        made.name,
        made.seed,
        made.shape,
        made.value,
    )
    for a, b in zip(made.recordings, read.recordings):
        assert all(np.array_equal(getattr(a, k), getattr(b, k)) for k in ("t", "u", "y"))
        assert (a.amplitude, a.frequency, a.settle_periods, dict(a.metadata)) == (
            b.amplitude,
            b.frequency,
            b.settle_periods,
            dict(b.metadata),
        )
    (meta,) = tmp_path.glob("*.json")
    meta.write_text("{not json")
    again = gen.cached_case("null", None, "", 0.0, 116, tmp_path)
    assert np.array_equal(again.recordings[0].y, made.recordings[0].y)
    assert json.loads(meta.read_text())["key"].endswith(gen.version() + '"]')
    gen.cached_case("null", None, "", 0.0, 117, tmp_path)
    assert len(list(tmp_path.glob("*.npz"))) == 2


def test_the_library_rows_dahl_loop_is_the_librarys_law() -> None:
    # The library row "dahl" is generated by the library's law (exponent 1), integrated its own way (exact
    # along each sample step): its steady loop under a sine is the library's closed form (reference/dahl.py)
    # to the sampling of the reversals; Dahl's exponent 2 ("dahl_n2", an outside row) is not.
    from bouc_wen_id.reference.dahl import dahl_loop

    p, amp, sigma = 1024, 1.3, 2.5
    x = amp * np.cos(2.0 * np.pi * np.arange(4 * p) / p)[None, :]
    ref = dahl_loop(amp, 0.0, 1.0, sigma, p)[0]
    one = gen._dahl_loop(x, sigma, 1.0)[0, -p:]
    two = gen._dahl_loop(x, sigma, 2.0)[0, -p:]
    assert np.max(np.abs(one - ref)) < 2e-3
    assert np.max(np.abs(two - ref)) > 0.05
