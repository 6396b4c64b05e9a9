"""Session 48: is a sensor lag the verdict calls "below its 90 %-power limit" really below it? Power by
simulation at the case's own design.

For one bench case of ``benches/diagnosis.py``'s ``sensor_lag`` row (``benches/generator.py``'s plant, its
own lag and noise, not the library's simulator): the diagnosis on the case's own noise states the lag's
detection limits (50 % and 90 % power of its F-test at the targeted step's level); the noise-free record is
then re-made at the true tau and at the stated 90 % value and diagnosed under ``DRAWS`` other noise draws
(draw k: the generator's noise for seed ``OTHER + 1000 k + seed``, as studies/bench47/noise_swap.py). Per
value: how often the lag's own first-step test passes (its F test at the step's level and the share gate:
what the limit promises) and how often the verdict names it (what the bench scores: also the law test, the
rivals and the held-out test).

Usage: ``python studies/bench48/lag_power.py SEED [SEED ...] [--draws N]``.
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "bench47"))

import bouc_wen_id as bw  # noqa: E402
import generator as gen  # noqa: E402
from noise_swap import OTHER  # noqa: E402


def _diagnose(recs: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


def _lag_passed(d: Any) -> bool:
    """Whether the lag candidate passed its in-sample tests (F at the step's level, the share gate) at the
    first selection step: what the detection limit is the power of."""
    trials = d.steps[0].trials if d.steps else ()
    return any(t.term == "sensor_lag" and t.passed for t in trials)


def _limits(d: Any) -> tuple[float, float]:
    lim = next((x for x in d.limits if x.term == "sensor_lag"), None)
    return (lim.limit, lim.limit_90) if lim is not None else (math.nan, math.nan)


def run(seed: int, draws: int) -> None:
    p = gen.make_plant(seed)
    b = gen.base(p)
    tau, _, y = gen._calibrate(p, "sensor_lag", "", 10.0, b)
    d0 = _diagnose(gen.recordings(p, y, seed))
    l50, l90 = _limits(d0)
    print(
        f"seed {seed} ({p.shape}): true tau {tau:.5g} s; own noise: {d0.status}, named "
        f"{list(d0.named_terms) or '-'}; stated limits 50 % {l50:.5g}, 90 % {l90:.5g} s"
    )
    for label, value in (("true tau", tau), ("stated 90 %", l90)):
        if not math.isfinite(value):
            continue
        yv = y if value == tau else gen.run(p, gen.Effect("sensor_lag", "", np.array([value])), shared=b)[0]
        named = passed = 0
        for k in range(draws):
            d = _diagnose(gen.recordings(p, yv, OTHER + 1000 * k + seed))
            passed += int(_lag_passed(d))
            named += int("sensor_lag" in d.named_terms)
        se = math.sqrt(max(named, 1) * max(draws - named, 1)) / draws**1.5
        print(
            f"  {label} {value:.5g} s: first-step test passed {passed}/{draws}, named {named}/{draws} "
            f"({named / draws:.2f} +- {se:.2f})",
            flush=True,
        )


def main(argv: list[str]) -> None:
    draws = int(argv[argv.index("--draws") + 1]) if "--draws" in argv else 16
    skip = {argv.index("--draws"), argv.index("--draws") + 1} if "--draws" in argv else set()
    for seed in (int(a) for k, a in enumerate(argv) if k not in skip):
        run(seed, draws)


if __name__ == "__main__":
    main(sys.argv[1:])
