"""Dahl friction in the exporters: the C99 function and both python-control systems carry its force as one
more state per place (``fu`` on u, ``fx`` on x), ``F' = sigma v' (1 - sgn(v') F / Fc)`` stepped as the
simulator steps it (``rust/simulate/with_terms/dahl.rs``: on u with the undelayed input's rate at the RK4
stage times, on x with x's rate at the stage states; ``F`` adds to the output before the sensor lag).

Held to the library's ``simulate_input`` (the Rust core) on seeded random plants: random G of order 0-4 with
or without delay, Dahl friction on u, on x or on both, with random other terms (play and sensor lag among
them), a smooth random input. The C is compiled by the machine's compiler, the discrete nlsys is run by
python-control's own ``input_output_response``; both transcribe the simulator's scheme operation for
operation, so they are held to 1e-9 of each signal's largest magnitude (the rounding of a few hundred steps
is ~1e-13; a one-step scheme difference, e.g. ``F`` stepped with the played rate or from the delayed input,
is ~1e-3 here: the tests below show both). python-control's adaptive solver on the continuous system is an
independent integrator, held to a fine simulation at its own tolerance.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.export import EXPORTED, SampledInput, discrete_response, input_signals, rk4_response

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_export import SIMULATED, compile_c, random_linear, rel, run_c, step  # noqa: E402

#: Largest ``sigma |v'| h / Fc`` drawn: the Dahl force relaxes at the rate ``sigma |v'| / Fc`` after a
#: reversal and classical RK4 is stable below ~2.8 times the step (docs/dahl-time-domain.md); the draw keeps
#: well inside, where the simulator is accurate, so no case compares two blow-ups.
STIFFNESS_PER_STEP = 0.5

#: Other terms drawn beside the friction (any term the simulator simulates).
OTHERS = list(SIMULATED)


def smooth_input(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Two sines and a low-passed random walk: the reversals a Dahl loop needs, at a bounded rate."""
    dt = float(rng.uniform(0.004, 0.01))
    t = np.arange(n) * dt
    walk = np.convolve(np.cumsum(rng.standard_normal(n)) * 0.05, np.ones(15) / 15.0, mode="same")
    u = rng.uniform(0.5, 1.5) * np.sin(rng.uniform(2, 8) * t) + 0.3 * np.sin(rng.uniform(8, 15) * t) + walk
    return t, u


def peak_xrate(plant: bw.WienerPlant, t: np.ndarray, u: np.ndarray, substeps: int) -> float:
    """The peak ``|xdot|`` of the run, from the x the simulator gives (differences, with margin)."""
    x = bw.simulate_input(plant, t, u, substeps=substeps, output=True)[0]
    return 2.0 * float(np.max(np.abs(np.diff(x)))) / step(t)


def dahl_plant(rng: np.random.Generator, places: str, t: np.ndarray, u: np.ndarray, substeps: int) -> Any:
    """A random G and Bouc-Wen, 0-3 other terms, Dahl friction at ``places`` ("u", "x" or "ux") with
    ``sigma`` from the drawn ``sigma |v'|_max h / Fc``; returns ``(plant, plain)`` (``plain`` without the
    friction)."""
    beta = rng.uniform(0.4, 1.5)
    h = bw.BoucWen(beta, rng.uniform(-0.3, 1.0) * beta, rng.uniform(1.2, 2.5), alpha=rng.uniform(0.5, 2))
    others = tuple(OTHERS[i] for i in rng.permutation(len(OTHERS))[: int(rng.integers(0, 4))])
    extra = tuple(cls(SIMULATED[cls](rng)) for cls in others)  # type: ignore[no-untyped-call]
    plain = bw.WienerPlant(random_linear(rng), h, extra)
    step_h = step(t) / substeps
    speeds = {"u": SampledInput(t, u).peak_rate(), "x": peak_xrate(plain, t, u, substeps)}
    friction: list[T.Term] = []
    for place in places:
        where = T.Place.INPUT if place == "u" else T.Place.X
        fc = float(rng.uniform(0.05, 0.5))
        sigma = float(rng.uniform(0.05, 1.0)) * STIFFNESS_PER_STEP * fc / (step_h * max(speeds[place], 1e-9))
        friction += [T.Dahl.at(where)(fc), T.DahlSigma.at(where)(sigma)]  # type: ignore[call-arg]
    return bw.WienerPlant(plain.linear, h, plain.terms + tuple(friction)), plain


def test_every_dahl_term_is_exported_with_its_state() -> None:
    """Dahl's four classes are in the exporters' set; each active place adds one state, named; a level or
    stiffness of 0 is no friction and adds none (as in the simulator)."""
    assert {T.Dahl, T.DahlSigma, T.DahlX, T.DahlSigmaX} <= set(EXPORTED)
    g = bw.TransferFunction([1.0], [0.1, 1.0], 0.01)
    h = bw.BoucWen(1.0, 0.5, 1.5)
    both = bw.WienerPlant(g, h, (T.Dahl(0.2), T.DahlSigma(3.0), T.DahlX(0.1), T.DahlSigmaX(2.0), T.Play(0.1)))
    assert list(bw.to_nlsys(both).state_labels) == ["xs0", "w", "xp", "fu", "fx"]
    assert list(bw.to_nlsys(both, dt=0.01).state_labels) == ["xs0", "w", "xp", "fu", "fx"]
    half = bw.WienerPlant(g, h, (T.Dahl(0.2), T.DahlX(0.1), T.DahlSigmaX(2.0)))  # no sigma on u: no force
    assert list(bw.to_nlsys(half).state_labels) == ["xs0", "w", "fx"]
    src = bw.to_c(both, name="dahl_model")
    assert "static const double dahl_model_sigmax = 2.0;" in src and "malloc" not in src


@pytest.mark.parametrize(("seed", "places"), [(s, p) for s in range(3) for p in ("u", "x", "ux")])
def test_c_and_nlsys_match_simulate_with_dahl_friction(seed: int, places: str, tmp_path: Path) -> None:
    """C, the discrete nlsys (python-control's own run) and the continuous nlsys under the simulator's RK4
    (no play, no lag: there it is the simulator's ODE) at 1e-9 of x, w, y; and the friction shows in y far
    above that."""
    rng = np.random.default_rng([31, seed, len(places), ord(places[0])])
    substeps = int(rng.integers(1, 5))
    t, u = smooth_input(rng, 300)
    plant, plain = dahl_plant(rng, places, t, u, substeps)
    ref = bw.simulate_input(plant, t, u, substeps=substeps, output=True)
    bare = bw.simulate_input(plain, t, u, substeps=substeps, output=True)
    assert np.all(np.isfinite(ref[2])) and rel(bare[2], ref[2]) > 1e-3, rel(bare[2], ref[2])
    name = f"dahl_{seed}_{places}"
    rc, *c_out = run_c(compile_c(bw.to_c(plant, name=name), name, tmp_path), u, step(t), substeps)
    assert rc == 0
    sysd = bw.to_nlsys(plant, vmax=1.0, vx=1.0, dt=step(t), substeps=substeps)
    outs = {"C": c_out, "discrete nlsys": discrete_response(sysd, t, u, plant=plant)}
    if not any(isinstance(term, (T.Play, T.SensorLag)) for term in plant.terms):
        sysc = bw.to_nlsys(plant, vmax=1.0, vx=1.0)
        outs["continuous nlsys"] = rk4_response(sysc, t, u, substeps=substeps, plant=plant)
    for label, got in outs.items():
        for g, want, sig in zip(got, ref, "xwy"):
            assert rel(np.asarray(g), want) <= 1e-9, (label, sig, plant.terms, rel(np.asarray(g), want))


def test_the_comparison_sees_a_scheme_or_parameter_change(tmp_path: Path) -> None:
    """What 1e-9 rules out: the C at another step (2 substeps against the simulator's 3: an RK4 step
    difference) and a 1e-6 relative change of either ``sigma`` are both far above it."""
    rng = np.random.default_rng(77)
    t, u = smooth_input(rng, 300)
    g = bw.TransferFunction([2.0, 5.0], [1.0, 1.2, 9.0], 0.013)
    h = bw.BoucWen(1.0, 0.4, 1.6, alpha=1.3)

    def plant(su: float, sx: float) -> bw.WienerPlant:
        return bw.WienerPlant(g, h, (T.Dahl(0.3), T.DahlSigma(su), T.DahlX(0.2), T.DahlSigmaX(sx)))

    ref = bw.simulate_input(plant(4.0, 3.0), t, u, substeps=3, output=True)[2]
    fn = compile_c(bw.to_c(plant(4.0, 3.0), name="power"), "power", tmp_path)
    assert rel(run_c(fn, u, step(t), 3)[3], ref) <= 1e-9
    assert rel(run_c(fn, u, step(t), 2)[3], ref) > 1e-7
    for su, sx in ((4.0 * (1 + 1e-6), 3.0), (4.0, 3.0 * (1 + 1e-6))):
        assert rel(bw.simulate_input(plant(su, sx), t, u, substeps=3, output=True)[2], ref) > 1e-8


def test_python_controls_own_solver_on_the_continuous_system() -> None:
    """An independent integrator: python-control's ``input_output_response`` (SciPy's adaptive solver,
    rtol 1e-9) on the continuous system with Dahl friction on u and on x, a delayed resonant G, against the
    simulator at a fine step (h = dt / 32). python-control interpolates the input rows linearly between the
    times it is given, and the force on u integrates ``udot``: given at the samples only, y is off by 1.5e-4
    of its peak (measured); given at 8 points per sample, by 2.4e-6, the second order of that interpolation
    (without Dahl friction: 6.7e-6 and 1.5e-7)."""
    control = pytest.importorskip("control")
    g = bw.TransferFunction([0.5, 2.0], [1.0, 0.8, 4.0], 0.02)
    plant = bw.WienerPlant(
        g,
        bw.BoucWen(1.0, 0.5, 1.6, alpha=1.2),
        (T.Dahl(0.2), T.DahlSigma(3.0), T.DahlX(0.15), T.DahlSigmaX(2.5), T.Viscous(0.05)),
    )
    dt = 0.002
    t = np.arange(1500) * dt
    u = np.sin(4.0 * t) + 0.3 * np.sin(11.0 * t)
    sys_c = bw.to_nlsys(plant)
    assert list(sys_c.state_labels) == ["xs0", "xs1", "w", "fu", "fx"]
    ref = bw.simulate_input(plant, t, u, substeps=32, output=True)
    errs = []
    for fine in (1, 8):
        tf = np.arange((t.size - 1) * fine + 1) * (dt / fine)
        resp = control.input_output_response(
            sys_c,
            tf,
            input_signals(sys_c, t, u, tf),
            X0=np.zeros(sys_c.nstates),
            t_eval=t,
            solve_ivp_kwargs={"rtol": 1e-9, "atol": 1e-11, "max_step": dt},
        )
        errs.append([rel(np.asarray(a), b) for a, b in zip(resp.outputs, (ref[2], ref[0], ref[1]))])
    assert max(errs[1]) < 1e-5 and errs[0][0] > 16.0 * errs[1][0], errs
    bare = bw.WienerPlant(g, plant.hysteresis, plant.terms[4:])
    assert rel(bw.simulate_input(bare, t, u, substeps=32, output=True)[2], ref[2]) > 1e-2


@pytest.mark.parametrize("extra", ["lag", "play", "lag+play"])
def test_dahl_beside_the_lag_and_the_play(extra: str, tmp_path: Path) -> None:
    """The lag takes ``F`` into its input at the step's start, middle (the force's continuous extension) and
    end; the play's frozen mode does not touch the force on x (it moves with x's rate, not the played one):
    C and the discrete nlsys at 1e-9, and the lag's and play's own effect on y far above it."""
    rng = np.random.default_rng([5, len(extra)])
    t, u = smooth_input(rng, 300)
    g = bw.TransferFunction([2.0, 5.0], [1.0, 1.2, 9.0], 0.013)
    h = bw.BoucWen(1.0, 0.4, 1.6, alpha=1.3)
    others = {"lag": (T.SensorLag(0.03),), "play": (T.Play(0.08),)}
    more = tuple(term for key in extra.split("+") for term in others[key])
    friction = (T.Dahl(0.3), T.DahlSigma(4.0), T.DahlX(0.2), T.DahlSigmaX(3.0))
    plant = bw.WienerPlant(g, h, friction + more)
    ref = bw.simulate_input(plant, t, u, substeps=2, output=True)
    no_extra = bw.simulate_input(bw.WienerPlant(g, h, friction), t, u, substeps=2, output=True)
    assert rel(no_extra[2], ref[2]) > 1e-3
    name = f"beside_{extra.replace('+', '_')}"
    rc, *c_out = run_c(compile_c(bw.to_c(plant, name=name), name, tmp_path), u, step(t), 2)
    d_out = discrete_response(bw.to_nlsys(plant, dt=step(t), substeps=2), t, u)
    assert rc == 0
    for label, got in (("C", c_out), ("discrete nlsys", d_out)):
        for g_, want, sig in zip(got, ref, "xwy"):
            assert rel(np.asarray(g_), want) <= 1e-9, (label, sig, rel(np.asarray(g_), want))
