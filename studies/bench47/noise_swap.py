"""Session 47: is a bench miss the case's noise draw or its plant? Re-diagnose one case's noise-free
record (``benches/generator.py``'s own plant and effect) under other seeded noise draws, and its own noise
draw on the plain plant (the effect removed).

Usage: ``python studies/bench47/noise_swap.py KIND NAME PLACE SIZE SEED [DRAWS]`` (NAME ``-`` for a null).
Prints, per draw, the status, the plain model's p and what was named; then the case's own noise on the plain
plant. Draw k's noise is the generator's own for the seed ``OTHER + 1000 k + seed`` (no bench case has it).
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path
from typing import Any, Optional

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))

import bouc_wen_id as bw  # noqa: E402
import generator as gen  # noqa: E402

OTHER = 10_000_000


def _say(tag: str, recs: list[Any]) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(recs)
    pp, pf = d.plain.p_value, d.final.p_value
    print(f"{tag}: {d.status:<12} plain p {pp:.3g}  final p {pf:.3g}  named {list(d.named_terms) or '-'}")


def main(argv: list[str]) -> None:
    kind, place, size, seed = argv[0], argv[2], float(argv[3]), int(argv[4])
    name: Optional[str] = None if argv[1] == "-" else argv[1]
    draws = int(argv[5]) if len(argv) > 5 else 8
    p = gen.make_plant(seed, low_amplitude=kind == "null")
    plain = gen.run(p, gen.Effect())[0]
    y = plain if name is None else gen._calibrate(p, name, place, size, gen.base(p))[2]
    print(f"seed {seed} ({p.shape}): {kind} {name or 'plain'}@{place or '-'} {size:g}x")
    _say("  own noise", gen.recordings(p, y, seed))
    for k in range(draws):
        _say(f"  draw {k}", gen.recordings(p, y, OTHER + 1000 * k + seed))
    if name is not None:
        _say("  own noise, plain plant", gen.recordings(p, plain, seed))


if __name__ == "__main__":
    main(sys.argv[1:])
