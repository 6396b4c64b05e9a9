"""The degradation test's false-alarm rate on a null when the block levels misstate the noise where the drift
regressor acts (calib46.py): the F-test's scale is the blocks' chi-square over its dof (about 0.57 on H's
AR(2) noise), so a regressor whose harmonics sit where the levels are calibrated at ``c`` has its null
projection inflated by ``c / 0.57``. Level: the directed test at alpha = 0.05 over 19 candidates (one-sided),
and the drift gate's alpha / 4 when locate's drift test saw nothing (drift.with_drift_gate).

    python studies/nuar46/risk46.py
"""

from __future__ import annotations

from scipy.stats import chi2

ALPHA, FAMILY, SCALE = 0.05, 19, 0.57


def main() -> None:
    print("regressor at   calibration  inflation  P(pass directed)  P(pass gate alpha/4)")
    for where, c in (("at the scale", SCALE), ("h1", 0.71), ("h3", 0.38), ("h2 (AR(2) peak)", 2.96)):
        f = c / SCALE
        rates = []
        for level in (ALPHA, ALPHA / 4.0):
            thr = chi2.isf(2.0 * level / FAMILY, 1)  # one-sided: p halved (boundary), Bonferroni
            rates.append(0.5 * chi2.sf(thr / f, 1))
        print(f"{where:15s} {c:8.2f} {f:10.2f} {rates[0]:14.2g} {rates[1]:18.2g}")


if __name__ == "__main__":
    main()
