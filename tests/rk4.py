"""One classical RK4 step on a pair of state arrays, shared by the tests' own simulators (degradation_sim.py,
drift_null_sim.py): ``(a, b)`` advanced by ``h`` under ``rate(t, a, b) -> (a', b')``."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

Rate = Callable[[Any, Any, Any], tuple[Any, Any]]


def rk4_step(rate: Rate, t: Any, a: Any, b: Any, h: Any) -> tuple[Any, Any]:
    a1, b1 = rate(t, a, b)
    a2, b2 = rate(t + h / 2, a + h / 2 * a1, b + h / 2 * b1)
    a3, b3 = rate(t + h / 2, a + h / 2 * a2, b + h / 2 * b2)
    a4, b4 = rate(t + h, a + h * a3, b + h * b3)
    return a + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4), b + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4)
