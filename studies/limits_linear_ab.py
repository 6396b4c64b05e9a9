"""The detection limits' linear-trace cut (session 47, docs/diagnosis-speed.md) measured in one process: MR
levels diagnosed with the cut off (``limits.LINEAR_TERMS`` emptied: the code before it) and on, in turns,
then the level's captured ``detection_limits`` call timed 3 times each way; CPU is ``time.process_time``.

Usage: ``OMP_NUM_THREADS=1 PYTHONPATH=python python studies/limits_linear_ab.py [--levels 0.25,0]
[--data DIR]``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
import warnings
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import bouc_wen_id as bw  # noqa: E402
from bouc_wen_id.diagnosis import limits, run  # noqa: E402


def _rel(a: float, b: float) -> float:
    if a == b:
        return 0.0
    return abs(a - b) / abs(b) if math.isfinite(b) and b != 0.0 else math.inf


def main(argv: list[str] | None = None) -> int:
    import _adapters as A

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=A.default_data_dir())
    ap.add_argument("--levels", default="0.25,0")
    args = ap.parse_args(argv)
    blocks = [A.load_mr_damper(args.data / A.DATASETS["mr-damper"] / f) for f in A.MR_FILES]
    linear, real = limits.LINEAR_TERMS, limits.detection_limits
    captured: list[tuple[Any, Any]] = []

    def capture(*a: Any, **k: Any) -> Any:
        captured.append((a, k))
        return real(*a, **k)

    for level in (float(v) for v in args.levels.split(",")):
        ms = [b[A.MR_CURRENTS.index(level)] for b in blocks]
        captured.clear()
        run.detection_limits = capture  # type: ignore[attr-defined]
        try:
            for on in (False, True):
                limits.LINEAR_TERMS = linear if on else ()
                t0 = time.process_time()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    d = bw.diagnose(ms, y_unit=ms[0].units.get("y", ""), u_unit=ms[0].units.get("u", ""))
                cpu = time.process_time() - t0
                print(
                    f"{level:g} A diagnosis, cut {'on' if on else 'off'}: CPU {cpu:.2f} s, {d.status}",
                    flush=True,
                )
            a, k = captured[0]
            times: dict[bool, list[float]] = {False: [], True: []}
            found: dict[bool, Any] = {}
            for _ in range(3):
                for on in (False, True):
                    limits.LINEAR_TERMS = linear if on else ()
                    t0 = time.process_time()
                    found[on] = real(*a, **k)
                    times[on].append(time.process_time() - t0)
        finally:
            run.detection_limits = real  # type: ignore[attr-defined]
            limits.LINEAR_TERMS = linear
        for on in (False, True):
            print(f"{level:g} A detection_limits, cut {'on' if on else 'off'}: CPU {sorted(times[on])}")
        worst = max(_rel(x.limit, y.limit) for x, y in zip(found[True], found[False]))
        print(f"{level:g} A limits' largest relative difference: {worst:.2e}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
