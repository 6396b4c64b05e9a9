"""A distorted drive (2-3 % second or third harmonic, seen by the plant too) through several G shapes.

    PYTHONPATH=python python studies/distorted_drive.py G:K:LEVEL:SEED:C [...]

G is one of ``res_d`` (36/(s^2 + 1.2 s + 36), 0.03 s delay: Q 5 at 6 rad/s), ``res4`` (16/(s^2 + 0.8 s + 16):
Q 5 at 4 rad/s), ``twopole`` (6/(s^2 + 5 s + 6): poles at 2 and 3 rad/s), ``fo`` (4/(s + 4)) and ``fo_d``
(``fo`` with a 0.05 s delay); K the harmonic (2 or 3), LEVEL its size relative to the fundamental, C a dashpot
on the measured input (0: a plain device). Five frequencies 1-7 rad/s at U = 1, 12 settling and 10 kept
periods of 64 samples, noise sd 0.01, Bouc-Wen beta 1, gamma 0.3, mu 1.5, simulated by ``simulate_input``
on the distorted input. One JSON line per case: the status, the named terms (value, se), the final p.
"""

from __future__ import annotations

import json
import sys
import time
import warnings

import bouc_wen_id as bw
import numpy as np

GS = {
    "res_d": ([36.0], [1.0, 1.2, 36.0], 0.03),
    "res4": ([16.0], [1.0, 0.8, 16.0], 0.0),
    "twopole": ([6.0], [1.0, 5.0, 6.0], 0.0),
    "fo": ([4.0], [1.0, 4.0], 0.0),
    "fo_d": ([4.0], [1.0, 4.0], 0.05),
}


def recordings(g: str, k: int, level: float, seed: int, c: float) -> list[bw.Recording]:
    num, den, delay = GS[g]
    lin = bw.TransferFunction(num, den, delay=delay)
    plant = bw.WienerPlant(lin, bw.BoucWen(beta=1.0, gamma=0.3, mu=1.5))
    rng = np.random.default_rng(seed)
    p, settle, periods = 64, 12, 10
    out = []
    for om in (1.0, 2.0, 3.5, 5.0, 7.0):
        t = np.arange((settle + periods) * p) * (2 * np.pi / om / p)
        th = om * t
        u = np.cos(th) + level * np.cos(k * th + 0.4)
        udot = -om * (np.sin(th) + k * level * np.sin(k * th + 0.4))
        _, w = bw.simulate_input(plant, t, u, substeps=8)
        y = w + c * udot + rng.normal(0.0, 0.01, t.size)
        out.append(bw.Recording(t, u, y, 1.0, om, settle_periods=settle))
    return out


def main(specs: list[str]) -> None:
    for spec in specs:
        g, k, level, seed, c = spec.split(":")
        recs = recordings(g, int(k), float(level), int(seed), float(c))
        t0 = time.time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs)
        named = {t.term: (float(f"{t.value:.4g}"), float(f"{t.standard_error:.2g}")) for t in d.named}
        row = {"case": spec, "status": d.status, "named": named, "final_p": float(f"{d.final.p_value:.2g}")}
        print(json.dumps({**row, "s": round(time.time() - t0, 1)}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
