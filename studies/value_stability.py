"""Does the value check (diagnosis/value_stability.py) flag true terms? Does it flag a drifting one?

In-library cases made two ways (the package's simulator with first-order and resonant+delay G, white and
AR(1) noise; benches/generator.py rows, white noise) should keep their status; plants outside the library
(a parallel stiffness that drifts slowly through each record, a slow creep state) are what it is for.

Run: ``PYTHONPATH=python OMP_NUM_THREADS=1 python studies/value_stability.py [case ...]`` (no argument:
every case). One line per case: status, named, unstable terms, the check's seconds and the diagnosis's.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id import terms as T

FIRST = bw.TransferFunction([1.0], [0.05, 1.0])
RESONANT = bw.TransferFunction([36.0], [1.0, 1.8, 36.0], delay=0.08)


def _plan(g: Any, om: np.ndarray, levels: tuple[float, ...], seed: int, noise: float, settle: int) -> Any:
    oms = np.repeat(om, len(levels))
    gain, _ = g.gain_phase(oms)
    amps = np.tile(levels, om.size) / gain
    return bw.SinePlan(
        oms,
        amps,
        settle_periods=settle,
        periods=16,
        samples_per_period=64,
        substeps=8,
        noise_sd=noise,
        seed=seed,
    )


def _ar1(recs: list[Any], seed: int, sd: float, phi: float = 0.8) -> list[Any]:
    """The recordings with AR(1) noise of stationary sd ``sd`` added (they were simulated noise-free)."""
    rng = np.random.default_rng([seed, 11])
    out = []
    for r in recs:
        e = rng.normal(0.0, sd * math.sqrt(1 - phi * phi), r.y.size)
        n = np.empty_like(e)
        n[0] = rng.normal(0.0, sd)
        for i in range(1, e.size):
            n[i] = phi * n[i - 1] + e[i]
        out.append(
            bw.Recording(r.t, r.u, r.y + n, r.amplitude, r.frequency, r.settle_periods, metadata=r.metadata)
        )
    return out


def package(g: Any, terms: tuple[Any, ...], seed: int, ar: bool, settle: int = 8) -> list[Any]:
    om = np.array([3.0, 9.0, 25.0]) if g is FIRST else np.array([3.0, 6.0, 9.0])
    plant = bw.WienerPlant(g, bw.BoucWen(0.7, 0.3, 1.8), terms=terms)
    recs = bw.simulate(plant, _plan(g, om, (0.8, 2.0), seed, 0.0 if ar else 0.01, settle))
    return _ar1(recs, seed, 0.01) if ar else recs


def outside(kind: str, seed: int) -> list[Any]:
    """First-order plant, no term; added here: ``drift`` a parallel stiffness on x whose value rises 60 %
    through each record (a warming device); ``creep`` y += c, c' = (0.3 x - c) / 5 s, 2 settle periods."""
    om = np.array([3.0, 9.0, 25.0])
    plant = bw.WienerPlant(FIRST, bw.BoucWen(0.7, 0.3, 1.8))
    recs = bw.simulate(plant, _plan(FIRST, om, (0.8, 2.0), seed, 0.01, 2 if kind == "creep" else 8))
    out = []
    for r in recs:
        x = np.asarray(r.x)
        t = np.asarray(r.t)
        if kind == "drift":
            add = 0.3 * (1.0 + 0.6 * t / t[-1]) * x
        else:
            add = np.zeros_like(x)
            dt = float(t[1] - t[0])
            for i in range(1, x.size):
                add[i] = add[i - 1] + dt * (0.3 * x[i - 1] - add[i - 1]) / 5.0
        out.append(
            bw.Recording(t, r.u, r.y + add, r.amplitude, r.frequency, r.settle_periods, metadata=r.metadata)
        )
    return out


def generator(name: str, place: str, seed: int) -> list[Any]:
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
    import generator as gen

    return list(gen.make_case("library", name, place, 8.0, seed).recordings)


CASES: dict[str, Callable[[], list[Any]]] = {
    "pkg-first-white-stiffness@x": lambda: package(FIRST, (T.StiffnessX(0.3),), 1, False),
    "pkg-first-white-viscous": lambda: package(FIRST, (T.Viscous(0.004),), 2, False),
    "pkg-first-white-offset": lambda: package(FIRST, (T.Offset(0.02),), 3, False),
    "pkg-first-ar1-stiffness@x": lambda: package(FIRST, (T.StiffnessX(0.3),), 4, True),
    "pkg-first-ar1-viscous": lambda: package(FIRST, (T.Viscous(0.004),), 5, True),
    "pkg-res-white-stiffness@x": lambda: package(RESONANT, (T.StiffnessX(0.3),), 6, False),
    "pkg-res-white-offset": lambda: package(RESONANT, (T.Offset(0.02),), 7, False),
    "pkg-res-ar1-stiffness@x": lambda: package(RESONANT, (T.StiffnessX(0.3),), 8, True),
    "gen-stiffness-x": lambda: generator("stiffness", "x", 9101),
    "gen-viscous-u": lambda: generator("viscous", "u", 9102),
    "gen-offset": lambda: generator("offset", "u", 9103),
    "gen-stiffness-u": lambda: generator("stiffness", "u", 9104),
    "outside-drift": lambda: outside("drift", 21),
    "outside-creep": lambda: outside("creep", 22),
}


def main(argv: list[str]) -> int:
    for name in argv or list(CASES):
        recs = CASES[name]()
        t0 = time.perf_counter()
        d = bw.diagnose(recs)
        wall = time.perf_counter() - t0
        info = d.settings.get("value_stability", {})
        moved = info.get("unstable", []) if isinstance(info, dict) else []
        worst = max((r["z"] for r in info.get("comparisons", []) if math.isfinite(r["z"])), default=math.nan)
        print(
            f"{name}: {d.status}; named {list(d.named_terms)}; unstable {moved}; max z {worst:.2f} "
            f"(threshold {info.get('z_threshold', math.nan):.2f}); check {info.get('seconds', 0.0):.2f} s "
            f"of {wall:.1f} s",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
