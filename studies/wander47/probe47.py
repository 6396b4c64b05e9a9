"""Per recording, the smooth curve wander_curve.py would fit to the period means (wander47 README).

    PYTHONPATH=python python studies/wander47/probe47.py SEED0 SEED1 [NOISE]  # design C, sim45's wander
    PYTHONPATH=python:tests python studies/wander47/probe47.py walk SEED0 SEED1  # test_diagnosis_baseline's

Per seed: which wander path fires, and per recording the curve's degree, its chi-square / dof and p (a
``*`` where it is taken, p >= CURVE_ALPHA; else the walk's steps).
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).parents[1] / "review45"))
import drive45 as dv  # noqa: E402
import sim45 as s  # noqa: E402
from bouc_wen_id.diagnosis import baseline, dc_wander, wander_curve, zero_drift  # noqa: E402

PERIODS = (6, 30, 6, 30, 30, 6, 30, 6)


def line(tag: str, recs: list[Any]) -> None:
    lv = 0.05 / 20
    w, z, c = baseline.detect(recs, lv), zero_drift.detect(recs, lv), dc_wander.detect(recs, lv)
    path = "baseline" if w else "zero_drift" if z else "dc_wander" if c else "none"
    cells = []
    for rec in recs:
        rows, _, _ = wander_curve._rows(rec)
        got = wander_curve.fit(rows)
        if got is None:
            cells.append("-")
            continue
        d, chi2, dof, p = got
        cells.append(f"{d}:{chi2:.0f}/{dof}:{p:.2g}{'*' if p >= wander_curve.CURVE_ALPHA else ''}")
    print(tag, path, " ".join(cells), flush=True)


def main(s0: int, s1: int, kind: str = "wander") -> None:
    p, d, _ = dv.scaled("C")
    d = replace(d, periods=PERIODS)
    runs = s.run(p, d)
    for seed in range(s0, s1):
        line(str(seed), s.recordings(runs, d, s.Noise(kind, dv.SD), seed))


def walks(s0: int, s1: int) -> None:
    sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))
    from test_diagnosis_baseline import _recs

    for seed in range(s0, s1):
        line(f"walk {seed}", _recs("walk", seed))


if __name__ == "__main__":
    if sys.argv[1] == "walk":
        walks(int(sys.argv[2]), int(sys.argv[3]))
    else:
        main(int(sys.argv[1]), int(sys.argv[2]), *sys.argv[3:4])
