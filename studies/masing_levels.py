"""benches/diagnosis.py with another design: the generator's latent levels replaced (docs/masing.md).

``python studies/masing_levels.py 0.5,1.2,3.0 -- --only stiffness,iwan --cases 5 --sizes 10,30 --workers 1``
(no ``--cache``: its keys do not hold the levels)
runs the bench with every case's experiments at latent levels 0.5 (below saturation), 1.2 and 3.0 of
saturation at each of its frequencies, instead of the generator's ``X_LEVELS`` (1.2, 3.0): the Masing caveat's
power statistic (diagnosis/masing.py) on designs that hold a below-saturation experiment.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))

import generator as gen  # noqa: E402


def main() -> int:
    levels = tuple(float(v) for v in sys.argv[1].split(","))
    gen.X_LEVELS = levels  # read when each plant is drawn (the bench's workers are forked after this)
    import diagnosis as bench  # noqa: E402

    rest = sys.argv[3:] if sys.argv[2:3] == ["--"] else sys.argv[2:]
    return int(bench.main(rest) or 0)


if __name__ == "__main__":
    raise SystemExit(main())
