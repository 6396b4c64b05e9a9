"""Why neither wander detector takes design C's smooth baseline out (cseed46 README, "Wander").

    PYTHONPATH=python python studies/cseed46/detect46.py SEED [SEED ...]

For review 45's config C with sim45's ``wander`` noise: ``baseline._statistics`` (the period means' chi-square
about a quadratic, its p, the pooled lag-1 correlation, the last half's p) and, per recording of 8 periods or
more, ``zero_drift._recording`` (the slope's chi-square, the decay test's one-sided p, the loop's chi-square,
the slope per period, the white variance).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review45"))
import drive45 as dv  # noqa: E402
import sim45 as s  # noqa: E402
from bouc_wen_id.diagnosis import baseline, zero_drift  # noqa: E402


def main(seeds: list[int]) -> None:
    p, d, _ = dv.scaled("C")
    runs = s.run(p, d)
    for seed in seeds:
        recs = s.recordings(runs, d, s.Noise("wander", dv.SD), seed)
        st = baseline._statistics(recs)
        if st is None:
            print(seed, "wander: nothing to test")
            continue
        chi2, dof, pval, r, late = st[:5]
        print(seed, f"wander chi2 {chi2:.1f} dof {dof} p {pval:.2g} r {r:.2f} late_p {late:.2g}")
        for rec in recs:
            rr = zero_drift._rows(rec)
            if rr is None:
                continue
            got = zero_drift._recording(rr[0], rr[1])
            nums = got if isinstance(got, str) else tuple(round(float(x), 4) for x in got)
            print("   ", rec.metadata["name"], "zero_drift (x2, decay p, loop x2, slope, white):", nums)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]])
