"""Summarise calib46.py's records: per design, the plain p's KS distance from uniform, its rate below 0.05
and 0.01, the statistic over dof against its F reference, and per experiment the residual chi-square over
its samples against the true and the estimated noise variance.

    python studies/cseed46/summarise46.py studies/cseed46/calib46.jsonl
"""

from __future__ import annotations

import json
import sys
from collections import defaultdict

import numpy as np
from scipy import stats


def main(path: str) -> None:
    rows: dict[str, list[dict]] = defaultdict(list)
    for line in open(path):
        if line.strip():
            r = json.loads(line)
            rows[f"{r['design']}/{r['noise']}"].append(r)
    for key, rs in rows.items():
        p = np.array([r["plain_p"] for r in rs])
        q = np.array([r["stat"] / r["dof"] for r in rs])
        ks = stats.kstest(p, "uniform")
        print(
            f"{key}: n {p.size}, KS D {ks.statistic:.3f} (p {ks.pvalue:.3f}), p<0.05 {np.sum(p < 0.05)}, "
            f"p<0.01 {np.sum(p < 0.01)}, p<0.025 {np.sum(p < 0.025)}, min p {p.min():.2g}; "
            f"stat/dof mean {q.mean():.4f} sd {q.std(ddof=1):.4f} (dof {rs[0]['dof']})"
        )
        per = defaultdict(lambda: defaultdict(list))
        for r in rs:
            for j, e in enumerate(r["exps"]):
                n = 200.0
                per[j]["true"].append(e["chi2_true"] / n)
                per[j]["own"].append(e["chi2_own"] / n)
                per[j]["var"].append(e["var_ratio"])
                per[j]["periods"] = e["periods"]
        for j, d in per.items():
            print(
                f"   e{j} ({d['periods']:g} periods): chi2/P true-var mean {np.mean(d['true']):.3f} "
                f"sd {np.std(d['true'], ddof=1):.3f}; own-var mean {np.mean(d['own']):.3f} "
                f"sd {np.std(d['own'], ddof=1):.3f}; noise_var/true mean {np.mean(d['var']):.3f} "
                f"sd {np.std(d['var'], ddof=1):.3f}"
            )


if __name__ == "__main__":
    main(sys.argv[1])
