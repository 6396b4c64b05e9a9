"""Which wander path each design-C wander null takes, and the DC-only wander's numbers (wander46 README).

    PYTHONPATH=python python studies/wander46/probe46.py SEED0 SEED1
    PYTHONPATH=python python studies/wander46/probe46.py bench SEED0 SEED1
    PYTHONPATH=python:tests python studies/wander46/probe46.py tests

Per seed (review 45's C, sim45's ``wander`` noise, seeds as calib46.py's): whether ``baseline.detect`` or
``zero_drift.detect`` fires, and ``dc_wander._statistics`` (the period means' roughness about each
recording's best settling exponential, its p, the fundamental's pooled trend p).
"""

from __future__ import annotations

import sys
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review45"))
import drive45 as dv  # noqa: E402
import sim45 as s  # noqa: E402
from bouc_wen_id.diagnosis import baseline, zero_drift  # noqa: E402

PERIODS = (6, 30, 6, 30, 30, 6, 30, 6)


def main(s0: int, s1: int) -> None:
    try:
        from bouc_wen_id.diagnosis import dc_wander
    except ImportError:  # main: no DC-only wander test
        dc_wander = None
    p, d, _ = dv.scaled("C")
    d = replace(d, periods=PERIODS)
    runs = s.run(p, d)
    for seed in range(s0, s1):
        recs = s.recordings(runs, d, s.Noise("wander", dv.SD), seed)
        w = baseline.detect(recs, 0.05 / 20)
        z = zero_drift.detect(recs, 0.05 / 20)
        line = f"{seed} baseline {'yes' if w else 'no'} zero_drift {'yes' if z else 'no'}"
        if z is not None:
            line += f" (decaying {len(z.decaying)}, loop_trends {z.loop_trends})"
        if dc_wander is not None:
            st = dc_wander._statistics(recs)
            if st is not None:
                line += f" | settle chi2 {st[0]:.0f}/{st[1]} p {st[2]:.2g} loop p {st[3]:.2g}"
        print(line, flush=True)


def bench_nulls(s0: int, s1: int) -> None:
    """The designs bench's nulls (a low-amplitude experiment whose loop centre settles slowly): whether any
    wander test fires on them (``probe46.py bench S0 S1``)."""
    sys.path.insert(0, str(Path(__file__).parents[2] / "benches"))
    import generator as g
    from bouc_wen_id.diagnosis import dc_wander

    for seed in range(s0, s1):
        recs = g.make_case("null", None, "", 0.0, seed).recordings
        st = dc_wander._statistics_dc(recs)
        w, z = baseline.detect(recs, 0.05 / 20), zero_drift.detect(recs, 0.05 / 20)
        line = f"bench null {seed} baseline {'yes' if w else 'no'} zero_drift {'yes' if z else 'no'} "
        line += f"dc_wander {'yes' if dc_wander.detect(recs, 0.05 / 20) else 'no'}"
        if st is not None:
            line += f" | settle chi2 {st[0]:.0f}/{st[1]} p {st[2]:.2g} loop p {st[3]:.2g}"
        print(line, flush=True)


def zero_drift_sets() -> None:
    """tests/test_diagnosis_zero_drift.py's sets (a settling centre, white, AR(1), a fading loop, a line; the
    slow settling sets), seeds 0-4: whether dc_wander fires (``probe46.py tests``)."""
    sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))
    from bouc_wen_id.diagnosis import dc_wander
    from test_diagnosis_zero_drift import _recs, _settling

    for kind in ("settling", "white", "ar1", "ar1 slow", "fading", "drift"):
        print(kind, [dc_wander.detect(_recs(kind, s), 0.05 / 20) is not None for s in range(5)])
    for size, tau in ((5.0, 2.0), (4.0, 1.5)):
        got = [dc_wander.detect(_settling(s, size, tau), 0.05 / 20) is not None for s in range(5)]
        print("settling set", size, tau, got)


if __name__ == "__main__":
    if sys.argv[1] == "tests":
        zero_drift_sets()
    elif sys.argv[1] == "bench":
        bench_nulls(int(sys.argv[2]), int(sys.argv[3]))
    else:
        main(int(sys.argv[1]), int(sys.argv[2]))
