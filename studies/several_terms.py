"""Several large library terms at once (issue 18, the pair step of diagnosis/pairs.py).

Plants with two or three library terms through G of other kinds (resonant with a delay, first order) and
noise levels, diagnosed as a user would; prints the verdict and every set the pair step tried.

    PYTHONPATH=python python studies/several_terms.py readme3 1
    PYTHONPATH=python python studies/several_terms.py res_pl 3   # also readme_vp, res_vl, first_vp, outside
    PYTHONPATH=python python studies/several_terms.py kc_u_2p 3  # the revisit (revisit.py)
"""

from __future__ import annotations

import sys
import time
from typing import Any

import bouc_wen_id as bw
from bouc_wen_id.terms import Play, SensorLag, Stiffness, Term, Viscous

README_G = bw.TransferFunction([25.0], [1.0, 2.0, 25.0], delay=0.05)
README_F = [1, 2, 3, 4, 5, 6.5, 8]
#: name: (G, terms, frequencies, noise sd)
PLANTS: dict[str, tuple[Any, tuple[Term, ...], list[float], float]] = {
    "readme3": (README_G, (Viscous(0.05), Play(0.1), SensorLag(0.01)), README_F, 0.005),
    "readme_vp": (README_G, (Viscous(0.05), Play(0.1)), README_F, 0.005),
    "first_vp": (
        bw.TransferFunction([8.0], [1.0, 8.0]),
        (Viscous(0.04), Play(0.1)),
        [0.5, 1, 2, 3, 4, 6],
        0.01,
    ),
    "res_vl": (
        bw.TransferFunction([100.0], [1.0, 4.0, 100.0], delay=0.02),
        (Viscous(0.05), SensorLag(0.01)),
        README_F,
        0.008,
    ),
    "res_pl": (
        bw.TransferFunction([36.0], [1.0, 3.0, 36.0], delay=0.03),
        (Play(0.1), SensorLag(0.015)),
        [0.5, 1, 2, 3, 4, 5],
        0.01,
    ),
    # Two terms on u through a two-pole G without delay (poles 1.2 and 7 rad/s): 1/G is a polynomial, so
    # viscous damping on x passes its law at step 1 and the pair is found only by the revisit (revisit.py).
    "kc_u_2p": (
        bw.TransferFunction([12.6], [1.0, 8.2, 8.4]),
        (Stiffness(0.1), Viscous(0.02)),
        [0.6, 1, 1.5, 3, 4.5, 6],
        0.01,
    ),
}


def recordings(name: str, seed: int) -> list[Any]:
    hyst = bw.BoucWen(beta=1.6, gamma=0.4, mu=1.6, alpha=2.0)
    if name == "outside":  # a damping growing with the rate (outside the library) beside play
        g = PLANTS["res_pl"][0]
        out: list[Any] = []
        for k, f in enumerate([0.5, 1, 2, 3, 4, 5]):
            plan = bw.SinePlan(frequencies=[f], amplitudes=1.0, settle_periods=30, periods=40,
                               samples_per_period=512, noise_sd=0.01, seed=seed + k)  # fmt: skip
            out += bw.simulate(bw.WienerPlant(g, hyst, terms=(Viscous(0.02 * f), Play(0.1))), plan)
        return out
    g, terms, freqs, noise = PLANTS[name]
    spp = 1024 if name == "readme3" else 512  # the README's own plan for its plant
    plan = bw.SinePlan(frequencies=freqs, amplitudes=1.0, settle_periods=30, periods=40,
                       samples_per_period=spp, noise_sd=noise, seed=seed)  # fmt: skip
    return list(bw.simulate(bw.WienerPlant(g, hyst, terms=terms), plan))


def main() -> None:
    name, seed = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 3
    recs = recordings(name, seed)
    t0 = time.perf_counter()
    d = bw.diagnose(recs)
    named = [(t.term, f"{t.value:.4g}") for t in d.named]
    print(f"{name} seed {seed}: {time.perf_counter() - t0:.1f} s, {d.status}, named {named}")
    print("  ", d.verdict)
    for st in d.steps:
        print("   step", st.chosen, getattr(st, "pair", ()), "law failed:", st.law_failed)
        for p in getattr(st, "pairs", ()):
            if hasattr(p, "replaced"):  # the revisit's record (revisit.py)
                print("     revisit of", p.replaced, "pool", p.pool, "->", p.terms, p.outcome[:90])
            elif p.refused != "no fit":
                print("     set", p.terms, f"{p.cost:.4g}", [f"{v:.2g}" for v in p.law_p], p.refused[:90])


if __name__ == "__main__":
    main()
