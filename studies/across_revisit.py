"""diagnose's revisits across conditions (diagnosis/across_revisit.py): per-level verdicts against the joint
structure with the revisits switched off (main's joint selection) and on.

Two effects at once, inertia on x and a sensor lag (review 33's mx_lag_30, named "viscous damping on u" by a
level's forward selection and fixed there by the rival revisit), at two or three conditions:

- ``--generator SEEDS``: benches/generator.py's plants (its exact G, its RK4 hysteresis; the two effects
  composed from its own pieces: the plain loop plus its inertia on x, seen through its exact lag), each
  effect sized ``--size`` averaged-noise sd alone; one plant per seed, its conditions ``--noise`` draws of
  the noise (the same plant recorded again); ``--shape two_pole``: review 33's G and band (20 / (s^2 + 12 s
  + 20), no delay, 1-7 rad/s) with the generator's loop and levels (``--one-level``: its higher one only);
- ``--review DIR --case CASE``: review 33's simulator (``DIR``: a copy of /work/review33's sim.py and
  run_case.py), the case at ``--noise`` draws.

Each line: the per-level verdicts' named terms, then the joint structure's, off and on, and the seconds of
each ``diagnose_across`` (the per-level diagnoses given, as studies/diagnose_real.py gives them).

    PYTHONPATH=python python studies/across_revisit.py --generator 1,2 --noise 11,12
    PYTHONPATH=python python studies/across_revisit.py --review /tmp/acrossrev --case mx_lag_30 --noise 1,2
    PYTHONPATH=python python studies/across_revisit.py --nulls 9001:9010 --noise 11,12
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def generator_groups(
    seed: int, noise: list[int], size: float, shape: str, one_level: bool = False
) -> tuple[list[Any], dict[str, Any]]:
    """One generator plant with inertia on x and a sensor lag, each ``size`` averaged-noise sd alone, recorded
    at each noise seed of ``noise``."""
    sys.path.insert(0, str(REPO / "benches"))
    import generator as G

    if shape == "two_pole":  # review 33's G (poles at 2 and 10 rad/s, no delay) and band, the seed's loop
        q = G.make_plant(seed, shape="first")
        num, den = np.array([20.0]), np.array([1.0, 12.0, 20.0])
        levels = G.X_LEVELS if not one_level else G.X_LEVELS[-1:]  # one: review 33's single amplitude
        om = np.repeat(np.array([1.0, 2.0, 3.5, 5.0, 7.0]), len(levels))
        lev = np.tile(np.asarray(levels), 5)
        g = np.abs(np.polyval(num, 1j * om) / np.polyval(den, 1j * om))
        p = replace(q, shape=shape, num=num, den=den, delay=0.0, omegas=om, amplitudes=lev / g, levels=lev)
        p = replace(p, w0=np.zeros(om.size))
    else:
        p = G.make_plant(seed, shape=shape or None)
    b = G.base(p)
    m, got_m = G.calibrate(p, "inertia", "x", size)
    tau, got_t = G.calibrate(p, "sensor_lag", "", size)
    ne = p.omegas.size
    eff = G.Effect("inertia", "x", np.array([m]))
    val = np.full((1, ne), m)
    wf = G._hysteresis(p, None, np.zeros((1, ne)), b)
    v = wf + G._parallel(p, eff, val, b.x[:, ::2], b.xd[:, ::2], b.xdd[:, ::2], b.grids)
    v = G._lag(v, np.full((1, ne), tau), b.h)
    y = np.ascontiguousarray(v[..., : -1 : G.SUBSTEPS])[0]
    truth = {"shape": p.shape, "m_x": m, "lag": tau, "size_m": got_m, "size_lag": got_t}
    return [G.recordings(p, y, s) for s in noise], truth


def review_groups(folder: Path, case: str, noise: list[int]) -> tuple[list[Any], dict[str, Any]]:
    """Review 33's case ``case`` at each noise seed (its run_case.build)."""
    sys.path.insert(0, str(folder))
    import run_case as rc

    out, eff = [], {}
    for s in noise:
        rc.CASES[case]["seed"] = s
        recs, eff = rc.build(case)
        out.append(recs)
    return out, {k: float(v) for k, v in eff.items()}


def compare(groups: list[Any]) -> dict[str, Any]:
    """Per-level diagnoses, then diagnose_across with the revisits off and on."""
    import bouc_wen_id as bw
    from bouc_wen_id.diagnosis import revisit, rival_revisit

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g) for g in groups]
        out: dict[str, Any] = {"levels": [sorted(t.term for t in d.named) for d in own]}
        for on in (False, True):
            revisit.ENABLED = rival_revisit.ENABLED = on
            t0 = time.perf_counter()
            a = bw.diagnose_across(groups, [float(i) for i in range(len(groups))], per_condition=own)
            key = "on" if on else "off"
            out[key] = {"named": sorted(a.named), "status": a.status, "seconds": time.perf_counter() - t0}
            out[key]["verdict"] = a.verdict
    out["level_verdicts"] = [d.verdict for d in own]
    return out


def nulls(seeds: list[int], noise: list[int]) -> None:
    """Null sets across (benches/generator.py's null plants, with their low-amplitude experiment, each at the
    noise seeds ``noise``): ``diagnose_across`` with the revisits on; a line each, with the revisits'
    records (none: the joint steps are main's)."""
    import bouc_wen_id as bw
    from bouc_wen_id.diagnosis import revisit

    sys.path.insert(0, str(REPO / "benches"))
    import generator as G

    for seed in seeds:
        p = G.make_plant(seed, low_amplitude=True)
        y = G.run(p, G.Effect())[0]
        groups = [G.recordings(p, y, s) for s in noise]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = bw.diagnose_across(groups, [float(i) for i in range(len(groups))])
        row = {"null": seed, "shape": p.shape, "named": list(a.named), "status": a.status}
        row |= {"revisits": len(revisit.records(a.steps)), "seconds": a.seconds}
        print(json.dumps(row), flush=True)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--generator", default="", help="plant seeds of benches/generator.py")
    ap.add_argument("--shape", default="", help="G: first, resonant, flat (default: the seed's), two_pole")
    ap.add_argument("--size", type=float, default=30.0)
    ap.add_argument("--one-level", action="store_true", help="two_pole: one latent level, as review 33's")
    ap.add_argument("--review", type=Path, default=None, help="a copy of review 33's sim.py, run_case.py")
    ap.add_argument("--case", default="mx_lag_30")
    ap.add_argument("--noise", default="1,2", help="noise seeds: one condition each")
    ap.add_argument("--nulls", default="", help="null plant seeds of benches/generator.py (first:last)")
    args = ap.parse_args(argv)
    noise = [int(s) for s in args.noise.split(",")]
    if args.nulls:
        first, last = (int(v) for v in args.nulls.split(":"))
        nulls(list(range(first, last + 1)), noise)
    runs: list[tuple[str, list[Any], dict[str, Any]]] = []
    if args.review is not None:
        runs.append((f"review {args.case}", *review_groups(args.review, args.case, noise)))
    for s in [int(v) for v in args.generator.split(",") if v]:
        runs.append((f"generator {s}", *generator_groups(s, noise, args.size, args.shape, args.one_level)))
    for name, groups, truth in runs:
        row = {"run": name, "noise": noise, "truth": truth, **compare(groups)}
        print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
