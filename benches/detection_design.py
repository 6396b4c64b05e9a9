"""Designing to see it: the planned design against the bench's default design, on benches/generator.py's data.

The diagnosis bench misses some 10x sensor lags and series dashpots (docs/power.md): the plain model absorbs
all but a small non-centrality of them on its default design (five frequencies x two saturating amplitudes,
16 averaged periods, P = 128). Per G shape (resonant with a delay; first order) and term, this script takes a
seeded plant of benches/generator.py (its exact G, its own RK4 of the hysteresis and of the effect), sizes the
effect at 10x the averaged noise on the default design (the bench's sizing), then

- predicts the power of the diagnosis's test of the term on the default design
  (:func:`bouc_wen_id.planning.detection_power`), and plans a design of the SAME test time
  (:func:`bouc_wen_id.plan_detection`: the band of the default design, its largest amplitude, P = 128,
  the same settling) and predicts its power;
- draws ``--draws`` seeded noisy recordings of each design from the generator and diagnoses each: the term's
  own F-test passing at its level (what the power predicts), the term named, any detection (not "adequate").

Per row: predicted power, the F-test's empirical rate with its 95 % binomial (Wilson) interval, named and
detected rates, seconds per diagnosis.

``--cases sensor_lag:35014,...`` takes the plants of exactly those seeds (the diagnosis bench's missed
cases). ``--hint SEED,...`` checks the adequate verdict's design hint instead (:func:`hint_rows`).

Usage: ``python benches/detection_design.py [--draws 12] [--terms sensor_lag,series_dashpot]
[--shapes resonant,first] [--cases TERM:SEED,...] [--hint SEED,...] [--size 10] [--seed 11] [--workers 1]
[--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import replace
from pathlib import Path
from typing import Any, Optional

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import generator as gen  # noqa: E402  (benches/ on the path first)


def _prior(p: Any) -> Any:
    import bouc_wen_id as bw

    return bw.WienerPlant(
        bw.TransferFunction(list(p.num), list(p.den), p.delay), bw.BoucWen(p.beta, p.gamma, p.mu, 1.0)
    )


def _default(p: Any) -> list[Any]:
    from bouc_wen_id.planning import PlannedExperiment

    return [
        PlannedExperiment(float(w), float(u), gen.PERIODS, gen.P, gen.SETTLE)
        for w, u in zip(p.omegas, p.amplitudes)
    ]


def _plant(seed: int, shape: str) -> Any:
    """The first seed from ``seed`` whose plant has the shape (and, resonant, a delay)."""
    for s in range(seed, seed + 200):
        p = gen.make_plant(s, shape)
        if shape != "resonant" or p.delay > 0:
            return p
    raise RuntimeError(shape)


def _noise_free(p: Any, design: list[Any], name: str, value: float) -> Any:
    """Noise-free outputs (experiments x samples) of ``design`` on plant ``p`` with the effect at ``value``
    (the generator's run; the longest experiment's length, the others cut from it)."""
    om = np.array([e.frequency for e in design])
    amp = np.array([e.amplitude for e in design])
    q = replace(p, omegas=om, amplitudes=amp, levels=amp * np.abs(p.freqresp(om)), w0=np.zeros(om.size))
    total = max(gen.SETTLE + e.periods for e in design) * gen.P
    return gen.run(q, gen.Effect(name, "", np.array([value])), total=total)[0]


def _records(design: list[Any], y: Any, seed: int) -> list[Any]:
    """Noisy recordings of ``design`` from its noise-free outputs ``y`` (seeded white noise, 1 %)."""
    import bouc_wen_id as bw

    rng = np.random.default_rng([seed, 7])
    out = []
    for i, e in enumerate(design):
        n = (gen.SETTLE + e.periods) * gen.P
        t = np.arange(n) * (gen.TWO_PI / e.frequency / gen.P)
        out.append(
            bw.Recording(
                t,
                e.amplitude * np.cos(e.frequency * t),
                y[i, :n] + rng.normal(0.0, gen.NOISE_SD, n),
                e.amplitude,
                e.frequency,
                settle_periods=gen.SETTLE,
                metadata={"name": f"exp{i}"},
            )
        )
    return out


def _draw(job: tuple[list[Any], Any, str, int]) -> dict[str, Any]:
    import bouc_wen_id as bw

    design, y, name, seed = job
    recs = _records(design, y, seed)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(recs)
    f_pass, n_trials = False, 0
    if d.steps:
        st = d.steps[0]
        n_trials = len(st.trials)
        level = (0.5 if st.targeted else 1.0) * float(d.settings["alpha"])
        f_pass = any(
            t.term == name and math.isfinite(t.p_adjusted) and t.p_adjusted < level for t in st.trials
        )
    return {
        "f": f_pass,
        "named": name in d.named_terms,
        "detected": d.status != "adequate",
        "trials": n_trials,
        "seconds": time.perf_counter() - t0,
    }


def wilson(k: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """95 % Wilson interval of a binomial rate ``k / n``."""
    if n == 0:
        return math.nan, math.nan
    ph = k / n
    c = (ph + z * z / (2 * n)) / (1 + z * z / n)
    h = z * math.sqrt(ph * (1 - ph) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(c - h, 0.0), min(c + h, 1.0)


def row(
    shape: str, name: str, size: float, seed: int, draws: int, workers: int, least: int = 3
) -> list[dict[str, Any]]:
    """The default and the planned design of one shape and term: predictions and Monte-Carlo counts
    (``shape`` "seed": the plant of exactly ``seed``, whatever its shape)."""
    import bouc_wen_id as bw
    from bouc_wen_id.planning import detection_power

    p = gen.make_plant(seed) if shape == "seed" else _plant(seed, shape)
    value, got = gen.calibrate(p, name, "", size)
    prior, default = _prior(p), _default(p)
    budget = float(sum(e.duration for e in default))
    rate = gen.P * float(np.max(p.omegas)) / gen.TWO_PI
    kw: dict[str, Any] = {
        "band": (float(np.min(p.omegas)), float(np.max(p.omegas))),
        "max_amplitude": float(np.max(p.amplitudes)),
        "noise_sd": gen.NOISE_SD,
        "sample_rate": rate,
        "max_samples_per_period": gen.P,
        "settle_periods": gen.SETTLE,
        "baseline": default,
        "min_experiments": least,
    }
    t0 = time.perf_counter()
    plan = bw.plan_detection(prior, budget, {name: value}, **kw)
    plan_s = time.perf_counter() - t0
    designs = [
        ("default", default, detection_power(prior, default, name, value, noise_sd=gen.NOISE_SD)),
        ("planned", list(plan.experiments), plan.predicted),
    ]
    if plan.predicted.power < 0.9:  # the stated larger budget: the planned design's periods scaled
        big = list(plan.scaled(0.9))
        pred = detection_power(prior, big, name, value, noise_sd=gen.NOISE_SD)
        designs.append((f"planned {pred.total_time:.0f} s", big, pred))
    out = []
    for label, design, pred in designs:
        t1 = time.perf_counter()
        y = _noise_free(p, design, name, value) if draws else None  # --draws 0: the predictions alone
        gen_s = time.perf_counter() - t1
        jobs = [(design, y, name, 10**6 * (seed + 1) + k) for k in range(draws)]
        if workers > 1:
            with ProcessPoolExecutor(workers) as ex:
                res = list(ex.map(_draw, jobs))
        else:
            res = [_draw(j) for j in jobs]
        k = sum(r["f"] for r in res)
        lo, hi = wilson(k, draws)
        n = max(draws, 1)
        out.append(
            {
                "shape": p.shape,
                "term": name,
                "size": got,
                "value": value,
                "seed": p.seed,
                "design": label,
                "experiments": [[e.frequency, e.amplitude, e.periods] for e in design],
                "time": float(sum(e.duration for e in design)),
                "lam_linear": pred.lam_linear,
                "lam": pred.lam,
                "power": pred.power,
                "f_rate": k / n if draws else math.nan,
                "f_interval": [lo, hi],
                "within": lo <= pred.power <= hi,
                "named": sum(r["named"] for r in res) / n if draws else math.nan,
                "detected": sum(r["detected"] for r in res) / n if draws else math.nan,
                "trials": sorted({r["trials"] for r in res}),
                "seconds": float(np.mean([r["seconds"] for r in res])) if draws else math.nan,
                "plan_seconds": plan_s,
                "generator_seconds": gen_s,
                "budget_for_90": plan.budget_for(0.9),
            }
        )
    return out


def hint_rows(seed: int, draws: int, workers: int) -> list[dict[str, Any]]:
    """The adequate verdict's design hint, checked: a null recording of plant ``seed`` on the default design
    is diagnosed; its sensor lag's 50 % limit L50 and hint (every experiment's periods times f; one
    experiment's times s_j) are read; sensor lags of L50 are then drawn on the default design (the limit
    promises 50 %) and on the two hinted designs (90 % promised)."""
    import bouc_wen_id as bw
    from bouc_wen_id.planning import PlannedExperiment

    p = gen.make_plant(seed)
    default = _default(p)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(_records(default, _noise_free(p, default, "sensor_lag", 0.0), 10**6 + seed))
    lim = next((x for x in d.limits if x.term == "sensor_lag"), None)
    if d.status != "adequate" or lim is None or lim.hint is None:
        print(f"seed {seed}: {d.status}, no sensor-lag hint to check")
        return []
    h = lim.hint
    print(f"seed {seed} ({p.shape}): {d.verdict}")
    every = [replace(e, periods=math.ceil(h.periods_factor * e.periods)) for e in default]
    designs: list[tuple[str, list[PlannedExperiment], float]] = [
        ("default", default, 0.5),
        ("every", every, 0.9),
    ]
    if h.experiment >= 0:
        one = list(default)
        e = one[h.experiment]
        one[h.experiment] = replace(e, periods=math.ceil(h.experiment_factor * e.periods))
        designs.append((f"exp {h.experiment}", one, 0.9))
    out = []
    for label, design, promised in designs:
        y = _noise_free(p, design, "sensor_lag", lim.limit)
        jobs = [(design, y, "sensor_lag", 10**7 * (seed + 1) + k) for k in range(draws)]
        if workers > 1:
            with ProcessPoolExecutor(workers) as ex:
                res = list(ex.map(_draw, jobs))
        else:
            res = [_draw(j) for j in jobs]
        k = sum(r["f"] for r in res)
        lo, hi = wilson(k, draws)
        out.append(
            {
                "seed": seed,
                "shape": p.shape,
                "design": label,
                "tau": lim.limit,
                "time": float(sum(e.duration for e in design)),
                "promised": promised,
                "f_rate": k / draws,
                "f_interval": [lo, hi],
                "within": lo <= promised <= hi,
                "detected": sum(r["detected"] for r in res) / draws,
            }
        )
        r = out[-1]
        print(
            f"  {label:<8} tau {lim.limit:.3g} s  time {r['time']:7.1f} s  promised {promised:.2f}  "
            f"F rate {r['f_rate']:.2f} ({lo:.2f}-{hi:.2f})  detected {r['detected']:.2f}",
            flush=True,
        )
    return out


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=12)
    ap.add_argument("--terms", default="sensor_lag,series_dashpot")
    ap.add_argument("--shapes", default="resonant,first")
    ap.add_argument("--size", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument(
        "--cases",
        default="",
        help="TERM:SEED,... plants of exactly these seeds (e.g. the bench's missed cases sensor_lag:35014) "
        "instead of --shapes x --terms",
    )
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument(
        "--min-experiments", type=int, default=3, help="plan_detection's min_experiments (3, its default)"
    )
    ap.add_argument("--hint", default="", help="SEED,...: check the adequate verdict's design hint instead")
    a = ap.parse_args(argv)
    if a.hint:
        hints = [r for sd in a.hint.split(",") for r in hint_rows(int(sd), a.draws, a.workers)]
        if a.json is not None:
            a.json.write_text(json.dumps(hints, indent=1), encoding="utf-8")
        return 0
    rows: list[dict[str, Any]] = []
    print(
        f"{'shape':<9} {'term':<15} {'design':<14} {'time s':>7} {'lam1':>7} {'lam':>7} {'power':>6} "
        f"{'F rate':>6} {'95 % interval':>14} {'named':>6} {'detect':>6} {'s/diag':>6}"
    )
    jobs = [(shape, name, a.seed) for shape in a.shapes.split(",") for name in a.terms.split(",")]
    if a.cases:
        jobs = [("seed", c.split(":")[0], int(c.split(":")[1])) for c in a.cases.split(",")]
    for shape, name, seed in jobs:
        if True:
            for r in row(shape, name, a.size, seed, a.draws, a.workers, a.min_experiments):
                rows.append(r)
                lo, hi = r["f_interval"]
                print(
                    f"{r['shape']:<9} {r['term']:<15} {r['design']:<14} {r['time']:>7.1f} "
                    f"{r['lam_linear']:>7.1f} "
                    f"{r['lam']:>7.1f} {r['power']:>6.2f} {r['f_rate']:>6.2f} {f'{lo:.2f}-{hi:.2f}':>14} "
                    f"{r['named']:>6.2f} {r['detected']:>6.2f} {r['seconds']:>6.1f}",
                    flush=True,
                )
    inside = sum(r["within"] for r in rows)
    print(f"predicted power inside the empirical F-test rate's 95 % interval: {inside} of {len(rows)} rows")
    if a.json is not None:
        a.json.write_text(json.dumps(rows, indent=1), encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
