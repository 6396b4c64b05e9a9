"""Is a second term named after a first the data's or the noise's? One bench case's plant and effect
(benches/generator.py, at its calibrated size) under other noise draws: a term that the first term's misfit
draws comes back at every draw; a noise false alarm does not (after_named.py's docstring, session 33).

    PYTHONPATH=python python studies/after_named_noise.py library play 32015 0 5
    PYTHONPATH=python python studies/after_named_noise.py pending pinching 44014 0 5
    PYTHONPATH=python python studies/after_named_noise.py lag 0.002,0.003,0.004 1 5

The last form is the price of the step's level: a sensor lag of each size behind an output offset of 0.05
(tests/test_diagnosis_after_named.py's first-order G and design), seeds 1-4: the named terms and each step's
sensor-lag adjusted p (the step after a named one tests it at alpha / 10).

Arguments: the case's kind, effect, seed (benches/diagnosis.py's case id), and the range of draws (draw 0 is
the bench's own noise; draw k's noise is seeded ``seed + 1000003 k``). Each line: the named terms and, for
each targeted step after a named one, its best candidate's adjusted p, F and held-out gain (chi2 units).
"""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")


def lags(sizes: list[float], first: int, last: int) -> None:
    import numpy as np
    from bouc_wen_id import terms as T

    om = np.repeat(2.0 * math.pi * np.array([0.5, 1.5, 4.0]), 2)
    lin = bw.TransferFunction([1.0], [0.05, 1.0])
    amps = np.tile([0.8, 2.0], 3) / lin.gain_phase(om)[0]
    for lag in sizes:
        for seed in range(first, last):
            plan = bw.SinePlan(om, amps, settle_periods=8, periods=12, samples_per_period=64, substeps=8,
                               noise_sd=0.01, seed=seed)  # fmt: skip
            plant = bw.WienerPlant(lin, bw.BoucWen(0.7, 0.3, 1.8), terms=(T.SensorLag(lag), T.Offset(0.05)))
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = bw.diagnose(bw.simulate(plant, plan))
            got = [
                f"step {k}{' (after)' * bool(getattr(st, 'after_named', False))}: {t.p_adjusted:.3g}"
                for k, st in enumerate(d.steps, 1)
                for t in st.trials
                if t.term == T.SensorLag.kind and math.isfinite(t.p_adjusted)
            ]
            print(f"lag {lag} seed {seed}: named {list(d.named_terms)}; sensor lag p adj {got}", flush=True)


def main() -> None:
    if sys.argv[1] == "lag":
        return lags([float(v) for v in sys.argv[2].split(",")], int(sys.argv[3]), int(sys.argv[4]))
    kind, effect, seed = sys.argv[1], sys.argv[2], int(sys.argv[3])
    first, last = int(sys.argv[4]), int(sys.argv[5])
    plant = gen.make_plant(seed)
    _, _, y = gen._calibrate(plant, effect, "", 10.0, gen.base(plant))
    for k in range(first, last):
        recs = gen.recordings(plant, y, seed + 1000003 * k)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs)
        after = []
        for st in d.steps:
            tried = [t for t in st.trials if math.isfinite(t.p_adjusted)]
            if not (getattr(st, "after_named", False) and tried):
                continue
            best = min(tried, key=lambda t: t.p_adjusted)
            ho = best.held_out
            gain = math.nan if ho is None else sum(ho.cost_before) - sum(ho.cost_after)
            after.append(
                f"{best.term} p adj {best.p_adjusted:.3g} F {best.statistic:.3g} held-out {gain:.3g}"
            )
        print(f"{kind} {effect} {seed} draw {k}: named {list(d.named_terms)}; after a named term: {after}")


if __name__ == "__main__":
    main()
