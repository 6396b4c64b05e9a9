"""Does the diagnosis *name* what a detection plan promises? Plans drawn and diagnosed, on several plants.

``bouc-wen-id plan --budget 300 --band 1 10 --max-amplitude 1 --noise 0.05 --sample-rate 100
--settle-periods 10 --detect sensor_lag=0.01`` plans sine experiments for a named term; the diagnosis names
the term only if its F-test passes *and* it improves the held-out fit (leave one experiment out), its law
holds and its value is away from the null. This script plans (``--min-experiments``), takes the plan's
stated 90 % design (:meth:`DetectionPlan.scaled`; ``--time T``: every experiment's periods scaled to about
T s instead), draws ``--draws`` recordings with the library's simulator (the plant plus the term; seeded
white noise, seed ``1000 k + i`` for draw k, experiment i) and diagnoses each: the term's first-step F-test
passing at its level, the term named, any other physics named ("wrong"). It prints the plan's predicted
power to detect and predicted chance to name (:func:`~bouc_wen_id.planning.naming_chance`) on the drawn
design, with the empirical rates and their 95 % (Clopper-Pearson) intervals. docs/power.md, "Plans for
naming".

``--plant``: ``demo`` (the README's: resonant, omega_n 5, zeta 0.2, 0.05 s delay), ``resonant`` (omega_n 7,
zeta 0.1, 0.03 s delay) or ``first_order`` (1 / (0.15 s + 1), no delay); ``--term``/``--size``: the term
(default the README's sensor lag 0.01 s; e.g. ``viscous@x`` 0.004).

Usage: ``python benches/plan_naming.py [--plant demo] [--term sensor_lag --size 0.01] [--draws 12]
[--min-experiments 3] [--time T] [--budget 300] [--json F]``
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any, Optional

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "python"))

LAB: dict[str, Any] = dict(
    band=(1.0, 10.0), max_amplitude=1.0, noise_sd=0.05, sample_rate=100.0, settle_periods=10
)
TERM, SIZE, BUDGET = "sensor_lag", 0.01, 300.0


def plant(name: str) -> Any:
    """The bench's plants: the demo (resonant with a delay), another resonance with a delay, a first order,
    a first order with a delay."""
    import bouc_wen_id as bw

    if name == "demo":
        return bw.demo_plant()
    h = bw.BoucWen(beta=1.6, gamma=0.4, mu=1.6, alpha=2.0)
    if name == "resonant":
        return bw.WienerPlant(bw.TransferFunction([49.0], [1.0, 1.4, 49.0], delay=0.03), h)
    if name == "first_order":
        return bw.WienerPlant(bw.TransferFunction([1.0], [0.15, 1.0]), h)
    if name == "first_order_delay":  # the reviewer's plant (session 31): other G, other hysteresis
        other = bw.BoucWen(beta=0.9, gamma=0.3, mu=2.5, alpha=1.5)
        return bw.WienerPlant(bw.TransferFunction([2.0], [0.3, 1.0], delay=0.02), other)
    raise SystemExit(f"unknown --plant {name!r}: demo, resonant, first_order or first_order_delay")


def _at_time(exps: list[Any], target: float) -> list[Any]:
    """``exps`` with every experiment's periods scaled by one factor so the test time is about ``target``."""
    settle = sum(e.duration - e.periods * 2.0 * math.pi / e.frequency for e in exps)
    run = sum(e.periods * 2.0 * math.pi / e.frequency for e in exps)
    f = max((target - settle) / run, 1e-9)
    return [replace(e, periods=max(1, math.ceil(f * e.periods))) for e in exps]


def interval(k: int, n: int) -> tuple[float, float]:
    """Clopper-Pearson 95 % interval of a rate k / n."""
    from scipy.stats import beta  # type: ignore[import-untyped]

    lo = float(beta.ppf(0.025, k, n - k + 1)) if k > 0 else 0.0
    hi = float(beta.ppf(0.975, k + 1, n - k)) if k < n else 1.0
    return lo, hi


def _draws(truth: Any, exps: list[Any], term: str, noise: float, draws: int) -> tuple[int, int, int]:
    """``draws`` seeded recordings of ``truth`` on ``exps``, diagnosed: (F passed, named, wrong) counts."""
    import bouc_wen_id as bw

    f_k = n_k = wrong = 0
    for k in range(draws):
        recs = []
        for i, e in enumerate(exps):
            recs += bw.simulate(truth, e.plan(noise, seed=1000 * k + i))
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs)
        st = d.steps[0] if d.steps else None
        level = (0.5 if st is not None and st.targeted else 1.0) * 0.05
        fp = st is not None and any(
            t.term == term and math.isfinite(t.p_adjusted) and t.p_adjusted < level for t in st.trials
        )
        other = [t for t in d.named_terms if t != term]
        f_k += fp
        n_k += term in d.named_terms
        wrong += bool(other)
        print(f"  draw {k}: F {fp}, {d.status}, named {d.named_terms} ({time.perf_counter() - t0:.1f} s)")
        sys.stdout.flush()
    return f_k, n_k, wrong


def main(argv: Optional[list[str]] = None) -> int:
    import bouc_wen_id as bw
    from bouc_wen_id.planning import detection_power, naming_chance
    from bouc_wen_id.terms import TERMS

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plant", default="demo")
    ap.add_argument("--term", default=TERM)
    ap.add_argument("--size", type=float, default=SIZE)
    ap.add_argument("--budget", type=float, default=BUDGET)
    ap.add_argument("--draws", type=int, default=12)
    ap.add_argument("--min-experiments", type=int, default=3)
    ap.add_argument("--time", type=float, default=None, help="scale the plan to about this test time, s")
    ap.add_argument("--json", default=None, help="write the design, predictions and counts here")
    a = ap.parse_args(argv)
    prior = plant(a.plant)
    noise = float(LAB["noise_sd"])
    plan = bw.plan_detection(prior, a.budget, {a.term: a.size}, min_experiments=a.min_experiments, **LAB)
    exps = _at_time(list(plan.experiments), a.time) if a.time else list(plan.scaled(0.9))
    pred = detection_power(prior, exps, a.term, a.size, noise_sd=noise)
    name = naming_chance(prior, exps, a.term, a.size, noise_sd=noise)
    print(
        f"{a.plant}, {a.term} = {a.size:g}, min_experiments={a.min_experiments}: "
        f"{[(round(e.frequency, 2), e.periods) for e in exps]} time {pred.total_time:.0f} s, "
        f"power to detect {pred.power:.3f} (lam refit {pred.lam:.1f}), predicted chance to name "
        f"{name.chance:.3f} (weakest fold lam {name.weakest_fold:.2f}; a linear rival chosen instead "
        f"{name.rival_named:.3f})"
    )
    norm = prior.normalized()  # the planned size is in the alpha-normalised model's units
    truth = bw.WienerPlant(norm.linear, norm.hysteresis, (TERMS[a.term](a.size),))
    f_k, n_k, wrong = _draws(truth, exps, a.term, noise, a.draws)
    fl, fh = interval(f_k, a.draws)
    nl, nh = interval(n_k, a.draws)
    print(
        f"F passed {f_k}/{a.draws} (95 % {fl:.2f}-{fh:.2f}; predicted {pred.power:.2f}), named "
        f"{n_k}/{a.draws} (95 % {nl:.2f}-{nh:.2f}; predicted {name.chance:.2f}), wrong physics named "
        f"{wrong}/{a.draws}"
    )
    if a.json:
        out = {
            "plant": a.plant,
            "term": a.term,
            "size": a.size,
            "experiments": [e.to_dict() for e in exps],
            "power": pred.power,
            "naming": name.to_dict(),
            "draws": a.draws,
            "f_passed": f_k,
            "named": n_k,
            "wrong": wrong,
        }
        Path(a.json).write_text(json.dumps(out, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
