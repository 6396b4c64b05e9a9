"""The same samples diagnosed through both input paths (issue 18; review 34, problem 8).

Each case is simulated by review 34's own generator (``run34.build``: its RK4 plant, exact sensor lag, its
noise kinds, non-integer samples per period); the same samples are then given as Recordings (amplitude,
frequency and settle periods stated) and as Measurements (the lab path: amplitude, frequency and the
steady stretch estimated from the record). One JSON line per (case, seed): each path's status, final p
and named terms.

    PYTHONPATH=python:/work/review34 nice -n 10 python studies/lab_vs_recording.py \\
        --cases null_f5,cu_f5 --seeds 1-20 [--paths lab,rec] [--json F]
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from typing import Any

#: Cases: (G, design, noise, effects, samples per period). Effects in review 34's units (x its calibration).
CASES: dict[str, tuple[str, str, str, dict[str, float], float]] = {
    "null_f5": ("fo_delay", "f5", "white", {}, 128.0),
    "null_f3a2_nonint": ("res_delay", "f3a2", "white", {}, 100.37),
    "null_2p_laplace": ("two_pole", "f5", "laplace", {}, 128.0),
    "null_f5_ar": ("fo_delay", "f5", "ar0.5", {}, 128.0),
    "cu_f5": ("fo_delay", "f5", "white", {"c_u": 10.0}, 128.0),
    "kx_f3a2": ("two_pole", "f3a2", "white", {"k_x": 10.0}, 128.0),
    "kx_f3a2_nonint": ("two_pole", "f3a2", "white", {"k_x": 10.0}, 100.37),
    "mx_res_f5": ("res_delay", "f5", "white", {"m_x": 10.0}, 128.0),
    "kx_fo_nonint77": ("fo_delay", "f3a2", "white", {"k_x": 10.0}, 77.7),
    "null_fo_nonint77": ("fo_delay", "f3a2", "white", {}, 77.7),
    "cu_f5_nonint": ("fo_delay", "f5", "white", {"c_u": 10.0}, 100.37),
}


def _seeds(text: str) -> list[int]:
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def run_one(rc: Any, key: str, seed: int, paths: list[str]) -> dict[str, Any]:
    import bouc_wen_id as bw

    g, des, nz, eff, p = CASES[key]
    cid = f"lvr_{key}"
    rc.case(cid, g, des, nz, eff, key, P=p, seed=seed)
    recs, _ = rc.build(cid)
    out: dict[str, Any] = {"case": key, "seed": seed}
    for path in paths:
        items = (
            recs
            if path == "rec"
            else [
                bw.Measurement(r.t, r.u, r.y, nominal_frequency=r.frequency, name=f"e{i}")
                for i, r in enumerate(recs)
            ]
        )
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = bw.diagnose(items)
            out[path] = {
                "status": str(d.status),
                "p": round(float(d.final.p_value), 4),
                "dof": int(d.final.dof),
                "named": [f"{n.term}={n.value:.4g}+-{n.standard_error:.2g}" for n in d.named],
                "head": d.verdict.splitlines()[0][:160],
            }
        except Exception as exc:  # noqa: BLE001 - a study records every failure and goes on
            out[path] = {"error": f"{type(exc).__name__}: {exc}"[:200]}
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", default=",".join(CASES))
    ap.add_argument("--seeds", default="1-5")
    ap.add_argument("--paths", default="rec,lab")
    ap.add_argument(
        "--review-dir", default="/work/review34", help="folder of review 34's run34.py and sim.py"
    )
    ap.add_argument("--json", default=None, help="append the lines to this file too")
    a = ap.parse_args(argv)
    sys.path.insert(0, a.review_dir)
    import run34 as rc  # type: ignore[import-not-found]  # review 34's generator

    for key in a.cases.split(","):
        for seed in _seeds(a.seeds):
            line = json.dumps(run_one(rc, key, seed, a.paths.split(",")))
            print(line, flush=True)
            if a.json:
                with open(a.json, "a") as fh:
                    fh.write(line + "\n")


if __name__ == "__main__":
    main()
