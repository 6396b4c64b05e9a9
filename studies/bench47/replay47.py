"""Session 47: replay bench cases of ``benches/diagnosis.py`` from the cache and print what was said.

Usage: ``python studies/bench47/replay47.py CACHE KIND NAME PLACE SIZE SEED [SEED ...]``; NAME ``-`` for a
null (e.g. ``target/benchcache null - "" 0 52055``). Per seed: the plant, the true value, the achieved size,
the diagnosis's summary (verdict, selection steps with each candidate's F, p and law p) and its CPU seconds.
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benches"))

import bouc_wen_id as bw  # noqa: E402
import generator as gen  # noqa: E402


def main(argv: list[str]) -> None:
    cache, kind, place, size = Path(argv[0]), argv[1], argv[3], float(argv[4])
    name = None if argv[2] == "-" else argv[2]
    for seed in (int(s) for s in argv[5:]):
        case = gen.cached_case(kind, name, place, size, seed, cache)
        c0 = time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(case.recordings)
        cpu = time.process_time() - c0
        print(f"===== seed {seed}: shape {case.shape}, value {case.value:.6g}, achieved {case.achieved:.3g}")
        print(d.summary())
        print(f"(diagnosis {cpu:.1f} s CPU)")


if __name__ == "__main__":
    main(sys.argv[1:])
