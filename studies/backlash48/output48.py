"""Session 48 (backlash48): the play on the measured output (``play@output``) on data made apart from the
library, the bench's play rows and nulls, and the CPU per diagnosis.

Cases (each one ``bw.diagnose`` on ``Recording`` objects, as a user's files):

- ``out``: the bench's independent generator (``benches/generator.py``: G solved exactly, its own RK4 of the
  hysteresis, its own noise) for a plant of shape ``first`` or ``resonant`` (with a delay), its plain output
  then seen through a play of half-width c at the samples (:func:`played`, written here), c sized so that its
  contribution is 10x or 30x the averaged noise sd (the bench's size measure);
- ``play``: the bench's play row (``make_case("library", "play", ...)``, play on x);
- ``null``: the bench's null row.

Prints one JSON line per case: names, alternatives' kinds, the verdict's head, the value of play@output
with its se where named, CPU seconds of the diagnosis (``time.process_time``).

    PYTHONPATH=python:benches python studies/backlash48/output48.py out 10 first 0   # kind size shape seed
    PYTHONPATH=python:benches python studies/backlash48/output48.py play 30 - 3
    PYTHONPATH=python:benches python studies/backlash48/output48.py null 0 - 5
"""

from __future__ import annotations

import json
import math
import sys
import time
import warnings

import generator as G  # benches/generator.py
import numpy as np


def played(y: np.ndarray, c: float) -> np.ndarray:
    """The play of half-width c on each row of samples: every output within c of the last one."""
    out = np.empty_like(y)
    for i, row in enumerate(y):
        p = min(max(0.0, row[0] - c), row[0] + c)
        for k, v in enumerate(row):
            p = min(max(p, v - c), v + c)
            out[i, k] = p
    return out


def size_of(y: np.ndarray, plain: np.ndarray) -> float:
    """The bench's size: RMS over the averaged periods in averaged-noise sd."""
    d = G._steady(y[None]) - G._steady(plain[None])
    return float(np.sqrt(np.mean(d**2)) / (G.NOISE_SD / math.sqrt(G.PERIODS)))


def output_case(size: float, shape: str, seed: int) -> tuple[list[object], float, float]:
    p = G.make_plant(seed, shape)
    plain = G.run(p, G.Effect())[0]
    lo, hi = 1e-4, 0.5 * float(p.levels.min())
    for _ in range(30):  # bisection in log c: the contribution grows with c
        c = math.sqrt(lo * hi)
        got = size_of(played(plain, c), plain)
        if abs(got / size - 1) < 0.02:
            break
        lo, hi = (c, hi) if got < size else (lo, c)
    return G.recordings(p, played(plain, c), seed), c, got


def main() -> None:
    import bouc_wen_id as bw

    kind, size, shape, seed = sys.argv[1], float(sys.argv[2]), sys.argv[3], int(sys.argv[4])
    truth, achieved = math.nan, math.nan
    if kind == "out":
        recs, truth, achieved = output_case(size, shape, 4800 + seed)
    elif kind == "play":
        case = G.make_case("library", "play", "", size, 1000 + seed)
        recs, truth, achieved, shape = case.recordings, case.value, case.achieved, case.shape
    else:
        case = G.make_case("null", None, "", 0.0, 9000 + seed)
        recs, shape = case.recordings, case.shape
    c0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(recs)
    cpu = time.process_time() - c0
    named = {t.term: (t.value, t.standard_error) for t in d.named}
    row = {
        "case": f"{kind}-{size:g}-{shape}-{seed}",
        "truth": truth,
        "achieved": achieved,
        "status": str(getattr(d.status, "value", d.status)),
        "named": named,
        "alternatives": [[a.term, a.rival] for a in d.alternatives],
        "readings": [getattr(r, "words", str(r)) for r in d.readings],
        "verdict": d.verdict[:600],
        "cpu": round(cpu, 2),
    }
    if "play@output" in named and math.isfinite(truth):
        v, se = named["play@output"]
        row["within_3se"] = bool(abs(v - truth) <= 3 * se)
    print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
