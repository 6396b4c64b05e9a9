"""The named value against the truth where some inputs are clipped (diagnosis/clean_value.py, session 34).

Runs reviewer 33's simulator and case registry (``/work/review33``: ``sim.py``, ``run_case.py``; put that
directory on ``PYTHONPATH``) at the seeds given, with three more clipped cases registered here, and prints
per named term the quoted value and standard error, the truth, the pooled fit's value and standard error
(``Diagnosis.final_fit``), and both in standard errors from the truth::

    PYTHONPATH=$PWD/python:/work/review33 python studies/clean_values.py clip_cu 1,2,3
    PYTHONPATH=$PWD/python:/work/review33 python studies/clean_values.py clip_cx_res 1,2,3
"""

from __future__ import annotations

import json
import sys
import time
import warnings

import bouc_wen_id as bw
import run_case as rc  # reviewer 33's registry (not in this repository)
from bouc_wen_id.diagnosis.fitting import Scale, physical

#: The reviewer's effect keys and the library's code names.
MAP = {
    "c_u": "viscous",
    "k_u": "stiffness",
    "m_u": "inertia",
    "f_u": "coulomb",
    "k_x": "stiffness@x",
    "c_x": "viscous@x",
    "m_x": "inertia@x",
    "f_x": "coulomb@x",
    "lag": "sensor_lag",
    "offset": "offset",
}

rc.case("clip_cu_fo", "fo_delay", "f3a2", "white", {"c_u": 10}, "viscous@u (clipped)",
        clip=[0.9, None, 0.85, None, None, None])  # fmt: skip
rc.case("clip_kx_2p", "two_pole", "f8", "ar0.5", {"k_x": 10}, "stiffness@x (clipped)",
        clip=[None, 0.9, None, None, 0.85, None, None, 0.9])  # fmt: skip
rc.case("clip_cx_res", "res_delay", "f3a2", "white", {"c_x": 10}, "viscous@x (clipped)",
        clip=[None, None, 0.9, None, None, 0.85])  # fmt: skip


def main(cid: str, seeds: list[int]) -> None:
    for sd in seeds:
        rc.CASES[cid]["seed"] = sd
        recs, eff = rc.build(cid)
        t0 = time.time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs)
        s = Scale(d.settings["scale"]["y"], d.settings["scale"]["u"])
        rows = []
        for t in d.named:
            truth = next((v for k, v in eff.items() if MAP.get(k) == t.term), None)
            row: dict[str, object] = dict(term=t.term, value=t.value, se=t.standard_error, truth=truth)
            if t.term in d.final_fit.params.terms:
                pv, pse = physical(d.final_fit, s, t.term)
                row.update(pooled=pv, pooled_se=pse)
                if truth is not None:
                    row.update(z=round((t.value - truth) / t.standard_error, 2))
                    row.update(z_pooled=round((pv - truth) / pse, 2))
            rows.append(row)
        said = [c for c in d.verdict.split("; ") if c.startswith("the values named")]
        out = dict(case=cid, seed=sd, status=d.status, rows=rows, clause=said[0] if said else "")
        print(json.dumps({**out, "seconds": round(time.time() - t0, 1)}), flush=True)


if __name__ == "__main__":
    main(sys.argv[1], [int(x) for x in sys.argv[2].split(",")])
