"""The drift test's block chi-square over its dof, harmonic by harmonic, on noise alone, weighed by
``data.harmonic_levels`` (as ``drift.drift_data`` weighs the blocks: block samples over each harmonic's
level, about their weighted mean): 1 is calibrated, below 1 the levels overstate the blocks' noise, above
1 they understate it (a term acting there looks significant on noise).

    PYTHONPATH=python python studies/levels47/calib47.py [KIND ...] [--alpha A]   # this branch
    PYTHONPATH=/work/main/python python studies/levels47/calib47.py ...          # main, for comparison

Kinds (40 samples a period, 20 periods, 200 records each): ar2 (review 46's: poles 0.95 e^{+-0.3i} a
sample, its peak at 1.9 harmonics), white, ar1 (phi 0.9), ar1s (phi 0.99), pink (1/f). ``--alpha`` sets
``level_bands.BAND_ALPHA`` (this branch only).
"""

from __future__ import annotations

import math
import sys

import numpy as np
from bouc_wen_id.diagnosis import data
from scipy.signal import lfilter  # type: ignore[import-untyped]

P, N, K, RECORDS = 40, 20, 15, 200


def noise(kind: str, n: int, rng: np.random.Generator) -> np.ndarray:
    if kind == "ar2":
        r, th = 0.95, 0.3
        return np.asarray(lfilter([1.0], [1.0, -2 * r * math.cos(th), r * r], rng.normal(size=n + 500))[500:])
    if kind == "ar1":
        return np.asarray(lfilter([1.0], [1.0, -0.9], rng.normal(size=n + 500))[500:])
    if kind == "ar1s":
        return np.asarray(lfilter([1.0], [1.0, -0.99], rng.normal(size=n + 2000))[2000:])
    if kind == "pink":
        f = np.fft.rfftfreq(n)
        s = np.zeros(f.size)
        s[1:] = 1.0 / np.sqrt(f[1:])
        return np.fft.irfft(s * (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)), n)
    return rng.normal(size=n)


def calibration(kind: str) -> np.ndarray:
    rng = np.random.default_rng(5)
    chi, dof = np.zeros(K + 1), np.zeros(K + 1)
    for _ in range(RECORDS):
        rows = noise(kind, N * P, rng).reshape(N, P)
        hv = data.harmonic_levels(rows, float(np.var(rows)))
        coef, w, _, _ = data._recording_blocks(rows)
        dev = coef - (w[:, None] * coef).sum(axis=0) / w.sum()
        c = 0.5 * np.abs(dev) ** 2 * w[:, None] / hv
        c[:, 0] = dev[:, 0].real ** 2 * w / hv[0]
        d = np.full(K + 1, 2.0 * (w.size - 1))
        d[0] = w.size - 1
        chi, dof = chi + c.sum(axis=0), dof + d
    return np.asarray(chi / dof)


def main(argv: list[str]) -> None:
    if "--alpha" in argv:
        from bouc_wen_id.diagnosis import level_bands

        i = argv.index("--alpha")
        level_bands.BAND_ALPHA = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2 :]
    print(f"{data.__file__}")
    print("kind   " + " ".join(f"{j:5d}" for j in range(K + 1)) + "   1..15")
    for kind in argv[1:] or ["ar2", "white", "ar1", "ar1s", "pink"]:
        r = calibration(kind)
        print(f"{kind:6s} " + " ".join(f"{v:5.2f}" for v in r) + f"   {float(np.mean(r[1:])):.3f}")


if __name__ == "__main__":
    main(sys.argv)
