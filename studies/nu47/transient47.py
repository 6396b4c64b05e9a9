"""Session 47 (nu47): the energy each experiment has dissipated when driven through G from rest (the record,
review 44's plant simulated by the library) against the pure sine ``x = |G| U cos(omega t - phi)`` from rest
that drift.corrected simulates, over the record's periods; at d = 0, so the strengths are those of the
virgin loop. The ratio of the mean energies is the ratio of the mean strength changes ``d E a`` the two see.

    OMP_NUM_THREADS=1 PYTHONPATH=python nice -n 10 python studies/nu47/transient47.py A
"""

from __future__ import annotations

import cmath
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent.parent / "review44"))
import bouc_wen_id as bw  # noqa: E402
import drive44 as dr  # noqa: E402


def energy(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    """e(t) = int w dx by the trapezoid rule on the samples."""
    return np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(x))])


def main(argv: list[str]) -> None:
    cfg = argv[0]
    p, d, _, _ = dr.build("nu", 30.0, cfg)
    g = p.g
    hy = bw.BoucWen(beta=p.hy.beta, gamma=p.hy.gamma, mu=p.hy.mu, alpha=1.0)
    for w_, a in zip(d.omegas, d.amps):
        plan = bw.SinePlan([w_], a, d.settle, d.periods, d.samples, noise_sd=0.0, seed=1, substeps=8)
        tf = bw.TransferFunction(list(g.num), list(g.den), delay=g.delay)
        (r,) = bw.simulate(bw.WienerPlant(tf, hy), plan)
        resp = g.response(w_)
        phi = -cmath.phase(resp)
        lin = bw.TransferFunction([abs(resp)], [1.0], phi / w_)
        (q,) = bw.simulate(bw.WienerPlant(lin, hy), plan)
        n0 = d.settle * d.samples
        e1, e2 = energy(np.asarray(r.x), np.asarray(r.w)), energy(np.asarray(q.x), np.asarray(q.w))
        m1, m2 = e1[n0:].mean(), e2[n0:].mean()
        head = f"omega {w_:5.1f} U {a:.3f}: mean e over the record,"
        print(f"{head} G from rest {m1:.5g}, sine {m2:.5g}, ratio {m1 / m2:.4f}")


if __name__ == "__main__":
    main(sys.argv[1:])
