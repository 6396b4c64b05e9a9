"""Pink (1/f) noise read as an unsettled transient (studies/pink45/README.md, left open): how often
outliers.transient_periods flags the first periods of noise-only records, and how often it still finds a
loop centre that settles, before and after the DC's own yardstick under a noise coloured at the DC.

    PYTHONPATH=python python studies/pink46/transient46.py             # this checkout
    PYTHONPATH=/work/main/python python studies/pink46/transient46.py  # main, for the "before" column

Records of review 45's config B shape (15 settling + 8 analysed periods of 200 samples; also 20 analysed),
noise of unit sd: white, AR(1) phi = 0.9, pink made two ways (review 45's FFT shaping, sim45.noise; a sum of
12 AR(1)s, tests/pink_noise.py). ``flagged``: the share whose first period transient_periods calls transient;
``trimmed``: that settling._settled then trims (no trend in the rest). Then the same noises plus a loop centre
that settles, ``c exp(-k / tau)`` from the first analysed period (k in periods; c 1, 3, 10 in units of the
draw's innovation: the AR(1)'s sd is 2.3 of it, the others' 1; tau 4 and 8 periods, the bench's slow-centre
null settles over about 8): the share found (flagged).
Every draw from ``np.random.default_rng([46, case, size])``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from bouc_wen_id.diagnosis.outliers import transient_periods
from bouc_wen_id.diagnosis.settling import _trending

sys.path.insert(0, str(Path(__file__).parents[1] / "review45"))
sys.path.insert(0, str(Path(__file__).parents[1] / "pink45"))
sys.path.insert(0, str(Path(__file__).parents[2] / "tests"))
from dc_level45 import draw  # noqa: E402

P, S, DRAWS = 200, 15, 200
KINDS = ("white", "ar1 0.9", "pink (sim45)", "pink (sum of AR(1)s)")


def rates(kind: str, n_per: int, size: float, tau: float, case: int) -> tuple[float, float]:
    rng = np.random.default_rng([46, case, int(size * 10), int(tau)])
    k = np.arange((S + n_per) * P) / P - S
    centre = np.where(k >= 0.0, size * np.exp(-np.maximum(k, 0.0) / tau), 0.0) if size else 0.0
    flagged = trimmed = 0
    for _ in range(DRAWS):
        y = draw(kind, (S + n_per) * P, rng) + centre
        got = transient_periods(y, P, S, n_per)
        flagged += got > 0
        trimmed += got > 0 and n_per - got >= 4 and not _trending(y, P, S + got, n_per - got)
    return flagged / DRAWS, trimmed / DRAWS


def main() -> None:
    print("noise only: share of records flagged / trimmed as transient")
    for n_per in (8, 20):
        for case, kind in enumerate(KINDS):
            f, t = rates(kind, n_per, 0.0, 1.0, case)
            print(f"  {n_per} periods, {kind}: flagged {f:.3f}, trimmed {t:.3f}", flush=True)
    print("a loop centre settling as c exp(-k / tau), 8 periods: share flagged")
    for case, kind in enumerate(KINDS):
        for tau in (4.0, 8.0):
            said = []
            for size in (1.0, 3.0, 10.0):
                f, _ = rates(kind, 8, size, tau, 10 + case)
                said.append(f"c {size:g}: {f:.2f}")
            print(f"  {kind}, tau {tau:g}: " + ", ".join(said), flush=True)


if __name__ == "__main__":
    main()
