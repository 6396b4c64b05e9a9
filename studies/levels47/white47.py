"""Which records' drift weights this branch can move: ``harmonic_var`` is set only where ``noise_colour``
flags a colour (data._levels); a white record keeps one level and its results are bit-identical.

    PYTHONPATH=python python studies/levels47/white47.py [SEEDS]

For review 46's H plan under white noise (``null-0-Hw``) and AR(2) (``null-0-H``): records with a
per-harmonic level, over 8 records per seed.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parents[1] / "review46"))
import drive46  # noqa: E402
import sim46  # noqa: E402
from bouc_wen_id.diagnosis.data import prepare  # noqa: E402
from bouc_wen_id.diagnosis.settling import _settled  # noqa: E402


def main(argv: list[str]) -> None:
    seeds = [int(x) for x in argv[1:]] or list(range(1, 17))
    runs, pl, *_ = drive46.build("null", 0.0, "H")
    for kind in ("white", "ar2"):
        coloured = total = 0
        for seed in seeds:
            exps = prepare(_settled(sim46.recordings(runs, pl, kind, drive46.SD, seed))[0])
            coloured += sum(e.harmonic_var.size > 0 for e in exps)
            total += len(exps)
        print(f"{kind}: {coloured} of {total} records carry per-harmonic levels ({len(seeds)} seeds)")


if __name__ == "__main__":
    main(sys.argv)
