"""Our designs bench's AR(1) records handed to ``diagnose`` as lab measurements (the path whose drift gate
``lab_colour.harmonic_levels`` fixed): benches/diagnosis_designs.py's ``ar1`` design (phi 0.8) or ``ar1
slow`` (0.99), strength degradation at SIZE x or nothing hidden, each recording's settled periods as a
``bw.Measurement`` (its time, input and output; the averaging then finds the periods itself).

Usage: ``python studies/drift_gate_designs.py "ar1" degradation 10 --seeds 0 1 2`` (EFFECT ``none``: null).
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
import diagnosis_designs as dd  # noqa: E402


def measurements(design: str, effect: str, size: float, seed: int) -> list[Any]:
    des = dd.DESIGNS[design]
    p = dd.plant_for(des, seed)
    name = None if effect == "none" else effect
    y, _, _ = dd.outputs(p, des, name, "", size)
    out = []
    for r in dd.recordings(p, des, y, seed):
        s = int(r.settle_periods) * int(r.samples_per_period)
        out.append(bw.Measurement(r.t[s:], r.u[s:], r.y[s:], nominal_frequency=float(r.frequency)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("design")
    ap.add_argument("effect")
    ap.add_argument("size", type=float)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    a = ap.parse_args()
    for seed in a.seeds:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(measurements(a.design, a.effect, a.size, seed))
        deg = d.degradation
        gate = "-" if deg is None else f"drift p {deg.drift_p_value:.3g}, chi2 {deg.cost0:.0f} on {deg.dof0}"
        print(
            f"{a.design} {a.effect} {a.size:g} seed {seed}: {d.status}; named {list(d.named_terms)}; {gate}"
        )
        print("   ", d.verdict[:160])


if __name__ == "__main__":
    main()
