"""Session 46: how much of a 10x sensor lag is a pure time delay, which the plain model takes exactly.

The plain Wiener-Bouc-Wen model has a free |G| and phase per experiment; the Bouc-Wen element is rate
independent, so delaying its input x by d delays its output by d: every experiment's own phase absorbs a
pure output delay exactly. A first-order lag 1/(tau s + 1) is a delay tau to first order in k omega tau;
only its departure from a delay (second order: gain droop (k omega tau)^2 / 2 at harmonic k) can show.

Per seed of the bench's sensor_lag 10x row (benches/generator.py's plant and lag, noise-free, reduced to
averaged periods by the library's own ``prepare``): the raw lag contribution ``y_lag - y_plain``, and what
is left after each experiment's best pure delay of ``y_plain`` (its harmonics shifted, the delay fitted by
least squares), both as RMS in averaged-noise sd (NOISE_SD / sqrt(PERIODS)); omega_max tau. The plain
model's own leftover (the bench's ``unabs``: phase AND |G| free) can only be at most the delay-only one.

Usage: ``python studies/bench46/lag_vs_delay.py [SEED ...]`` (default: the row's 20 seeds 35000-35019).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar  # type: ignore[import-untyped]

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))

import generator as gen  # noqa: E402
from bouc_wen_id.diagnosis.data import prepare  # noqa: E402


def _ybars(p: gen.Plant, y: np.ndarray, seed: int) -> list[tuple[np.ndarray, float]]:
    """Each experiment's averaged period and its frequency (rad/s), as the diagnosis reduces them."""
    return [(e.ybar, e.frequency) for e in prepare(gen.recordings(p, y, seed, noise_sd=0.0))]


def delay_left(target: np.ndarray, plain: np.ndarray, omega: float, guess: float) -> tuple[float, float]:
    """The residual sum of squares of ``target`` against ``plain`` delayed by the best d, and that d."""
    n = plain.size
    c = np.fft.rfft(plain)
    k = np.arange(c.size)

    def cost(d: float) -> float:
        shifted = np.fft.irfft(c * np.exp(-1j * k * omega * d), n)
        return float(np.sum((target - shifted) ** 2))

    res = minimize_scalar(cost, bounds=(0.0, 4.0 * guess + 1e-9), method="bounded", options={"xatol": 1e-12})
    return float(res.fun), float(res.x)


def main(seeds: list[int]) -> None:
    sd = gen.NOISE_SD / math.sqrt(gen.PERIODS)
    print("seed   shape      tau       w_max*tau  raw_sd  delay_left_sd  absorbed_by_delay")
    for seed in seeds:
        p = gen.make_plant(seed)
        b = gen.base(p)
        plain = gen.run(p, gen.Effect(), shared=b)[0]
        tau, _, lagged = gen._calibrate(p, "sensor_lag", "", 10.0, b)
        y0, y1 = _ybars(p, plain, seed), _ybars(p, lagged, seed)
        n = sum(a.size for a, _ in y0)
        raw = sum(float(np.sum((a1 - a0) ** 2)) for (a0, _), (a1, _) in zip(y0, y1))
        left = sum(delay_left(a1, a0, w, tau)[0] for (a0, w), (a1, _) in zip(y0, y1))
        print(
            f"{seed}  {p.shape:9s} {tau:.3e}  {float(p.omegas.max()) * tau:.4f}    "
            f"{math.sqrt(raw / n) / sd:6.2f}  {math.sqrt(left / n) / sd:8.3f}       {1 - left / raw:.6f}"
        )


if __name__ == "__main__":
    main([int(s) for s in sys.argv[1:]] or list(range(35000, 35020)))
