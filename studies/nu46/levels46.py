"""Session 46 (nu46): the mean of ``S_j / L_j`` (true AR(0.9) level over ``data.harmonic_levels``' estimate)
at harmonics 1..3 of four one-period rows of 256 samples, 3000 seeded draws; it is the factor by which the
drift test's weight ``1 / L`` is too large on average, and the drift-space variance too small for a regressor
at that harmonic. Run with PYTHONPATH at the code to measure (main: 1.84, 1.53, 1.29; commit 0561b72, with
``nu / (nu - 2)``: 1.23, 1.15, 1.03).

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/nu46/levels46.py
"""

from __future__ import annotations

import numpy as np
from bouc_wen_id.diagnosis.data import harmonic_levels

PHI, N, P = 0.9, 4, 256


def main() -> None:
    rng = np.random.default_rng([46, 0])
    j = np.arange(4)
    true = (1 - PHI**2) / np.abs(1 - PHI * np.exp(-2j * np.pi * j / P)) ** 2
    ratios = []
    for _ in range(3000):
        e = rng.standard_normal(N * P + 500)
        x = np.empty_like(e)
        x[0] = e[0]
        for k in range(1, x.size):
            x[k] = PHI * x[k - 1] + np.sqrt(1 - PHI**2) * e[k]
        lv = harmonic_levels(x[500:].reshape(N, P), 1.0)
        ratios.append(true[1:4] / lv[1:4])
    print("E[S/L] at harmonics 1..3:", np.round(np.mean(ratios, axis=0), 3))


if __name__ == "__main__":
    main()
