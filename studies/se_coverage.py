"""Do the quoted standard errors say how sure the named values are? A seeded coverage study.

For each library term that the diagnosis names with ``value +- se``, one plant with that term hidden is
recorded ``--seeds N`` times with fresh white noise (the noise-free run made once), each draw is diagnosed,
and the table gives, over the draws where the term was named:

- ``ratio``: the scatter of the named value (sample sd) over the median quoted se; 1 when the se is right,
  with the 95 % interval ``sqrt(chi2_{n-1}(q) / (n - 1))`` of the ratio for n draws (``lo``-``hi``);
- ``cover``: the share of draws with ``|value - truth| < 2 se`` (0.95 for an unbiased value and a right se;
  a first-order model's bias lowers it although the ratio is right).

Two generators: ``bench`` (benches/generator.py, the case builder benches/diagnosis.py uses: ``make_plant``,
``_calibrate``, ``recordings``) and ``review`` (the review-33 simulator ``sim.py`` in ``--review-dir``, its
own RK4, G and design ``f5``). Sizes are in averaged-noise sd (each generator's own calibration). Cheap
enough for a quiet machine: ``nice -n 10 python studies/se_coverage.py --seeds 8``.

    PYTHONPATH=python nice -n 10 python studies/se_coverage.py --seeds 8 --gens bench,review \\
        --terms degradation,viscous --shape resonant --g two_pole
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import sys
import time
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Any, Optional

import numpy as np

HERE = Path(__file__).resolve().parent
#: term label -> (library code name, bench (name, place), review-33 effect key or None)
TERMS: dict[str, tuple[str, tuple[str, str], Optional[str]]] = {
    "degradation": ("degradation", ("degradation", ""), "degr"),
    "stiffness_degradation": ("stiffness_degradation", ("stiffness_degradation", ""), None),
    "viscous@u": ("viscous", ("viscous", "u"), "c_u"),
    "viscous@x": ("viscous@x", ("viscous", "x"), "c_x"),
    "stiffness@u": ("stiffness", ("stiffness", "u"), "k_u"),
    "inertia@u": ("inertia", ("inertia", "u"), "m_u"),
    "offset": ("offset", ("offset", ""), "offset"),
    "play": ("play", ("play", ""), "play"),
    "sensor_lag": ("sensor_lag", ("sensor_lag", ""), "lag"),
    "series_dashpot": ("series_dashpot", ("series_dashpot", ""), "dashpot"),
}


def ratio_interval(n: int, level: float = 0.95) -> tuple[float, float]:
    """The ``level`` interval of (sample sd) / (true sd) for ``n`` normal draws."""
    from scipy.stats import chi2  # type: ignore[import-untyped]

    k = n - 1
    if k < 1:
        return math.nan, math.nan
    a = (1.0 - level) / 2.0
    return math.sqrt(chi2.ppf(a, k) / k), math.sqrt(chi2.ppf(1.0 - a, k) / k)


def bench_draws(
    name: str, place: str, size: float, plant_seed: int, shape: str, seeds: int, first: int = 1
) -> Any:
    """(truth, [recordings per draw]) from benches/generator.py, draws ``first`` .. ``first + seeds - 1``."""
    sys.path.insert(0, str(HERE.parent / "benches"))
    import generator as gen

    p = gen.make_plant(plant_seed, shape=shape)
    value, _, y = gen._calibrate(p, name, place, size, gen.base(p))
    return value, (gen.recordings(p, y, 1000 + k) for k in range(first, first + seeds))


def review_draws(
    key: str, size: float, g: str, review_dir: str, seeds: int, first: int = 1, sub: int = 3
) -> Any:
    """(truth, [recordings per draw]) from the review-33 simulator (sim.py, run_case.py's G and design),
    RK4 at ``sub`` steps per sample (its play switches at a step, so its width is wider by about the
    distance x travels in half a step: ``--review-sub`` shows that bias shrink)."""
    sys.path.insert(0, review_dir)
    import bouc_wen_id as bw
    import run_case as rc
    from sim import Plant, calibrate, noise, simulate

    num, den, delay = rc.G[g]
    oms, amps, pers = rc.DES["f5"]
    base = Plant(num, den, delay, 1.0, 0.3, 1.5, 1.0, {})
    value = calibrate(base, key, size, oms, amps, rc.SD, float(np.mean(pers)), rc.TRIAL[key])
    plant = Plant(num, den, delay, 1.0, 0.3, 1.5, 1.0, {key: value})
    ts, us, ys, _ = simulate(plant, oms, amps, np.array(pers), 15, P=128, sub=sub)

    def draw(k: int) -> list[Any]:
        rng = np.random.default_rng([k, 33])
        return [
            bw.Recording(
                t,
                u,
                noise("white", y, rc.SD, rng, 128, oms[i]),
                amplitude=amps[i],
                frequency=oms[i],
                settle_periods=15,
            )
            for i, (t, u, y) in enumerate(zip(ts, us, ys))
        ]

    return value, (draw(k) for k in range(first, first + seeds))


def blind_draws(code: str, size: float, seed: int, design: str, seeds: int, first: int = 1) -> Any:
    """(the blind case's value, [items per draw]) from benches/blind.py's generator (written apart from
    ours): its case ``seed`` with ``code`` at ``size``, white noise, the experiment ``design``
    (``first_order``: a first-order G; "" the seed's own); each draw adds fresh white noise at the case's
    level to the same noise-free outputs and reads the lab's CSV files back with ``bw.load``, as blind.py
    does. The value is in blind's units (its element's alpha), not necessarily the library's (play's is
    converted: times alpha); read ``ratio``, not ``cover``, when ``mean/truth`` is not near 1."""
    import tempfile

    sys.path.insert(0, str(HERE.parent / "benches"))
    import blind
    import bouc_wen_id as bw

    seen: dict[str, Any] = {}
    original = blind.add_noise

    def spy(y: Any, kind: str, pct: float, rng: Any, drift: float = blind.DRIFT, periods: Any = None) -> Any:
        seen.update(y=y, pct=pct, periods=periods)  # the last call: the outputs with the effect
        return original(y, kind, pct, rng, drift, periods)

    blind.add_noise = spy
    try:
        made = blind.make_case(blind.Case(code, size, 0, seed, "white", blind.DRIFT, design or None))
    finally:
        blind.add_noise = original
    if made["info"]["design"] in ("fixed_rate", "clipped"):
        raise SystemExit(f"blind seed {seed}: design {made['info']['design']} adds input noise; pick another")

    def draw(k: int) -> list[Any]:
        rng = np.random.default_rng([k, 35])
        ym, _ = blind.add_noise(seen["y"], "white", seen["pct"], rng, periods=seen["periods"])
        with tempfile.TemporaryDirectory() as tmp:
            paths = []
            for i, (e, u, y) in enumerate(zip(made["exps"], made["u"], ym)):
                paths.append(Path(tmp) / f"run_{i:02d}.csv")
                blind.write_csv(paths[-1], e, u, y)
            return list(bw.load(paths))

    value = float(made["info"]["value"])
    if code == "play":  # blind's half-width is in its x; the library's x is alpha x (w's slope 1 at reversal)
        value *= float(made["info"]["alpha"])
    return value, (draw(k) for k in range(first, first + seeds))


@contextlib.contextmanager
def _before_se(seen: list[float]) -> Iterator[None]:
    """Record the drift term's se as quoted before session 34 (the blocks' or the refinement's, without the
    steady fit's share, diagnosis/drift_se.py) while diagnosing: the value is the same, only the se grew."""
    from bouc_wen_id.diagnosis import drift_se

    original = drift_se.added

    def spy(deg: Any, *args: Any) -> Any:
        seen.append(float(deg.standard_error))
        return original(deg, *args)

    drift_se.added = spy
    try:
        yield
    finally:
        drift_se.added = original


def study(label: str, gen_name: str, args: argparse.Namespace) -> Optional[dict[str, Any]]:
    """One row: the term's draws diagnosed, the named values and ses."""
    import bouc_wen_id as bw

    code, (bname, bplace), rkey = TERMS[label]
    t0 = time.time()
    if gen_name == "bench":
        truth, draws = bench_draws(
            bname, bplace, args.size, args.plant_seed, args.shape, args.seeds, args.first_seed
        )
        where = f"bench {args.shape} plant {args.plant_seed}"
    elif gen_name == "blind":
        truth, draws = blind_draws(
            code, args.size, args.blind_seed, args.blind_design, args.seeds, args.first_seed
        )
        where = f"blind {args.blind_design or 'seed'} {args.blind_seed}"
    else:
        if rkey is None:
            return None
        truth, draws = review_draws(
            rkey, args.size, args.g, args.review_dir, args.seeds, args.first_seed, args.review_sub
        )
        where = f"review {args.g}" + (f" sub {args.review_sub}" if args.review_sub != 3 else "")
    vals, ses, before, missed, sets = [], [], [], 0, []
    for recs in draws:
        seen: list[float] = []
        with warnings.catch_warnings(), _before_se(seen):
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs, candidates=[code] if args.only_term else None)
        got = [t for t in d.named if t.term == code]
        sets.append([t.term for t in d.named])  # what was named beside it (a set that moves the value)
        if not got:
            missed += 1
            continue
        vals.append(float(got[0].value))
        ses.append(float(got[0].standard_error))
        before.append(seen[-1] if seen and code in ("degradation", "stiffness_degradation") else ses[-1])
    n = len(vals)
    v, s = np.array(vals), np.array(ses)
    ratio = float(np.std(v, ddof=1) / np.median(s)) if n >= 2 else math.nan
    cover = float(np.mean(np.abs(v - truth) < 2.0 * s)) if n else math.nan
    lo, hi = ratio_interval(n)
    old = float(np.std(v, ddof=1) / np.median(before)) if n >= 2 else math.nan
    return dict(
        term=label,
        gen=where,
        size=args.size,
        truth=truth,
        named=n,
        missed=missed,
        ratio=ratio,
        ratio_before=old,
        lo=lo,
        hi=hi,
        cover=cover,
        mean=float(v.mean()) if n else math.nan,
        median_se=float(np.median(s)) if n else math.nan,
        values=vals,
        ses=ses,
        named_sets=sets,
        seconds=round(time.time() - t0, 1),
    )


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8, help="noise draws per term (>= 3)")
    ap.add_argument("--terms", default=",".join(TERMS), help="comma list of " + ",".join(TERMS))
    ap.add_argument("--gens", default="bench,review", help="comma list of bench, review, blind")
    ap.add_argument("--size", type=float, default=30.0, help="effect size in averaged-noise sd")
    ap.add_argument("--shape", default="resonant", help="bench G: first (with a delay), resonant, flat")
    ap.add_argument("--plant-seed", type=int, default=3303, help="the bench plant's seed")
    ap.add_argument("--g", default="two_pole", help="review G: two_pole, fo_delay, res_delay, ...")
    ap.add_argument("--review-dir", default="/work/review33", help="folder of the review-33 sim.py")
    ap.add_argument("--first-seed", type=int, default=1, help="the first noise draw (more draws, run apart)")
    ap.add_argument("--review-sub", type=int, default=3, help="review sim's RK4 steps per sample")
    ap.add_argument("--blind-seed", type=int, default=35, help="benches/blind.py's case seed")
    ap.add_argument("--blind-design", default="first_order", help="blind.py's design ('' the seed's own)")
    ap.add_argument(
        "--only-term", action="store_true", help="diagnose with the term as the only candidate (no other set)"
    )
    ap.add_argument("--json", default="", help="append each row as a JSON line to this file")
    args = ap.parse_args(argv)
    if args.seeds < 3:
        ap.error("--seeds must be >= 3")
    unknown = [t for t in args.terms.split(",") if t not in TERMS]
    if unknown:
        ap.error(f"unknown terms {unknown}; known: {list(TERMS)}")
    print(
        f"{'term':22s} {'generator':26s} {'named':>5s} {'ratio':>6s} {'before':>6s} {'95% if right':>12s} "
        f"{'cover2se':>8s} {'mean/truth':>10s} {'median se':>10s}"
    )
    for gen_name in args.gens.split(","):
        for label in args.terms.split(","):
            row = study(label, gen_name, args)
            if row is None:
                continue
            print(
                f"{row['term']:22s} {row['gen']:26s} {row['named']:2d}/{args.seeds:<2d} {row['ratio']:6.2f} "
                f"{row['ratio_before']:6.2f} "
                f"{row['lo']:5.2f}-{row['hi']:5.2f}  {row['cover']:8.2f} {row['mean'] / row['truth']:10.4f} "
                f"{row['median_se']:10.3g}",
                flush=True,
            )
            if args.json:
                with open(args.json, "a") as fh:
                    fh.write(json.dumps(row) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
