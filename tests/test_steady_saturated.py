"""The steady loop of a saturated Bouc-Wen loop (``rust/steady.rs`` ``BRACKET_SLACK``; issue 18 item 4).

When ``|A|`` is many times the loop's width, ``w(0)`` sits at the bound ``(1/(beta+gamma))^(1/mu)`` and the
shooting's first Newton step lands exactly there. With the open bracket ``(-bound, bound)`` that step was
refused and the shooting bisected (20 coarse and 45 fine passes on the MR damper's fits at 0 A); the first
bracket now has a 1e-9 relative slack. Held here: Rust and the NumPy oracle agree on random saturated loops,
the shooting converges in at most two Newton steps, and ``w(0)`` is the bound.
"""

from __future__ import annotations

import numpy as np
import pytest
from bouc_wen_id._backend import get_backend
from numpy.testing import assert_allclose

RUST = get_backend("rust").paper
NUMPY = get_backend("numpy").paper


def _saturated(seed: int) -> tuple[float, float, float, float, float, int, int]:
    """A random loop whose amplitude is 50-100 times its width (the MR damper's fits at 0 A: 96; ``Phi(pi)``
    underflows), on the MR damper's fine grids (at least 486 RK4 steps per period)."""
    rng = np.random.default_rng(seed)
    beta = rng.uniform(0.3, 2.0)
    gamma = beta * rng.uniform(0.0, 1.0)
    mu = rng.uniform(1.2, 2.5)
    bound = (1.0 / (beta + gamma)) ** (1.0 / mu)
    amp = rng.uniform(50.0, 100.0) * bound * rng.choice([-1.0, 1.0])
    p = int(rng.choice([243, 325, 391, 401]))
    return amp, beta, gamma, mu, rng.uniform(0.0, 2.0 * np.pi), p, 2


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_saturated_loop_parity_and_newton(seed: int) -> None:
    args = _saturated(seed)
    amp, beta, gamma, mu = args[:4]
    w, jac, top, iterations = RUST.steady_loop(*args)
    w_ref, jac_ref, top_ref, iterations_ref = NUMPY.steady_loop(*args)
    assert_allclose(w, w_ref, rtol=1e-11, atol=1e-12)
    assert_allclose(jac, jac_ref, rtol=1e-9, atol=1e-10)
    assert iterations == iterations_ref
    # Newton, not bisection: the open bracket took 40-45 fine passes here.
    assert iterations <= 2
    bound = (1.0 / (beta + gamma)) ** (1.0 / mu)
    assert abs(top) == pytest.approx(bound, rel=1e-9)
    assert np.max(np.abs(w)) <= bound * (1.0 + 1e-9)
