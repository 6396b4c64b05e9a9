"""Issue #21 item 2: the whole model exported as a python-control nlsys, as C99 and as JSON.

The C source and the nlsys are held to the library's simulator (``simulate_input``, the Rust core) on
random plants with random terms and random inputs: a second, independently written integrator each (the C
is compiled by the machine's compiler, the nlsys is a Python right-hand side under a Python RK4).
"""

from __future__ import annotations

import ctypes
import json
import shutil
import subprocess
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.errors import FileFormatError, InvalidParameterError, NonFiniteError, UnstableSystemError
from bouc_wen_id.export import (
    EXPORTED,
    SampledInput,
    UnsupportedTermError,
    discrete_response,
    input_signals,
    peak_speeds,
    rk4_response,
    stage_inputs,
)

#: Terms the simulator simulates, with a value drawn from a generator (each admissible for any plant below).
SIMULATED = {
    T.Offset: lambda r: r.uniform(-1, 1),
    T.Stiffness: lambda r: r.uniform(-1, 1),
    T.Viscous: lambda r: r.uniform(0, 0.3),
    T.Inertia: lambda r: r.uniform(0, 0.02),
    T.Coulomb: lambda r: r.uniform(0, 0.5),
    T.SensorLag: lambda r: r.uniform(0.01, 0.2),
    T.Asymmetry: lambda r: r.uniform(-0.1, 0.1),
    T.Play: lambda r: r.uniform(0.01, 0.1),
    T.Degradation: lambda r: r.uniform(0, 0.1),
    T.StiffnessDegradation: lambda r: r.uniform(0, 0.1),
    T.Pinching: lambda r: r.uniform(0, 0.6),
    T.StiffnessX: lambda r: r.uniform(-1, 1),
    T.ViscousX: lambda r: r.uniform(0, 0.3),
    T.InertiaX: lambda r: r.uniform(0, 0.02),
    T.CoulombX: lambda r: r.uniform(0, 0.5),
    # rho (1/s) against the input's 2-20 rad/s: the element creeps at rho w_u, a visible share of x's rate.
    T.SeriesDashpot: lambda r: r.uniform(0.5, 5.0),
}


def random_linear(rng: np.random.Generator) -> bw.TransferFunction:
    """A stable G of order 0-4 (real and complex poles), proper or strictly proper, with or without delay."""
    order = int(rng.integers(0, 5))
    den = np.array([1.0])
    while den.size - 1 < order:
        if order - (den.size - 1) >= 2 and rng.random() < 0.5:
            wn, z = rng.uniform(1, 8), rng.uniform(0.1, 0.9)
            den = np.polymul(den, [1.0, 2 * z * wn, wn * wn])
        else:
            den = np.polymul(den, [1.0, rng.uniform(0.5, 10)])
    den = den * rng.uniform(0.5, 2)
    ndeg = int(rng.integers(0, order + 1))
    num = rng.uniform(0.5, 2, ndeg + 1) * rng.choice([-1, 1], ndeg + 1)
    num[0] = abs(num[0])
    # Peak gain between 0.5 and 2 over the band (a DC normalisation can leave a huge high-frequency gain).
    peak = np.max(
        np.abs(np.polyval(num, 1j * np.logspace(-2, 3, 400)) / np.polyval(den, 1j * np.logspace(-2, 3, 400)))
    )
    num = num * rng.uniform(0.5, 2) / peak
    delay = float(rng.choice([0.0, rng.uniform(0.001, 0.05)]))
    return bw.TransferFunction(num, den, delay)


def random_plant(rng: np.random.Generator, kinds: Any = SIMULATED) -> bw.WienerPlant:
    beta = rng.uniform(0.3, 1.5)
    gamma = rng.uniform(-0.5, 1.0) * beta
    h = bw.BoucWen(beta, gamma, rng.uniform(1.2, 2.5), alpha=rng.uniform(0.5, 2), w0=rng.uniform(-0.1, 0.1))
    pool = list(kinds)
    chosen = [pool[i] for i in rng.permutation(len(pool))[: int(rng.integers(0, len(pool) + 1))]]
    terms = []
    for cls in chosen:
        value = kinds[cls](rng) if isinstance(kinds, dict) else rng.uniform(0, 0.1)
        terms.append(T.Coulomb(value, smoothing=rng.uniform(0.005, 0.2)) if cls is T.Coulomb else cls(value))
    return bw.WienerPlant(random_linear(rng), h, tuple(terms))


def step(t: np.ndarray) -> float:
    """The step ``simulate_input`` takes (the mean difference). The C function must get the same double: the
    Catmull-Rom second derivative jumps at the knots, so one ulp of dt decides which side the inertia term
    sees at a sample."""
    return float(np.mean(np.diff(t)))


def random_input(rng: np.random.Generator, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    dt = float(rng.uniform(0.002, 0.01))
    t = np.arange(n) * dt
    u = np.cumsum(rng.standard_normal(n)) * 0.1 + rng.uniform(0.5, 2) * np.sin(rng.uniform(2, 20) * t)
    return t, u


def rel(a: np.ndarray, b: np.ndarray) -> float:
    """Largest difference relative to the reference signal's largest magnitude."""
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


# --------------------------------------------------------------------------------------------------- C99


def _compiler() -> str:
    for cc in ("cc", "gcc", "clang"):
        if shutil.which(cc):
            return cc
    pytest.skip("no C compiler (cc, gcc, clang) on this machine: the generated C cannot be compiled")


def compile_c(source: str, name: str, tmp: Path) -> Any:
    """``source`` compiled with ``-std=c99 -Wall -Wextra -Werror -pedantic -O2`` into a shared library."""
    c, so = tmp / f"{name}.c", tmp / f"{name}.so"
    c.write_text(source, encoding="utf-8")
    cmd = [_compiler(), "-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic", "-O2", "-shared", "-fPIC"]
    done = subprocess.run([*cmd, str(c), "-o", str(so), "-lm"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    fn = getattr(ctypes.CDLL(str(so)), name)
    p = ctypes.POINTER(ctypes.c_double)
    fn.argtypes = [p, ctypes.c_long, ctypes.c_double, ctypes.c_int, p, p, p]
    fn.restype = ctypes.c_int
    return fn


def run_c(fn: Any, u: np.ndarray, dt: float, substeps: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    p = ctypes.POINTER(ctypes.c_double)
    uu = np.ascontiguousarray(u, dtype=np.float64)
    x, w, y = (np.full(uu.size, np.nan) for _ in range(3))
    rc = fn(uu.ctypes.data_as(p), uu.size, dt, substeps, *(a.ctypes.data_as(p) for a in (x, w, y)))
    return int(rc), x, w, y


@pytest.mark.parametrize("seed", range(12))
def test_c_source_compiles_and_matches_the_simulator(seed: int, tmp_path: Path) -> None:
    rng = np.random.default_rng(seed)
    plant = random_plant(rng)
    t, u = random_input(rng)
    substeps = int(rng.integers(1, 5))
    fn = compile_c(bw.to_c(plant, name=f"plant_{seed}"), f"plant_{seed}", tmp_path)
    rc, x, w, y = run_c(fn, u, step(t), substeps)
    assert rc == 0
    xr, wr, yr = bw.simulate_input(plant, t, u, substeps=substeps, output=True)
    for got, want in ((x, xr), (w, wr), (y, yr)):
        assert rel(got, want) <= 1e-9, (plant.terms, rel(got, want))


def test_c_source_every_term_at_once_and_a_changed_model_differs(tmp_path: Path) -> None:
    """All the simulated terms together (play, lag and degradation interacting), and the comparison's power:
    a 1e-6 change of beta is seen far above the tolerance."""
    rng = np.random.default_rng(99)
    h = bw.BoucWen(1.0, 0.4, 1.6, alpha=1.4, w0=0.05)
    g = bw.TransferFunction([2.0, 5.0], [1.0, 1.2, 9.0], 0.013)
    terms = tuple(cls(f(rng)) for cls, f in SIMULATED.items())  # type: ignore[no-untyped-call]
    plant = bw.WienerPlant(g, h, terms)
    t, u = random_input(rng, 800)
    dt = step(t)
    fn = compile_c(bw.to_c(plant, name="full"), "full", tmp_path)
    rc, x, w, y = run_c(fn, u, dt, 3)
    xr, wr, yr = bw.simulate_input(plant, t, u, substeps=3, output=True)
    assert rc == 0 and rel(x, xr) <= 1e-9 and rel(w, wr) <= 1e-9 and rel(y, yr) <= 1e-9
    bumped = bw.WienerPlant(g, bw.BoucWen(1.0 + 1e-6, 0.4, 1.6, alpha=1.4, w0=0.05), terms)
    _, wb, _ = bw.simulate_input(bumped, t, u, substeps=3, output=True)
    assert rel(w, wb) > 1e-8


def test_c_function_refuses_bad_arguments_and_reports_a_blow_up(tmp_path: Path) -> None:
    plant = bw.WienerPlant(bw.TransferFunction([1.0], [0.1, 1.0]), bw.BoucWen(1.0, 0.5, 1.5))
    fn = compile_c(bw.to_c(plant, name="guarded"), "guarded", tmp_path)
    u = np.sin(np.linspace(0, 3, 50))
    assert run_c(fn, u[:1], 0.01, 2)[0] == -1
    assert run_c(fn, u, 0.0, 2)[0] == -1
    assert run_c(fn, u, float("nan"), 2)[0] == -1
    assert run_c(fn, u, 0.01, 0)[0] == -1
    bad = u.copy()
    bad[7] = np.inf
    assert run_c(fn, bad, 0.01, 2)[0] == -2
    huge = bw.WienerPlant(bw.TransferFunction([1.0], [0.1, 1.0]), bw.BoucWen(1e300, 0.5, 1.5))
    boom = compile_c(bw.to_c(huge, name="boom"), "boom", tmp_path)
    assert run_c(boom, u * 1e10, 0.01, 2)[0] == 1


def test_c_source_names_and_refusals() -> None:
    plant = bw.WienerPlant(bw.TransferFunction([1.0], [1.0, 1.0]), bw.BoucWen(1.0, 0.5, 1.5))
    src = bw.to_c(plant, name="my_model")
    assert "int my_model(const double *u, long n, double dt, int substeps" in src
    assert "malloc" not in src and "static double my_model_rate" in src
    for bad in ("1abc", "a-b", "", "x" * 64):
        with pytest.raises(InvalidParameterError, match="C identifier"):
            bw.to_c(plant, name=bad)
    distorted = bw.WienerPlant(plant.linear, plant.hysteresis, (T.Distortion(1.0),))
    with pytest.raises(InvalidParameterError, match="to_c: .*distortion"):
        bw.to_c(distorted)


# --------------------------------------------------------------------------------------- python-control

STATELESS_RK4 = {cls: f for cls, f in SIMULATED.items() if cls not in (T.Play, T.SensorLag)}


@pytest.mark.parametrize("seed", range(8))
def test_nlsys_under_the_simulators_rk4_matches_simulate_input(seed: int) -> None:
    """Every term whose simulator scheme is an RK4 step of an ODE: agreement to 1e-9 on the same step."""
    rng = np.random.default_rng(100 + seed)
    plant = random_plant(rng, STATELESS_RK4)
    t, u = random_input(rng, 300)
    substeps = int(rng.integers(1, 5))
    sys = bw.to_nlsys(plant, vmax=1.0, vx=1.0)
    x, w, y = rk4_response(sys, t, u, substeps=substeps, plant=plant)
    xr, wr, yr = bw.simulate_input(plant, t, u, substeps=substeps, output=True)
    for got, want in ((x, xr), (w, wr), (y, yr)):
        assert rel(got, want) <= 1e-9, (plant.terms, rel(got, want))


def test_nlsys_lag_and_play_agree_to_the_integration_error() -> None:
    """The lag's ODE under RK4 against the simulator's exponential step: both fourth order, their difference
    falls at least 8x per halving of h. The play's ODE (its mode decided at every stage) against the
    simulator's frozen-mode-and-clamp scheme: RK4 across the play's switches is first order, so the
    difference falls about as h (measured 2.8e-2 at 1 substep, 9.5e-4 at 32) while the simulator's own
    error is far smaller (7e-5 at 1 substep against 256)."""
    rng = np.random.default_rng(7)
    g = bw.TransferFunction([1.0], [0.1, 1.0])
    h = bw.BoucWen(1.0, 0.5, 1.5)
    t, u = random_input(rng, 300)
    plant = bw.WienerPlant(g, h, (T.SensorLag(0.02),))
    sys = bw.to_nlsys(plant)
    errs = []
    for sub in (2, 4, 8):
        y = rk4_response(sys, t, u, substeps=sub)[2]
        errs.append(rel(y, bw.simulate_input(plant, t, u, substeps=sub, output=True)[2]))
    assert errs[0] / errs[1] >= 8.0 and errs[1] / errs[2] >= 8.0 and errs[-1] < 1e-8, errs
    t = np.arange(300) * 0.01
    u = 1.5 * np.sin(3 * t) + 0.5 * np.sin(7.3 * t)
    plant = bw.WienerPlant(g, h, (T.Play(0.1),))
    sys = bw.to_nlsys(plant)
    errs = []
    for sub in (1, 32):
        y = rk4_response(sys, t, u, substeps=sub)[2]
        errs.append(rel(y, bw.simulate_input(plant, t, u, substeps=sub, output=True)[2]))
    assert errs[0] / errs[1] >= 10.0 and errs[1] < 2e-3, errs


def test_nlsys_in_python_control_input_output_response() -> None:
    """control's own adaptive integrator on the exported system agrees with a fine simulation (delay and
    mechanical terms, so the five inputs are all used)."""
    control = pytest.importorskip("control")
    g = bw.TransferFunction([0.5, 2.0], [1.0, 0.8, 4.0], 0.02)
    plant = bw.WienerPlant(g, bw.BoucWen(1.0, 0.5, 1.6, alpha=1.2), (T.Stiffness(0.3), T.Viscous(0.05)))
    dt = 0.002
    t = np.arange(1500) * dt
    u = np.sin(4.0 * t) + 0.3 * np.sin(11.0 * t)
    sys = bw.to_nlsys(plant)
    assert list(sys.input_labels) == ["u", "udot", "uddot", "v", "vdot", "vddot"]
    assert list(sys.output_labels) == ["y", "x", "w"]
    signals = input_signals(sys, t, u, t)
    resp = control.input_output_response(
        sys,
        t,
        signals,
        X0=np.zeros(sys.nstates),
        solve_ivp_kwargs={"rtol": 1e-9, "atol": 1e-11, "max_step": dt},
    )
    yr = bw.simulate_input(plant, t, u, substeps=8, output=True)[2]
    assert rel(resp.outputs[0], yr) < 1e-4


def test_nlsys_refusals_and_parameters() -> None:
    g = bw.TransferFunction([1.0], [1.0, 1.0])
    h = bw.BoucWen(1.0, 0.5, 1.5)
    with pytest.raises(InvalidParameterError, match="vmax"):
        bw.to_nlsys(bw.WienerPlant(g, h, (T.Coulomb(0.1),)))
    with pytest.raises(InvalidParameterError, match="vmax"):
        bw.to_nlsys(bw.WienerPlant(g, h), vmax=-1.0)
    with pytest.raises(InvalidParameterError, match="vx"):
        bw.to_nlsys(bw.WienerPlant(g, h, (T.CoulombX(0.1),)))
    with pytest.raises(InvalidParameterError, match="WienerPlant"):
        bw.to_nlsys(g)  # type: ignore[arg-type]
    sys = bw.to_nlsys(bw.WienerPlant(g, h, (T.Degradation(0.1), T.Play(0.1), T.SensorLag(0.1))))
    assert list(sys.state_labels) == ["xs0", "w", "e", "xp", "ys"]
    assert list(sys.input_labels) == ["u", "udot", "uddot"]


def test_sampled_input_is_the_simulators_interpolant() -> None:
    """A ramp is exact, a quadratic exact in the interior, the peak slope bounds a dense scan."""
    t = np.arange(30) * 0.1
    src = SampledInput(t, 3.0 * t + 1.0)
    for tau in (0.0, 0.05, 1.234, 2.8):
        assert src.at(tau)[:2] == pytest.approx((3.0 * tau + 1.0, 3.0), rel=1e-13)
    assert src.at(5.0) == (src.u[-1], 0.0, 0.0) and src.at(-1.0) == (0.0, 0.0, 0.0)
    q = SampledInput(t, t * t)
    for tau in (0.3, 1.55, 2.05):
        assert q.at(tau) == pytest.approx((tau * tau, 2 * tau, 2.0), rel=1e-9)
    scan = max(abs(q.at(s)[1]) for s in np.linspace(0, 2.9, 20001))
    assert scan <= q.peak_rate() * (1 + 1e-12) and q.peak_rate() <= scan * (1 + 1e-6)


# ----------------------------------------------------------------------------------------------- JSON

ALL_TERMS = {cls: None for cls in T.TERMS.values()}


@pytest.mark.parametrize("seed", range(25))
def test_json_round_trip_is_exact(seed: int, tmp_path: Path) -> None:
    rng = np.random.default_rng(1000 + seed)
    plant = random_plant(rng, [c for c in ALL_TERMS if c is not T.Asymmetry])
    path = tmp_path / "model.json"
    bw.save_model(plant, path, metadata={"units": "N, mm"})
    back = bw.load_model(path)
    assert back.to_dict() == plant.to_dict()
    assert [type(t) for t in back.terms] == [type(t) for t in plant.terms]
    assert back.linear.num.tobytes() == plant.linear.num.tobytes()
    assert back.linear.den.tobytes() == plant.linear.den.tobytes()
    assert back.hysteresis == plant.hysteresis and back.terms == plant.terms
    assert bw.model_from_json(bw.model_to_json(plant)).to_dict() == plant.to_dict()


def _doc() -> dict[str, Any]:
    plant = bw.WienerPlant(
        bw.TransferFunction([1.0], [0.5, 1.0], 0.01), bw.BoucWen(1.0, 0.5, 1.5), (T.Play(0.1),)
    )
    doc: dict[str, Any] = json.loads(bw.model_to_json(plant))
    return doc


def _edit(path: tuple[Any, ...], value: Any, delete: bool = False) -> str:
    doc = _doc()
    node = doc
    for key in path[:-1]:
        node = node[key]
    if delete:
        del node[path[-1]]
    else:
        node[path[-1]] = value
    return json.dumps(doc)


@pytest.mark.parametrize(
    ("text", "match"),
    [
        (_edit(("version",), 2), "version 2 is not known"),
        (_edit(("version",), "1"), "version '1'"),
        (_edit(("version",), True), "version True"),
        (_edit(("format",), "bouc_wen_id.result"), "not a bouc_wen_id model"),
        (_edit(("plant", "hysteresis", "mu"), None, delete=True), r"hysteresis: missing field\(s\) \['mu'\]"),
        (_edit(("plant", "linear", "gain"), 2.0), r"linear: unknown field\(s\) \['gain'\]"),
        (_edit(("plant", "hysteresis", "beta"), "1.0"), "hysteresis.beta must be a number"),
        (_edit(("plant", "linear", "den"), []), "den must be a non-empty list"),
        (_edit(("plant", "terms", 0, "kind"), "spring"), "unknown term kind 'spring'"),
        (_edit(("plant", "terms", 0, "width"), 1.0), r"unknown field\(s\) \['width'\]"),
        (_edit(("plant", "terms", 0, "b"), None, delete=True), r"missing field\(s\) \['b'\]"),
        (_edit(("plant", "terms"), {}), "terms must be a list"),
        (_edit(("extra",), 1), r"unknown field\(s\) \['extra'\]"),
        ("{not json", "not a JSON document"),
        ("[1, 2]", "not a bouc_wen_id model"),
    ],
)
def test_json_bad_documents_are_file_format_errors(text: str, match: str) -> None:
    with pytest.raises(FileFormatError, match=match):
        bw.model_from_json(text)


def test_json_inadmissible_values_keep_their_own_errors(tmp_path: Path) -> None:
    with pytest.raises(UnstableSystemError):
        bw.model_from_json(_edit(("plant", "linear", "den"), [-0.5, 1.0]))
    with pytest.raises(InvalidParameterError, match="half-width"):
        bw.model_from_json(_edit(("plant", "terms", 0, "b"), -0.1))
    path = tmp_path / "v9.json"
    path.write_text(_edit(("version",), 9), encoding="utf-8")
    with pytest.raises(FileFormatError, match="v9.json: model schema version 9"):
        bw.load_model(path)
    with pytest.raises(FileFormatError, match="cannot read"):
        bw.load_model(tmp_path / "missing.json")


# ------------------------------------------------------------------------------------------------ CLI


def test_cli_export_writes_c_and_json(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from bouc_wen_id.cli import main

    plant = bw.WienerPlant(
        bw.TransferFunction([1.0], [0.2, 1.0], 0.01),
        bw.BoucWen(1.0, 0.5, 1.5),
        (T.Viscous(0.1), T.Play(0.05)),
    )
    spec = tmp_path / "plant.json"
    spec.write_text(json.dumps(plant.to_dict()), encoding="utf-8")
    doc = tmp_path / "model.json"
    assert main(["export", str(spec), "--to", "json", "--out", str(doc)]) == 0
    assert bw.load_model(doc).to_dict() == plant.to_dict()
    src = tmp_path / "model.c"
    assert main(["export", str(doc), "--to", "c", "--name", "damper", "--out", str(src)]) == 0
    assert src.read_text(encoding="utf-8") == bw.to_c(plant, name="damper")
    capsys.readouterr()
    assert main(["export", str(doc), "--to", "c", "--out", str(src)]) == 2
    assert "exists; pass --overwrite" in capsys.readouterr().err
    assert main(["export", str(doc), "--to", "c", "--out", str(src), "--overwrite"]) == 0
    assert "int bouc_wen_model(" in src.read_text(encoding="utf-8")
    assert main(["export", str(doc), "--to", "c", "--name", "9bad"]) == 2
    assert "C identifier" in capsys.readouterr().err
    (tmp_path / "bad.json").write_text('{"format": "bouc_wen_id.model", "version": 3}', encoding="utf-8")
    assert main(["export", str(tmp_path / "bad.json"), "--to", "json"]) == 2
    assert "FileFormatError" in capsys.readouterr().err
    assert main(["export", str(tmp_path / "none.json"), "--to", "json"]) == 2


# ------------------------------------------------------------------------------ the whole model (issue 21)
# Every term of the registry at every place, exported to C and to a python-control system, agrees with
# ``simulate_input`` (the Rust core) to 1e-9 relative on the same step. The registry is iterated
# (:data:`bouc_wen_id.terms.TERMS`), not a hand-kept list: a term added to it is either exported (and held to
# the simulator here) or refused by name. The discrete-time nlsys is run by python-control's own
# ``input_output_response``.


#: Every registry class the simulator simulates (the distortion stands for one experiment's harmonics).
REGISTRY_SIMULATED = [cls for cls in T.TERMS.values() if cls is not T.Distortion]


def value_for(cls: type[T.Term], rng: np.random.Generator) -> float:
    """An admissible, clearly non-zero value for any plant of :func:`plant_with`."""
    lo, _ = cls.bounds
    if cls is T.SeriesDashpot:  # in 1/s: 0.02-0.1 would be lost against the input's 2-20 rad/s
        return float(rng.uniform(0.5, 5.0))
    v = float(rng.uniform(0.02, 0.1))
    return v if lo >= 0.0 else v * float(rng.choice([-1.0, 1.0]))


def make(cls: type[T.Term], value: float, rng: np.random.Generator) -> T.Term:
    if issubclass(cls, T.Coulomb):
        return cls(value, smoothing=float(rng.uniform(0.01, 0.2)))
    return cls(value)  # type: ignore[call-arg]


def plant_with(cls: type[T.Term], rng: np.random.Generator, extra: int) -> bw.WienerPlant:
    """A random stable G (order 0-4, with or without delay), a random Bouc-Wen, the term ``cls`` and
    ``extra`` other random simulated terms."""
    beta = rng.uniform(0.4, 1.5)
    h = bw.BoucWen(beta, rng.uniform(-0.3, 1.0) * beta, rng.uniform(1.2, 2.5), alpha=rng.uniform(0.5, 2))
    others = [c for c in REGISTRY_SIMULATED if c is not cls and c in EXPORTED]  # extras the exporters write
    chosen = [cls] + [others[i] for i in rng.permutation(len(others))[:extra]]
    terms = tuple(make(c, value_for(c, rng), rng) for c in chosen)
    return bw.WienerPlant(random_linear(rng), h, terms)


#: The terms the simulator had when the exporters were written (issue 21), and Dahl friction's (its force a
#: state per place, tests/test_export_dahl.py): each must stay exported.
KNOWN = (
    "offset stiffness viscous inertia coulomb sensor_lag asymmetry play degradation stiffness_degradation "
    "pinching stiffness@x viscous@x inertia@x coulomb@x series_dashpot dahl dahl_sigma dahl@x dahl_sigma@x"
).split()


def test_every_simulated_term_of_the_registry_is_exported() -> None:
    """The exporters' set is derived from the registry: it holds only registry classes, every term the
    simulator had at every place, and not the distortion."""
    kinds = {c.kind for c in EXPORTED}
    assert set(KNOWN) <= kinds, set(KNOWN) - kinds
    assert all(T.TERMS[c.kind] is c for c in EXPORTED)
    assert T.Distortion not in EXPORTED


@pytest.mark.parametrize("cls", REGISTRY_SIMULATED, ids=lambda c: c.kind)
def test_each_term_at_its_place_c_and_discrete_nlsys_match_the_simulator(cls: Any, tmp_path: Path) -> None:
    """Alone and with random others, on random G and inputs: C and the discrete nlsys at 1e-9 of x, w, y."""
    if cls not in EXPORTED:  # a registry term added without an exporter: refused by name (not a KNOWN one)
        assert cls.kind not in KNOWN
        with pytest.raises(UnsupportedTermError, match=f"{cls.kind!r}.* has no exporter"):
            bw.to_c(
                bw.WienerPlant(
                    bw.TransferFunction([1.0], [0.1, 1.0]),
                    bw.BoucWen(1.0, 0.5, 1.5),
                    (make(cls, 0.05, np.random.default_rng(0)),),
                )
            )
        return
    seed = 1 + REGISTRY_SIMULATED.index(cls)
    for trial, extra in enumerate((0, 3)):
        rng = np.random.default_rng(100 * seed + trial)
        plant = plant_with(cls, rng, extra)
        t, u = random_input(rng, 250)
        dt, substeps = step(t), int(rng.integers(1, 4))
        ref = bw.simulate_input(plant, t, u, substeps=substeps, output=True)
        name = f"m{seed}_{trial}"
        rc, *c_out = run_c(compile_c(bw.to_c(plant, name=name), name, tmp_path), u, dt, substeps)
        assert rc == 0
        vmax, vx = peak_speeds(plant, t, u, substeps)
        sysd = bw.to_nlsys(plant, vmax=vmax, vx=vx, dt=dt, substeps=substeps)
        d_out = discrete_response(sysd, t, u, plant=plant)
        for label, got in (("C", c_out), ("nlsys", d_out)):
            for g, want, sig in zip(got, ref, "xwy"):
                assert rel(np.asarray(g), want) <= 1e-9, (label, sig, plant.terms, rel(np.asarray(g), want))


def test_the_comparison_has_power_for_the_terms_on_x() -> None:
    """Dropping a term on x, or scaling its friction's Vx, is seen far above the tolerance."""
    rng = np.random.default_rng(3)
    g = bw.TransferFunction([2.0, 5.0], [1.0, 1.2, 9.0], 0.013)
    plant = bw.WienerPlant(g, bw.BoucWen(1.0, 0.4, 1.6), (T.ViscousX(0.05), T.CoulombX(0.2)))
    t, u = random_input(rng, 300)
    yr = bw.simulate_input(plant, t, u, substeps=2, output=True)[2]
    sysd = bw.to_nlsys(plant, vmax=1.0, vx=1.0, dt=step(t), substeps=2)
    assert rel(discrete_response(sysd, t, u, plant=plant)[2], yr) <= 1e-9
    assert rel(discrete_response(sysd, t, u)[2], yr) > 1e-4  # vx = 1 instead of the run's peak |xdot|
    bare = bw.WienerPlant(g, plant.hysteresis, (T.CoulombX(0.2),))
    assert rel(bw.simulate_input(bare, t, u, substeps=2, output=True)[2], yr) > 1e-3


def test_the_comparison_has_power_for_the_series_dashpot(tmp_path: Path) -> None:
    """The series dashpot at value_for's values changes w far above the tolerance, and the C and both nlsys
    forms follow it (with play, whose xp integrates the played rate, not the element's)."""
    rng = np.random.default_rng(21)
    g = bw.TransferFunction([2.0, 5.0], [1.0, 1.2, 9.0], 0.013)
    h = bw.BoucWen(1.0, 0.4, 1.6, alpha=1.3)
    t, u = random_input(rng, 300)
    rho = value_for(T.SeriesDashpot, rng)
    for extra in ((), (T.Play(0.05), T.Degradation(0.05))):
        plant = bw.WienerPlant(g, h, (T.SeriesDashpot(rho), *extra))
        bare = bw.WienerPlant(g, h, extra)
        ref = bw.simulate_input(plant, t, u, substeps=2, output=True)
        assert rel(bw.simulate_input(bare, t, u, substeps=2, output=True)[1], ref[1]) > 1e-2
        name = f"sd{len(extra)}"
        rc, *c_out = run_c(compile_c(bw.to_c(plant, name=name), name, tmp_path), u, step(t), 2)
        d_out = discrete_response(bw.to_nlsys(plant, dt=step(t), substeps=2), t, u)
        assert rc == 0
        for got in (c_out, d_out):
            assert all(rel(np.asarray(a), b) <= 1e-9 for a, b in zip(got, ref))
        if not extra:  # no play: the continuous system is the simulator's ODE
            c_rk4 = rk4_response(bw.to_nlsys(plant), t, u, substeps=2)
            assert all(rel(a, b) <= 1e-9 for a, b in zip(c_rk4, ref))


@pytest.mark.parametrize("seed", range(4))
def test_continuous_nlsys_with_terms_on_x_matches_under_the_simulators_rk4(seed: int) -> None:
    """Without play and lag the continuous system is the simulator's ODE: RK4 on it agrees to 1e-9, terms
    on x and on u together (x's derivatives from the state, at every relative degree of G)."""
    rng = np.random.default_rng(50 + seed)
    on_x = [T.StiffnessX, T.ViscousX, T.InertiaX, T.CoulombX, T.Viscous, T.Coulomb, T.Asymmetry, T.Pinching]
    h = bw.BoucWen(1.0, 0.5, 1.6, alpha=1.3)
    plant = bw.WienerPlant(random_linear(rng), h, tuple(make(c, value_for(c, rng), rng) for c in on_x))
    t, u = random_input(rng, 250)
    sysc = bw.to_nlsys(plant, vmax=1.0, vx=1.0)
    got = rk4_response(sysc, t, u, substeps=2, plant=plant)
    ref = bw.simulate_input(plant, t, u, substeps=2, output=True)
    for g, want in zip(got, ref):
        assert rel(g, want) <= 1e-9


def test_continuous_nlsys_play_and_lag_are_the_ode_discrete_is_the_scheme() -> None:
    """Why two forms: with play and lag the continuous ODE under RK4 differs from the simulator by its
    integration error (here > 1e-6), the discrete system not at all (<= 1e-9)."""
    rng = np.random.default_rng(11)
    g = bw.TransferFunction([1.0], [0.1, 1.0])
    plant = bw.WienerPlant(g, bw.BoucWen(1.0, 0.5, 1.5), (T.Play(0.1), T.SensorLag(0.02), T.ViscousX(0.02)))
    t, u = random_input(rng, 300)
    ref = bw.simulate_input(plant, t, u, substeps=2, output=True)[2]
    cont = rk4_response(bw.to_nlsys(plant), t, u, substeps=2)[2]
    disc = discrete_response(bw.to_nlsys(plant, dt=step(t), substeps=2), t, u)[2]
    assert rel(cont, ref) > 1e-6 and rel(disc, ref) <= 1e-9


@dataclass(frozen=True)
class Unregistered(T.Term):
    """A term the exporters were never told about (as a term added to the registry without an exporter)."""

    q: float

    kind: ClassVar[str] = "unregistered_test_term"
    symbol: ClassVar[str] = "q"


def test_unknown_and_distortion_terms_are_refused_by_name() -> None:
    g = bw.TransferFunction([1.0], [0.1, 1.0])
    h = bw.BoucWen(1.0, 0.5, 1.5)
    t = np.arange(50) * 0.01
    for term, word in ((Unregistered(0.1), "unregistered_test_term"), (T.Distortion(1.0), "distortion")):
        plant = bw.WienerPlant(g, h, (term,))
        with pytest.raises(UnsupportedTermError, match=word):
            bw.to_c(plant)
        with pytest.raises(UnsupportedTermError, match=word):
            bw.to_nlsys(plant)
        with pytest.raises(UnsupportedTermError, match=word):
            bw.to_nlsys(plant, dt=0.01)
        with pytest.raises(UnsupportedTermError, match=word):
            peak_speeds(plant, t, np.sin(t))
        assert issubclass(UnsupportedTermError, InvalidParameterError)
    # JSON holds the model, the distortion included.
    plant = bw.WienerPlant(g, h, (T.Distortion(0.8), T.ViscousX(0.1)))
    assert bw.model_from_json(bw.model_to_json(plant)).terms == plant.terms


def test_discrete_system_layout_and_refusals() -> None:
    g = bw.TransferFunction([1.0], [0.1, 1.0], 0.01)
    plant = bw.WienerPlant(g, bw.BoucWen(1.0, 0.5, 1.5), (T.Play(0.1), T.SensorLag(0.01), T.CoulombX(0.1)))
    with pytest.raises(InvalidParameterError, match="vx"):
        bw.to_nlsys(plant, dt=0.01)
    sysd = bw.to_nlsys(plant, vx=1.0, dt=0.01, substeps=4)
    assert sysd.dt == pytest.approx(0.0025) and sysd.params["substeps"] == 4
    assert list(sysd.state_labels) == ["xs0", "w", "xp", "ys"]
    assert sysd.ninputs == 18 and list(sysd.input_labels)[:6] == [
        "u_0",
        "udot_0",
        "uddot_0",
        "v_0",
        "vdot_0",
        "vddot_0",
    ]
    t = np.arange(40) * 0.02
    with pytest.raises(InvalidParameterError, match="dt=<this grid's step>"):
        stage_inputs(sysd, t, np.sin(t))
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises((InvalidParameterError, NonFiniteError), match="dt"):
            bw.to_nlsys(plant, vx=1.0, dt=bad)
    with pytest.raises(InvalidParameterError, match="substeps"):
        bw.to_nlsys(plant, vx=1.0, dt=0.01, substeps=0)
