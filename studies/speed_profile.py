"""Where one MR damper current level's CPU goes (issue 18 item 4; docs/diagnosis-speed.md, session 45).

Each level (the six files of one coil current, as ``studies/diagnose_real.py`` loads them) is diagnosed once
with the candidate threads off (``speed.THREAD_CANDIDATE_FITS``: every refinement then runs in the main
thread, so its caller is known; the results are the same either way). Printed per level: the process's CPU
seconds (``time.process_time``), the Rust refinements (``fit_augmented`` calls) with their LM iterations and
stopping rules, and their CPU by caller (the first diagnosis frame above ``fitting`` / ``free_dc`` /
``fit_share``); the refinements that repeat an earlier one on every input (a cache could take them), and those
that start where an earlier one ended (a chunk continued, a finish after a screen: their first evaluation
repeats that refinement's last accepted one); the model outputs evaluated outside the refinements
(``augmented_output``), their CPU and their repeats.

``--rejections N`` replays N of the first level's refinements (a seeded sample) once per iteration cap
``k = 1 .. iterations`` and counts the iterations that left the point unchanged (a rejected LM trial: the
same cost and parameters as at ``k - 1``); the pattern (``a`` accepted, ``r`` rejected) is printed per fit.

Usage: ``OMP_NUM_THREADS=1 python studies/speed_profile.py [--data DIR] [--levels 0,0.25]
[--rejections 25] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import collections
import hashlib
import json
import pickle
import random
import sys
import time
import traceback
import warnings
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))

import bouc_wen_id as bw  # noqa: E402
import bouc_wen_id.augmented as aug  # noqa: E402
from bouc_wen_id.diagnosis import fitting, speed  # noqa: E402

#: Frames that wrap a refinement; the caller named is the first frame outside them.
WRAPPERS = {"fitting", "free_dc", "fit_share", "speed_profile", "threading", "thread", "contextvars"}


def _digest(x: Any) -> str:
    return hashlib.blake2b(pickle.dumps(x, protocol=pickle.HIGHEST_PROTOCOL), digest_size=16).hexdigest()


def _caller() -> str:
    for fr in reversed(traceback.extract_stack()[:-2]):
        stem = Path(fr.filename).stem
        if stem not in WRAPPERS:
            return f"{stem}.{fr.name}"
    return "?"


class Recorder:
    """Wraps ``fitting.fit_augmented`` and every module's ``augmented_output`` while installed."""

    def __init__(self) -> None:
        self.fits: list[dict[str, Any]] = []
        self.outputs: list[tuple[str, str, float]] = []
        self.calls: list[tuple[Any, Any, dict[str, Any]]] = []
        self._fit = fitting.fit_augmented
        self._out = aug.augmented_output
        self._wrapped = self.output  # one bound method, so that uninstall finds what install set

    def fit(self, exps: Any, start: Any, **kw: Any) -> Any:
        t0 = time.process_time()
        f = self._fit(exps, start, **kw)
        cpu = time.process_time() - t0
        ek = _digest([(e.ybar.tobytes(), e.weight, e.amplitude, e.frequency, e.grid_phase) for e in exps])
        self.fits.append(
            {
                "caller": _caller(),
                "cpu": cpu,
                "max_iter": kw.get("max_iter"),
                "iterations": f.iterations,
                "stop": f.stop,
                "inputs": _digest((ek, start, sorted(kw.items()), [e.waveform for e in exps])),
                "start": _digest((ek, start)),
                "end": _digest((ek, f.params)),
            }
        )
        self.calls.append((list(exps), start, dict(kw)))
        return f

    def output(self, e: Any, par: Any, i: int, **kw: Any) -> Any:
        t0 = time.process_time()
        out = self._out(e, par, i, **kw)
        key = _digest(
            (e.ybar.size, e.amplitude, e.frequency, e.grid_phase, e.waveform, e.substeps, par, i, kw)
        )
        self.outputs.append((_caller(), key, time.process_time() - t0))
        return out

    def install(self) -> None:
        fitting.fit_augmented = self.fit
        for m in list(sys.modules.values()):
            if (
                m is not None
                and m.__name__.startswith("bouc_wen_id")
                and getattr(m, "augmented_output", None) is self._out
            ):
                m.augmented_output = self._wrapped  # type: ignore[attr-defined]

    def uninstall(self) -> None:
        fitting.fit_augmented = self._fit
        for m in list(sys.modules.values()):
            if m is not None and getattr(m, "augmented_output", None) is self._wrapped:
                m.augmented_output = self._out  # type: ignore[attr-defined]


def summary(rec: Recorder, cpu: float) -> dict[str, Any]:
    """The level's numbers (module docstring)."""
    fits = rec.fits
    by: dict[str, list[float]] = collections.defaultdict(lambda: [0, 0.0, 0])
    for f in fits:
        row = by[f["caller"]]
        row[0] += 1
        row[1] += f["cpu"]
        row[2] += f["iterations"]
    seen: set[str] = set()
    ends: set[str] = set()
    repeats = continued = 0
    for f in fits:
        repeats += f["inputs"] in seen
        continued += f["start"] in ends
        seen.add(f["inputs"])
        ends.add(f["end"])
    keys = collections.Counter(k for _, k, _ in rec.outputs)
    return {
        "cpu": cpu,
        "refinements": len(fits),
        "refinement_cpu": sum(f["cpu"] for f in fits),
        "iterations": sum(f["iterations"] for f in fits),
        "stops": dict(collections.Counter(f["stop"] for f in fits)),
        "at_cap": sum(f["iterations"] == f["max_iter"] for f in fits),
        "by_caller": {k: {"refinements": v[0], "cpu": v[1], "iterations": v[2]} for k, v in by.items()},
        "repeated_refinements": repeats,
        "starting_where_one_ended": continued,
        "outputs": len(rec.outputs),
        "output_cpu": sum(c for _, _, c in rec.outputs),
        "repeated_outputs": sum(n - 1 for n in keys.values()),
    }


def rejections(calls: list[tuple[Any, Any, dict[str, Any]]], count: int, seed: int = 1) -> dict[str, Any]:
    """Accepted and rejected LM iterations of ``count`` sampled refinements (module docstring)."""
    rng = random.Random(seed)
    sample = rng.sample(range(len(calls)), min(count, len(calls)))
    patterns = []
    for i in sample:
        exps, start, kw = calls[i]
        full = fitting.fit_augmented(exps, start, **kw)
        prev = None
        s = ""
        for k in range(1, full.iterations + 1):
            g = fitting.fit_augmented(exps, start, **{**kw, "max_iter": k})
            key = (g.cost, g.params.shared.tobytes(), g.params.gains.tobytes(), g.params.phases.tobytes())
            s += "r" if key == prev else "a"
            prev = key
        patterns.append(s)
    text = "".join(patterns)
    tails = sum(len(p) - len(p.rstrip("r")) for p in patterns)
    return {
        "accepted": text.count("a"),
        "rejected": text.count("r"),
        "final_rejection_runs": tails,
        "patterns": patterns,
    }


def main(argv: list[str] | None = None) -> int:
    import _adapters as A

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=A.default_data_dir())
    ap.add_argument("--levels", default="", help="currents in A, comma-separated (default: all five)")
    ap.add_argument("--rejections", type=int, default=0, help="refinements of the first level to replay")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    speed.THREAD_CANDIDATE_FITS = False
    blocks = [A.load_mr_damper(args.data / A.DATASETS["mr-damper"] / f) for f in A.MR_FILES]
    wanted = {float(v) for v in args.levels.split(",") if v}
    out: dict[str, Any] = {}
    for k, current in enumerate(A.MR_CURRENTS):
        if wanted and current not in wanted:
            continue
        ms = [b[k] for b in blocks]
        rec = Recorder()
        rec.install()
        try:
            t0 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                bw.diagnose(ms, y_unit=ms[0].units.get("y", ""), u_unit=ms[0].units.get("u", ""))
            cpu = time.process_time() - t0
        finally:
            rec.uninstall()
        row = summary(rec, cpu)
        if args.rejections and not any("rejections" in r for r in out.values()):
            row["rejections"] = rejections(rec.calls, args.rejections)
        out[f"{current:g} A"] = row
        print(f"{current:g} A: {json.dumps({k: v for k, v in row.items() if k != 'rejections'})}", flush=True)
        if "rejections" in row:
            rj = row["rejections"]
            print(
                f"  rejections: {rj['accepted']} accepted, {rj['rejected']} rejected "
                f"({rj['final_rejection_runs']} in a fit's final run)",
                flush=True,
            )
    if args.json is not None:
        args.json.write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
