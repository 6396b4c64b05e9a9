"""Coverage of the stated 90 % detection limit (docs/diagnosis.md, "Coverage of the 90 % value"): per design
and term, the detection limit read from a null recording's diagnosis, then the term simulated at that 90 %
value with noise seeds 0..N-1; counts the term's own first-step test passing (p adj below its step's level),
and records its F statistic: at the true 90 % value ``sqrt(F)`` exceeds ``z_c`` in 90 % of the seeds, so
the mean of ``F`` against ``(z_c + 1.28)^2 + 1`` says whether the stated noncentrality was reached.

Data from reviewer 34's simulator (``sim.py``, written apart from the package; --sim) through
studies/named_rate.py's designs. Prints one JSON line per case and a total line.

Usage: ``python studies/limit_coverage.py DESIGN:TERM [DESIGN:TERM ...] [--seeds 8] [--first 0]
[--sim /work/review34] [--refit]`` (designs f1a6, f1a3fo, f2res, f5res; terms k_x, k_u, c_u, c_x, f_x, f_u,
m_u, m_x). ``--refit``: each row also holds the plain model and the plain model plus the term refitted
(``fit_from``, ``fit_with``) on the diagnosis's own averaged experiments, and that F (``refit_F``), the plain
chi2 and its dof: whether the selection's machinery reproduces its own statistic.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

import named_rate  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("cells", nargs="+", help="DESIGN:TERM")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--first", type=int, default=0, help="first noise seed")
    ap.add_argument("--sim", default="/work/review34", help="folder holding reviewer 34's sim.py")
    ap.add_argument("--refit", action="store_true", help="refit on the diagnosis's own experiments")
    a = ap.parse_args()
    seen = _capture() if a.refit else {}
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
        for s in range(a.first, a.first + a.seeds):
            seen.clear()
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
            if a.refit and st is not None:
                row.update(_refit(seen, st, code))
            print(json.dumps(row), flush=True)
    print(json.dumps({"passed": passed, "total": total}), flush=True)


def _capture() -> dict[str, Any]:
    """The averaged experiments and substeps the diagnosis hands to its detection limits, kept per run."""
    import bouc_wen_id.diagnosis.run as run

    seen: dict[str, Any] = {}
    orig = run.detection_limits

    def keep(exps: Any, base: Any, steps: Any, *args: Any, **kw: Any) -> Any:
        seen.update(exps=exps, substeps=args[3], base=base)
        return orig(exps, base, steps, *args, **kw)

    run.detection_limits = keep  # type: ignore[assignment]
    return seen


def _refit(seen: dict[str, Any], st: Any, code: str) -> dict[str, Any]:
    from bouc_wen_id.diagnosis.fitting import fit_from, fit_with

    if "exps" not in seen:
        return {"refit_F": None}
    exps, sub = seen["exps"], seen["substeps"]
    base = st.base if st.base is not None else seen["base"]
    plain = fit_from(exps, base.params, sub) or base
    both = fit_with(exps, plain, code, sub)
    if both is None:
        return {"refit_F": None}
    dof = sum(e.ybar.size for e in exps) - len(both.params.values) - 3 - 2 * len(exps)
    return {"refit_F": (plain.cost - both.cost) / (both.cost / dof), "plain_chi2": plain.cost, "dof": dof + 1}


def _zc2(level: float, one_sided: bool) -> float:
    from scipy.special import ndtri  # type: ignore[import-untyped]

    return float(ndtri(1.0 - (level if one_sided else level / 2))) ** 2


if __name__ == "__main__":
    main()
