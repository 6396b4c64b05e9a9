"""Review 45 failure 1's cause, in numbers: under 1/f noise no spread inside a record gives the record mean's
variance, so the DC's tests and the settling test read the noise's slow content as structure.

    PYTHONPATH=python python studies/pink45/dc_level45.py

Records of config B's shape (15 settling + 8 analysed periods of 200 samples; also 20 analysed), noise only:
white, AR(1) phi = 0.9, and pink made two ways (review 45's FFT shaping, sim45.noise; and a sum of 12 AR(1)s
with time constants 2^j samples, another way). For each, over 300 seeded draws:

- ``z now``: the variance of the record DC's z, ``mean / sqrt(level / (N P))``, with ``level`` the diagnosis's
  DC level (data.noise_colour: the period DCs' spread about a quadratic trend, times the lag-1 inflation when
  coloured); 1 when the level is right;
- the same with the level raised (never lowered) to three in-record alternatives: the period DCs' spread about
  their mean (``about mean``), that times the lag-1 inflation (``x infl``), and the record's periodogram at
  the two sub-fundamental bins (noise only: the loop sits at multiples of N) (``low bins``);
- ``flagged`` / ``trimmed``: the share of records whose first periods outliers.transient_periods calls
  transient, and that settling._settled then trims (no trend in the rest).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from bouc_wen_id.diagnosis.data import cross_period_inflation, noise_colour
from bouc_wen_id.diagnosis.outliers import transient_periods
from bouc_wen_id.diagnosis.settling import _trending

sys.path.insert(0, str(Path(__file__).parents[1] / "review45"))
sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))
import sim45  # noqa: E402
from pink_noise import sum_of_ar1  # noqa: E402

P, S, DRAWS = 200, 15, 300


def ar1(n: int, rng: np.random.Generator, phi: float = 0.9) -> np.ndarray:
    e = rng.normal(size=n)
    x = np.empty(n)
    x[0] = e[0] / math.sqrt(1.0 - phi * phi)
    for i in range(1, n):
        x[i] = phi * x[i - 1] + e[i]
    return x


def draw(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    if kind == "white":
        return rng.normal(size=n)
    if kind == "ar1 0.9":
        return ar1(n, rng)
    if kind == "pink (sim45)":
        return sim45.noise(sim45.Noise("pink", 1.0), n, 0.01, rng)
    return sum_of_ar1(n, rng)


def main() -> None:
    for n_per in (8, 20):
        for kind in ("white", "ar1 0.9", "pink (sim45)", "pink (sum of AR(1)s)"):
            rng = np.random.default_rng([45, 4, n_per])
            z: dict[str, list[float]] = {"now": [], "about mean": [], "x infl": [], "low bins": []}
            flagged = trimmed = 0
            for _ in range(DRAWS):
                y = draw(kind, (S + n_per) * P, rng)
                rows = y[S * P :].reshape(n_per, P)
                diff = float(np.mean(np.diff(rows, axis=0) ** 2)) / 2.0
                level = noise_colour(rows, diff, P * (n_per - 1))[0]
                d, m = rows.mean(axis=1), float(rows.mean())
                spread = P * float(np.var(d, ddof=1))
                f = np.fft.rfft(y[S * P :] - np.tile(rows.mean(axis=0), n_per))
                low = float(np.mean(np.abs(f[1:3]) ** 2)) / (n_per * P)
                alts = (level, spread, spread * cross_period_inflation(d), low)
                for key, v in zip(z, alts):
                    z[key].append(m / math.sqrt(max(level, v) / (n_per * P)))
                k = transient_periods(y, P, S, n_per)
                flagged += k > 0
                trimmed += k > 0 and n_per - k >= 4 and not _trending(y, P, S + k, n_per - k)
            said = ", ".join(f"{key} {float(np.var(v)):.2f}" for key, v in z.items())
            print(
                f"{n_per} periods, {kind}: var of the DC's z: {said}; transient flagged "
                f"{flagged / DRAWS:.2f}, trimmed {trimmed / DRAWS:.2f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
