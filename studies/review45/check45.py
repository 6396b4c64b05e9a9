"""Review 45: sim45 (solve_ivp, DOP853, rtol 1e-9) against two other methods, on short records.

    PYTHONPATH=python python studies/review45/check45.py

1. The same right-hand side by a fixed-step RK4 (64 steps per sample): max |y difference| / w_u, per case.
2. Review 44's sim44 (closed-form G, RK4 in the travel, SUB = 2 and 8) on a shared plant: resonant wn 5,
   zeta 0.3, 8 ms delay, Bouc-Wen (1.2, 0.3, 1.5), plain and with play, pinching, strength and stiffness
   degradation.
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "review44"))
import drive45 as dv  # noqa: E402
import sim45 as s  # noqa: E402


def short(d: s.Design) -> s.Design:
    """The config's first two experiments, 3 settling and 2 recorded periods."""
    return replace(d, omegas=d.omegas[:2], amps=d.amps[:2], periods=(2, 2), settle=3)


def rk4_cases() -> None:
    extra = {
        "plain": {},
        "play": {"play": 0.2},
        "slack": {"slack": 0.2},
        "nu+eta": {"nu": 0.05, "eta": 0.05},
        "pinch": {"pinch": 0.6},
        "delta": {"delta": 0.2},
        "rate": {"rate": 1.0},
    }
    for cfg in ("A", "B", "C", "D"):
        p, d, _ = dv.scaled(cfg)
        d = short(d)
        for name, kv in extra.items():
            q = p
            for k, v in kv.items():
                q = s.with_value(q, k, v * (p.hy.w_u if k in ("play", "slack") else 1.0))
            err = max(s.rk4_check(q, d, i) for i in range(2))
            print(f"rk4 {cfg} {name:7s} max|dy|/w_u = {err / p.hy.w_u:.1e}")
        for name, q in (
            ("lag", replace(p, lag=0.02)),
            ("dahl_x", replace(p, dahl_x=0.05, dahl_x_travel=0.3)),
            ("pi_u", replace(p, pi_u=0.05)),
        ):
            err = max(s.rk4_check(q, d, i) for i in range(2))
            print(f"rk4 {cfg} {name:7s} max|dy|/w_u = {err / p.hy.w_u:.1e}")


def sim44_cases() -> None:
    import sim44

    g44 = sim44.resonant(5.0, 0.3, 0.008)
    g45 = s.Linear(g44.num, g44.den, 0.008)
    d44 = sim44.Design((2.0, 5.0, 10.0), (1.0, 2.0, 3.0), periods=2, settle=3)
    d45 = s.Design(d44.omegas, d44.amps, (2, 2, 2), settle=3, samples=256)
    for sub in (2, 8):  # sim44's RK4 steps per sample: its error shrinks toward sim45
        sim44.SUB = sub
        for name, kv in (
            ("plain", {}),
            ("play", {"play": 0.1}),
            ("pinch", {"pinch": 0.6}),
            ("nu", {"nu": 0.05}),
            ("eta", {"eta": 0.05}),
        ):
            h44 = replace(sim44.Hyst(1.2, 0.3, 1.5), **kv)
            h45 = replace(s.Hyst(1.2, 0.3, 1.5), **kv)
            r44 = sim44.run(sim44.Plant(g44, h44), d44)
            r45 = s.run(s.Plant(g45, h45), d45)
            err = max(float(np.max(np.abs(a[2] - b[2]))) for a, b in zip(r44, r45))
            print(f"sim44 SUB={sub} {name:6s} max|dy|/w_u = {err / h45.w_u:.1e}")


def rk4_no_delay() -> None:
    """Config C's larger RK4 difference is the fixed step straddling the delayed input's start (a jump)."""
    p, d, _ = dv.scaled("C")
    q = replace(p, g=replace(p.g, delay=0.0))
    err = max(s.rk4_check(q, short(d), i) for i in range(2))
    print(f"rk4 C plain, delay 0: max|dy|/w_u = {err / p.hy.w_u:.1e}")


if __name__ == "__main__":
    rk4_cases()
    rk4_no_delay()
    sim44_cases()
