"""Reviewer 35's distorted-drive cases and this session's additions, on reviewer 35's own simulator.

    PYTHONPATH=python python studies/review35_distorted.py CASE[:SEED] [...]

Needs reviewer 35's folder (``REVIEW35``, default /work/review35: sim35.py, run35.py). Adds G shapes (two real
poles; first order without delay; wn 4, Q 5 without delay) and a second harmonic of the input (sim35's input
patched: ``h2`` at phase -0.7, seen by the plant too). One JSON line per case: the verdict's head, the named
terms, the final chi2/dof.
"""

from __future__ import annotations

import json
import os
import sys
import warnings
from typing import Any

import numpy as np

sys.path.insert(0, os.environ.get("REVIEW35", "/work/review35"))
import bouc_wen_id as bw  # noqa: E402
import run35  # type: ignore[import-not-found]  # noqa: E402
import sim35  # type: ignore[import-not-found]  # noqa: E402

run35.G.update(
    {
        "twopole": ([6.0], [1.0, 5.0, 6.0], 0.0),
        "fo": ([4.0], [1.0, 4.0], 0.0),
        "res4": ([16.0], [1.0, 0.8, 16.0], 0.0),
    }
)
H2: dict[str, float] = {}


def _inp(t: Any, amp: float, om: float, clip: Any, delay: float) -> tuple[Any, Any, Any]:
    tt = t - delay
    h3, h2 = sim35.INPUT["h3"], H2.get("now", 0.0)
    a, b = 3 * om * tt + 0.4, 2 * om * tt - 0.7
    u = amp * (np.cos(om * tt) + sim35.INPUT["dc"] + h3 * np.cos(a) + h2 * np.cos(b))
    ud = -amp * om * (np.sin(om * tt) + 3 * h3 * np.sin(a) + 2 * h2 * np.sin(b))
    udd = -amp * om * om * (np.cos(om * tt) + 9 * h3 * np.cos(a) + 4 * h2 * np.cos(b))
    return u, ud, udd


def _case(cid: str, g: str, eff: dict[str, int], truth: str, h3: float = 0.0, h2: float = 0.0) -> None:
    run35.case(cid, g, "f5", "white", eff, truth, h3=h3)
    H2[cid] = h2


_case("null_h3tp", "twopole", {}, "adequate (h3 3 %, two real poles)", h3=0.03)
_case("cu_h3tp", "twopole", {"c_u": 10}, "viscous@u (h3 3 %, two real poles)", h3=0.03)
_case("null_h2fo0", "fo", {}, "adequate (h2 2 %, first order no delay)", h2=0.02)
_case("cu_h2fo0", "fo", {"c_u": 10}, "viscous@u (h2 2 %, first order no delay)", h2=0.02)
_case("null_h2r", "res_delay", {}, "adequate (h2 3 %, resonant + delay)", h2=0.03)
_case("cu_h2r", "res_delay", {"c_u": 10}, "viscous@u (h2 3 %, resonant + delay)", h2=0.03)
_case("null_h3r4", "res4", {}, "adequate (h3 3 %, wn 4 Q 5 no delay)", h3=0.03)
_case("kx_h3r", "res_delay", {"k_x": 10}, "stiffness@x (h3 3 %, resonant + delay)", h3=0.03)


def main(args: list[str]) -> None:
    sim35._inp = _inp
    for arg in args:
        cid, _, seed = arg.partition(":")
        if seed:
            run35.CASES[cid]["seed"] = int(seed)
        H2["now"] = H2.get(cid, 0.0)
        recs, eff = run35.build(cid)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs)
        f = d.final
        row = {"case": arg, "truth": eff, "named": [str(n) for n in d.named], "verdict": d.verdict[:240]}
        print(json.dumps({**row, "final_chi2_dof": round(f.cost / max(f.dof, 1), 3)}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
