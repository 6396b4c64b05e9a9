"""Coverage of the stated 90 % detection limit (docs/diagnosis.md, "Coverage of the 90 % value"): per design
and term, the detection limit read from a null recording's diagnosis, then the term simulated at that 90 %
value with noise seeds 0..N-1; counts the term's own first-step test passing (p adj below its step's level),
and records its F statistic: at the true 90 % value ``sqrt(F)`` exceeds ``z_c`` in 90 % of the seeds, so
the mean of ``F`` against ``(z_c + 1.28)^2 + 1`` says whether the stated noncentrality was reached.

Data from reviewer 34's simulator (``sim.py``, written apart from the package; --sim) through
studies/named_rate.py's designs. Prints one JSON line per case and a total line.

Usage: ``python studies/limit_coverage.py DESIGN:TERM [DESIGN:TERM ...] [--seeds 8] [--sim /work/review34]``
(designs f1a6, f1a3fo, f2res, f5res; terms k_x, k_u, c_u, c_x, f_x, f_u, m_u, m_x).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

import named_rate  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cells", nargs="+", help="DESIGN:TERM")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--sim", default="/work/review34", help="folder holding reviewer 34's sim.py")
    a = ap.parse_args()
    sys.path.insert(0, a.sim)
    passed = total = 0
    for cell in a.cells:
        des, term = cell.split(":")
        code = named_rate.CODE[term]
        t0 = time.time()
        d0 = named_rate.diagnose(named_rate.recordings(des, {}, 1000))
        null_s = time.time() - t0
        lim = next((x for x in d0.limits if x.term == code), None)
        if lim is None or not math.isfinite(lim.limit_90):
            print(json.dumps({"cell": cell, "limit_90": None}), flush=True)
            continue
        for s in range(a.seeds):
            d = named_rate.diagnose(named_rate.recordings(des, {term: lim.limit_90}, s))
            st = d.steps[0] if d.steps else None
            level = (0.5 if st is not None and st.targeted else 1.0) * float(d.settings["alpha"])
            tr = next((t for t in st.trials if t.term == code), None) if st is not None else None
            ok = tr is not None and tr.p_adjusted < level
            passed, total = passed + ok, total + 1
            row = {
                "cell": cell,
                "limit": lim.limit,
                "limit_90": lim.limit_90,
                "named_90": lim.named_90,
                "null_s": round(null_s, 1),
                "seed": s,
                "f_pass": ok,
                "F": None if tr is None else tr.statistic,
                "z_c2": None if lim.level <= 0 else _zc2(lim.level, lim.one_sided),
                "named": code in d.named_terms,
            }
            print(json.dumps(row), flush=True)
    print(json.dumps({"passed": passed, "total": total}), flush=True)


def _zc2(level: float, one_sided: bool) -> float:
    from scipy.special import ndtri  # type: ignore[import-untyped]

    return float(ndtri(1.0 - (level if one_sided else level / 2))) ** 2


if __name__ == "__main__":
    main()
