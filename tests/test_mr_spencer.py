"""The simulator and the fit of ``studies/mr_spencer.py`` (Spencer's MR damper model) on data whose answer is
known.

The study's verdict rests on three things checked here: its RK4 periodic steady state of Spencer's model
agrees with an independent integration of the model as Spencer et al. (1997) write it (in x, y, z, by
scipy's LSODA from rest until the loop repeats); its batched least-squares fit recovers a known parameter set
from noisy averaged periods it generated; and the model terms it compares are not interchangeable (Spencer
with its spring k0 draws another loop than without it, which the independent integrator confirms).
"""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest
from scipy.integrate import solve_ivp  # type: ignore[import-untyped]

STUDIES = Path(__file__).resolve().parents[1] / "studies"


def _load(name: str) -> ModuleType:
    if name in sys.modules:
        return sys.modules[name]
    if str(STUDIES) not in sys.path:
        sys.path.insert(0, str(STUDIES))
    spec = importlib.util.spec_from_file_location(name, STUDIES / f"{name}.py")
    assert spec is not None and spec.loader is not None, f"cannot load studies/{name}.py"
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


study = _load("mr_spencer")

#: A known Spencer parameter set in the damper's units (N, mm, s; A = 1): yield force about 600 N at a
#: 0.4 mm travel, c1 / c0 about 10, a k0 strong enough for the chain to settle within a few periods.
TRUE = {
    "alpha": 1500.0,
    "beta": 4.0,
    "gratio": 0.6,
    "n": 1.6,
    "c0": 2.5,
    "c1": 30.0,
    "k0": 40.0,
    "k1": 1.5,
    "f0": 12.0,
}
DESIGN = ((24.0, 0.5), (9.6, 2.0), (4.4, 4.0))  # (U mm, f Hz), as the damper's files


def _exps(ybars: list[np.ndarray]) -> list[object]:
    return [
        study.Exp(f"{u} mm {f} Hz", y, u, 2.0 * math.pi * f, np.array([0.02, -0.01]), 0.0)
        for (u, f), y in zip(DESIGN, ybars)
    ]


def _model_outputs(
    nat: dict[str, float], steps: int, variant: str = "spencer", fixed: bool = False
) -> list[np.ndarray]:
    model = study.Model(variant, study.VARIANTS[variant])
    exps = _exps([np.zeros(41)] * len(DESIGN))
    th = np.repeat(model.theta(model.q(nat)), len(exps), axis=0)
    st = (study.steady_fixed if fixed else study.steady)(th, exps, steps)
    assert st.periodicity < 1e-6
    return list(st.outputs)


def _lsoda_period(nat: dict[str, float], u: float, f: float, p: int, periods: int) -> np.ndarray:
    """Spencer's equations as written (states y, z; x = U Re[e^{iwt} + c2 e^{2iwt}]), LSODA from rest for
    ``periods`` periods; the last period's force on ``p`` points, projected on (p - 1) / 2 harmonics."""
    om = 2.0 * math.pi * f
    c2 = 0.02 - 0.01j
    al, be, n = nat["alpha"], nat["beta"], nat["n"]
    ga = nat["gratio"] * be
    c0, c1, k0, k1, f0 = nat["c0"], nat["c1"], nat["k0"], nat["k1"], nat["f0"]

    def x_of(t: float) -> tuple[float, float]:
        e1, e2 = np.exp(1j * om * t), np.exp(2j * om * t)
        return u * float(np.real(e1 + c2 * e2)), u * om * float(np.real(1j * e1 + 2j * c2 * e2))

    def rhs(t: float, s: np.ndarray) -> list[float]:
        y, z = s
        x, xd = x_of(t)
        yd = (al * z + c0 * xd + k0 * (x - y)) / (c0 + c1)
        v = xd - yd
        zd = -ga * abs(v) * z * abs(z) ** (n - 1.0) - be * v * abs(z) ** n + v
        return [yd, zd]

    period = 2.0 * math.pi / om
    fine = 2048
    t_out = (periods - 1) * period + np.arange(fine) * period / fine
    sol = solve_ivp(
        rhs,
        (0.0, periods * period),
        [0.0, 0.0],
        method="LSODA",
        t_eval=t_out,
        rtol=1e-10,
        atol=1e-12,
        max_step=period / 400.0,
    )
    assert sol.success
    force = np.empty(fine)
    for i, (t, y, z) in enumerate(zip(sol.t, sol.y[0], sol.y[1])):
        x, xd = x_of(float(t))
        yd = (al * z + c0 * xd + k0 * (x - y)) / (c0 + c1)
        force[i] = c1 * yd + k1 * x + f0
    out: np.ndarray = study._project(force[:, None], [p])[0]
    return out


def test_rk4_steady_state_matches_an_independent_integration_of_spencers_equations() -> None:
    """The study's Newton-shooting RK4 steady state and LSODA from rest (Spencer's x, y, z form) agree to
    1e-4 of the loop's spread; with k0 dropped (the ``series`` variant) the loop moves by far more than
    that, so the check sees the spring."""
    ours = _model_outputs(TRUE, 720)
    for (u, f), y in zip(DESIGN, ours):
        ref = _lsoda_period(TRUE, u, f, 41, periods=12 if f < 1 else 30)
        spread = float(np.linalg.norm(ref - ref.mean()))
        assert float(np.linalg.norm(y - ref)) / spread < 1e-4
    no_k0 = _model_outputs(TRUE | {"k0": 0.0}, 720, "series")
    moved = [float(np.linalg.norm(a - b) / np.linalg.norm(b - b.mean())) for a, b in zip(no_k0, ours)]
    assert min(moved) > 1e-2


def test_step_count_converges() -> None:
    """Doubling the RK4 steps moves the steady output by less than 1e-4 of its spread (the study reports the
    same check on every fitted model)."""
    a, b = _model_outputs(TRUE, 360, fixed=True), _model_outputs(TRUE, 720, fixed=True)
    for x, y in zip(a, b):
        assert float(np.linalg.norm(x - y) / np.linalg.norm(y - y.mean())) < 1e-4


def test_fit_recovers_a_known_parameter_set_from_noisy_periods() -> None:
    """Averaged periods drawn from TRUE plus 0.5 % seeded noise; the concurrent least-squares fits (two
    starts away from the truth) find the force to within the noise and the physics close to TRUE; a
    fit that leaves k0 out (``series``) stays well above the noise."""
    rng = np.random.default_rng(7)
    clean = _model_outputs(TRUE, 360)
    sigma = [0.005 * float(np.std(y)) for y in clean]
    exps = _exps([y + s * rng.standard_normal(y.size) for y, s in zip(clean, sigma)])
    full = study.Model("spencer", study.VARIANTS["spencer"])
    series = study.Model("series", study.VARIANTS["series"])
    starts = [
        TRUE | {"alpha": 900.0, "c1": 50.0, "k0": 15.0, "n": 2.0},
        TRUE | {"alpha": 2500.0, "c0": 1.5, "k0": 90.0, "gratio": 0.2},
    ]
    jobs = [study.fit_job(full, exps, full.q(s), 40) for s in starts]
    jobs += [study.fit_job(series, exps, series.q(starts[0] | {"k0": 0.0}), 40)]
    fits = study.Batcher(360).run(jobs)
    best = min(fits[:2], key=lambda f: f.cost)
    noise = [s / float(np.std(y)) for s, y in zip(sigma, clean)]  # NRMSE of the noise alone
    assert max(best.nrmse) < 1.5 * max(noise)
    got = study.describe(full, best.q)
    for k in ("alpha", "c0", "c1", "k0", "k1"):
        assert got[k] == pytest.approx(TRUE[k], rel=0.1), k
    assert got["f_yield"] == pytest.approx(study.describe(full, full.q(TRUE))["f_yield"], rel=0.02)
    assert min(fits[2].nrmse) > 5.0 * max(noise)
