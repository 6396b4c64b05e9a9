"""The bench's outside loops (``benches/generator.py``: ``iwan``, ``pi_u``) on data made another way than the
bench's default: three frequencies (0.5, 1, 2 x the corner) at ONE amplitude (latent |x| 3), G forced to one
shape (``first`` order, or ``resonant`` with its delay), and AR(1) output noise (``PHI``, marginal sd the
bench's ``NOISE_SD``; ``PHI`` 0 is white noise of its own draw). Prints each case's status, named terms,
final chi2/dof, adequacy p, the bench's score (``benches/diagnosis.py``: "WRONG" a confident wrong name, "fam"
a name with its family caveat in the headline) and headline; then the count of wrong names.

Usage: ``PYTHONPATH=python python studies/outside_design.py PHI ROWS SHAPES`` (e.g. ``0.7 iwan,pi_u
first,resonant``); seeds 3801 and 3802, sizes 10x and 30x.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))

import bouc_wen_id as bw  # noqa: E402
import diagnosis as bench  # noqa: E402
import generator as gen  # noqa: E402


def ar1_recordings(phi: float) -> Any:
    """``gen.recordings`` with AR(1) noise of coefficient ``phi`` (marginal sd ``noise_sd``), not white."""
    white = gen.recordings

    def make(
        p: Any, y: Any, seed: int, settle: int = gen.SETTLE, noise_sd: float = gen.NOISE_SD
    ) -> list[Any]:
        rng = np.random.default_rng([seed, 77])
        out = []
        for r in white(p, y, seed, settle, 0.0):
            n = r.y.size
            e = rng.normal(0.0, noise_sd * np.sqrt(1 - phi**2), n)
            v = np.empty(n)
            v[0] = rng.normal(0.0, noise_sd)
            for k in range(1, n):
                v[k] = phi * v[k - 1] + e[k]
            out.append(
                bw.Recording(
                    r.t,
                    r.u,
                    r.y + v,
                    r.amplitude,
                    r.frequency,
                    settle_periods=r.settle_periods,
                    metadata=dict(r.metadata),
                )
            )
        return out

    return make


def main() -> None:
    phi = float(sys.argv[1]) if len(sys.argv) > 1 else 0.7
    rows = sys.argv[2].split(",") if len(sys.argv) > 2 else ["iwan", "pi_u"]
    shapes = sys.argv[3].split(",") if len(sys.argv) > 3 else ["first", "resonant"]
    gen.FREQ_FACTORS = (0.5, 1.0, 2.0)
    gen.X_LEVELS = (3.0,)
    gen.recordings = ar1_recordings(phi)
    plant = gen.make_plant
    wrong = total = 0
    for name in rows:
        for shape in shapes:
            gen.make_plant = lambda seed, _s=None, low_amplitude=False, s=shape: plant(seed, s, low_amplitude)
            for size in (10.0, 30.0):
                for seed in (3801, 3802):
                    case = gen.make_case("outside", name, "", size, seed)
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore")
                        d = bw.diagnose(case.recordings)
                    f = d.final
                    sc = bench._score(d, "outside", None, "", name)
                    wrong, total = wrong + sc["wrong"], total + 1
                    mark = "WRONG" if sc["wrong"] else "fam" if sc["family"] else "-"
                    print(
                        f"{name} {shape} {size:g}x seed {seed}: {d.status_text} [{mark}]; "
                        f"{[t.term for t in f.terms]}; final chi2/dof {f.cost / f.dof:.3f} p {f.p_value:.3g} "
                        f"| {d.headline[:400]}",
                        flush=True,
                    )
    print(f"wrong confident names: {wrong} of {total}")


if __name__ == "__main__":
    main()
