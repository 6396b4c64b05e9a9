"""The adequacy test under AR(1) output noise (session 39, adequacy_chi2.py): the bench's nulls and one term
on data whose noise is coloured, G forced to one shape (``first`` order, or ``resonant`` with its delay), the
bench's design otherwise. Prints one line per seed (status, named terms, the plain model's adequacy chi2/dof
and p) and a summary row (false "unexplained"/named on nulls, or detections of the term).

Usage: ``PYTHONPATH=python python studies/colour_nulls.py PHI SHAPE FIRST_SEED SEEDS [TERM PLACE SIZE]``
(e.g. ``0.8 resonant 3900 20`` for nulls; ``0.8 first 3900 10 stiffness x 10`` for a term at 10x);
``PHI`` 0 is white noise.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import bouc_wen_id as bw  # noqa: E402
import generator as gen  # noqa: E402
from outside_design import ar1_recordings  # noqa: E402


def main() -> None:
    phi, shape = float(sys.argv[1]), sys.argv[2]
    first, count = int(sys.argv[3]), int(sys.argv[4])
    term = sys.argv[5] if len(sys.argv) > 5 else None
    place = sys.argv[6] if len(sys.argv) > 6 else ""
    size = float(sys.argv[7]) if len(sys.argv) > 7 else 0.0
    if phi > 0:
        gen.recordings = ar1_recordings(phi)
    plant = gen.make_plant
    gen.make_plant = lambda seed, _s=None, low_amplitude=False: plant(seed, shape, low_amplitude)
    hits, rows = 0, []
    for seed in range(first, first + count):
        case = gen.make_case("null" if term is None else "term", term, place, size, seed)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(case.recordings)
        named = [t.term for t in d.final.terms]
        label = term if place in ("", "u") else f"{term}@{place}"
        hit = (d.status != "adequate") if term is None else (label in named)
        hits += hit
        c = float(getattr(d.plain, "chi2_dof", d.plain.cost / max(d.plain.dof, 1)))
        rows.append(c)
        print(
            f"seed {seed}: {d.status}; {named}; plain chi2/dof {c:.3f} p {d.plain.p_value:.3g}",
            flush=True,
        )
    what = "not adequate (false)" if term is None else f"{term} named"
    mean = sum(rows) / len(rows)
    print(
        f"ROW phi {phi} {shape} {term or 'null'} {size:g}x: {what} {hits}/{count}; "
        f"mean plain chi2/dof {mean:.3f}"
    )


if __name__ == "__main__":
    main()
