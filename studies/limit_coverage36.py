"""Coverage of the stated 90 % detection limit on reviewer 36's generator (docs/diagnosis.md, "Coverage of
the 90 % value"): data made apart from the package and from the benches that shaped the limits.

Per cell (G shape, term, noise): for each null seed the detection limit is read from the diagnosis of a
null recording (no term), then the term is simulated at that stated 90 % value with fresh noise seeds, and
the term's own first-step test is checked (p adj below its step's level). The limit's own scatter from one
noisy null is part of what a user gets, so every draw pairs its own null with its own term recording.

G shapes: ``res`` 25/(s^2 + 2 s + 25) e^(-0.04 s) (resonant with delay, reviewer 36's default) and ``fo``
3/(s + 3) (first order). Terms: ``c_u`` (viscous on u), ``k_x`` (stiffness on x), ``c_x``, ``k_u``. Noise:
``white`` or ``ar0.8`` (AR(1), sd 0.01 both). Design f3a2 (1.2/2.8/5.5 rad/s at U 1.2 and 0.6), 8 periods
after 10 settling, 128 samples per period.

Usage: ``python studies/limit_coverage36.py G:TERM:NOISE [...] [--nulls 4] [--draws 4] [--first 0]
[--sim /work/review36]``. Prints one JSON line per draw and a total line.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import warnings
from typing import Any

import numpy as np

CODE = {"c_u": "viscous", "k_x": "stiffness@x", "c_x": "viscous@x", "k_u": "stiffness"}
GS = {"res": ([25.0], [1.0, 2.0, 25.0], 0.04), "fo": ([3.0], [1.0, 3.0], 0.0)}
OMS = [1.2, 2.8, 5.5, 1.2, 2.8, 5.5]
AMPS = [1.2, 1.2, 1.2, 0.6, 0.6, 0.6]
PERIODS, SETTLE, SAMPLES, SD = 8, 10, 128, 0.01


def recordings(g: str, eff: dict[str, float], noise: str, seed: int) -> list[Any]:
    import bouc_wen_id as bw
    import sim36  # type: ignore[import-not-found]

    num, den, delay = GS[g]
    spec = dict(num=num, den=den, delay=delay, beta=1.0, gamma=0.3, mu=1.5, eff=eff)
    rng = np.random.default_rng(seed)
    out = []
    for om, amp in zip(OMS, AMPS):
        t, u, y, _ = sim36.experiment(spec, om, amp, PERIODS, SETTLE, SAMPLES)
        out.append(
            bw.Recording(
                t, u, sim36.add_noise(noise, y, SD, rng), amplitude=amp, frequency=om, settle_periods=SETTLE
            )
        )
    return out


def diagnose(recs: list[Any]) -> Any:
    import bouc_wen_id as bw

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs)


def first_step(d: Any, code: str) -> tuple[bool, Any]:
    """Whether the term's own first-step test passed, and its F statistic."""
    st = d.steps[0] if d.steps else None
    if st is None:
        return False, None
    level = (0.5 if st.targeted else 1.0) * float(d.settings["alpha"])
    tr = next((t for t in st.trials if t.term == code), None)
    return tr is not None and tr.p_adjusted < level, None if tr is None else tr.statistic


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cells", nargs="+", help="G:TERM:NOISE")
    ap.add_argument("--nulls", type=int, default=4)
    ap.add_argument("--draws", type=int, default=4, help="term draws per null")
    ap.add_argument("--first", type=int, default=0, help="first null seed")
    ap.add_argument("--sim", default="/work/review36", help="folder holding reviewer 36's sim36.py")
    a = ap.parse_args()
    sys.path.insert(0, a.sim)
    passed = total = 0
    for cell in a.cells:
        g, term, noise = cell.split(":")
        code = CODE[term]
        for j in range(a.first, a.first + a.nulls):
            d0 = diagnose(recordings(g, {}, noise, 1000 + j))
            lim = next((x for x in d0.limits if x.term == code), None)
            if lim is None or not math.isfinite(lim.limit_90):
                row0 = {"cell": cell, "null": j, "limit_90": None, "status": d0.status}
                print(json.dumps(row0), flush=True)
                continue
            for s in range(a.draws):
                seed = 10_000 * (j + 1) + s
                ok, f = first_step(diagnose(recordings(g, {term: abs(lim.limit_90)}, noise, seed)), code)
                passed, total = passed + ok, total + 1
                row = {"cell": cell, "null": j, "seed": seed, "limit": lim.limit, "limit_90": lim.limit_90}
                row.update(null_status=d0.status, f_pass=ok, F=f)
                print(json.dumps(row), flush=True)
    print(json.dumps({"passed": passed, "total": total}), flush=True)


if __name__ == "__main__":
    main()
