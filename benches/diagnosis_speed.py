"""The diagnosis's speed (issue 18 item 4): seconds per MR damper current level and per 10-experiment
simulated diagnosis (and the wire rope's, full mode), before and after the speed switches of
``bouc_wen_id.diagnosis.speed``, in one run.

Each case is diagnosed twice in the same process, alternating: "before" with every switch of
:mod:`bouc_wen_id.diagnosis.speed` off (the code as it was), "after" with them on; wall seconds
(``time.perf_counter``) and CPU seconds of the process (``time.process_time``, every thread), their ratio,
and whether the verdict is the same (status, named terms and the verdict's text, every printed digit).
The ratio is measured at the same moment on the same machine, so it holds under load; the absolute
seconds do not (the load average is printed at the start and the end).

Cases: the MR damper's current levels (``studies/_adapters.py``, the six files of one current as
``studies/diagnose_real.py`` loads them) and 10-experiment simulated diagnoses (``benches/generator.py``:
five frequencies around a resonant or first-order G, two saturating amplitudes, 1 % noise, one concealed
effect). Run it WITHOUT ``OPENBLAS_NUM_THREADS`` / ``OMP_NUM_THREADS`` set (as a user's Python would be):
with them set, the BLAS switch has nothing to change.

Usage: ``python benches/diagnosis_speed.py [--quick] [--data DIR] [--json out.json]``; ``--quick`` (the
0 A level and one simulated case, about a minute on 2 idle cores) or the full set (five levels, the wire
rope, three simulated cases). Progress on stderr. Then the MR damper's levels diagnosed across
(``diagnose_across`` given each level's own diagnosis, as the study runs it; 0 A and 0.25 A with ``--quick``):
"same verdict" there is the whole result (``to_dict()``, every value) the same; ``--no-across`` skips it,
``--across-only`` runs it alone.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from functools import partial
from pathlib import Path
from typing import Any, Callable, Optional

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(REPO / "studies"))  # the data sets' adapters, imported by name

#: The simulated cases: (kind, effect, place, size in averaged-noise sd, seed) of benches/generator.py.
SIMULATED = (
    ("library", "viscous", "x", 10.0, 11),
    ("library", "coulomb", "u", 30.0, 12),
    ("null", None, "", 0.0, 13),
)


def _adapters() -> Any:
    import _adapters

    return _adapters


def _data_dir(given: Optional[Path], adapters: Any) -> Path:
    """The real data: ``--data``, else the adapters' default, else /work/shared/data/real."""
    for d in (given, adapters.default_data_dir(), Path("/work/shared/data/real")):
        if d is not None and (d / adapters.DATASETS["mr-damper"]).is_dir():
            return d
    raise SystemExit("error: the real data (mr-damper) were not found; give --data DIR")


def mr_cases(data: Path, adapters: Any, levels: list[float]) -> list[tuple[str, Callable[[], Any]]]:
    blocks = [adapters.load_mr_damper(data / adapters.DATASETS["mr-damper"] / f) for f in adapters.MR_FILES]
    out: list[tuple[str, Callable[[], Any]]] = []
    for k, current in enumerate(adapters.MR_CURRENTS):
        if current in levels:
            ms = [b[k] for b in blocks]
            out.append((f"MR damper {current:g} A", partial(list, ms)))
    return out


def wire_rope_case(data: Path, adapters: Any) -> list[tuple[str, Callable[[], Any]]]:
    """The wire-rope isolator's files, as ``studies/diagnose_real.py`` loads them (its slowest group)."""
    folder = data / adapters.DATASETS["wire-rope"]
    if not folder.is_dir():
        return []
    ms = [adapters.load_wire_rope(folder / f) for f in adapters.WIRE_ROPE_FILES]
    return [("wire rope, all files", partial(list, ms))]


def _recordings(*case: Any) -> Any:
    import generator as gen

    return gen.make_case(*case).recordings


def simulated_cases(count: int) -> list[tuple[str, Callable[[], Any]]]:
    out: list[tuple[str, Callable[[], Any]]] = []
    for kind, name, place, size, seed in SIMULATED[:count]:
        where = f"@{place}" if place else ""
        label = f"simulated {name or 'null'}{where} {size:g}x (seed {seed})"
        out.append((label, partial(_recordings, kind, name, place, size, seed)))
    return out


def _verdict(d: Any) -> dict[str, Any]:
    return {"status": d.status, "named": [str(t) for t in d.named], "verdict": d.verdict}


def timed(items: Any, fast: bool) -> tuple[float, float, dict[str, Any]]:
    """(wall s, CPU s, verdict) of one diagnosis, the speed switches on (``fast``) or off."""
    import bouc_wen_id as bw
    from bouc_wen_id.diagnosis import speed
    from bouc_wen_id.diagnosis.drift import _mean_period

    switches = [k for k in vars(speed) if k.isupper()]  # every switch of diagnosis/speed.py
    for k in switches:
        setattr(speed, k, fast)
    _mean_period.cache_clear()  # no hits from an earlier diagnosis of the same case (the warm-up)
    try:
        t0, c0 = time.perf_counter(), time.process_time()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(items)
        return time.perf_counter() - t0, time.process_time() - c0, _verdict(d)
    finally:
        for k in switches:
            setattr(speed, k, True)


def across_row(data: Path, adapters: Any, levels: list[float]) -> dict[str, Any]:
    """The MR damper's levels across (``studies/diagnose_real.py``'s ``mr_across``: each level's own
    diagnosis given, the study's candidates), timed with the switches off and on as :func:`timed` does; the
    levels' own diagnoses run once, switches on, untimed (the study's main run has them already). Off, the
    stored fits are keyed by other switches, so none is reused (fit_share.py)."""
    import diagnose_real as study
    from bouc_wen_id.diagnosis import speed

    blocks = [adapters.load_mr_damper(data / adapters.DATASETS["mr-damper"] / f) for f in adapters.MR_FILES]
    mr = []
    for k, current in enumerate(adapters.MR_CURRENTS):
        if current in levels:
            ms = [b[k] for b in blocks]
            mr.append((f"{current:g} A", ms, study._diagnose(ms, ms[0].units, False)))
    switches = [k for k in vars(speed) if k.isupper()]
    got = {}
    for fast in (False, True):
        for k in switches:
            setattr(speed, k, fast)
        try:
            when = "after" if fast else "before"
            print(f"across {len(mr)} levels: {when} ...", file=sys.stderr, flush=True)
            t0, c0 = time.perf_counter(), time.process_time()
            a = study.mr_across(mr, progress=False)
            got[fast] = (time.perf_counter() - t0, time.process_time() - c0, a.to_dict())
        finally:
            for k in switches:
                setattr(speed, k, True)
    (wb, cb, vb), (wa, ca, va) = got[False], got[True]
    vb.pop("seconds"), va.pop("seconds")
    return {"case": f"MR damper across {len(mr)} levels", "before_wall": wb, "before_cpu": cb,
            "after_wall": wa, "after_cpu": ca, "same_verdict": vb == va, "before": vb["verdict"],
            "after": va["verdict"]}  # fmt: skip


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="0 A and one simulated case")
    ap.add_argument("--data", type=Path, default=None, help="the real data folder (shared/data/real)")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--no-across", action="store_true", help="skip the MR levels' diagnose_across case")
    ap.add_argument("--across-only", action="store_true", help="only the MR levels' diagnose_across case")
    args = ap.parse_args(argv)
    chosen = [v for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS") if os.environ.get(v)]
    if chosen:
        print(f"note: {', '.join(chosen)} set: the BLAS switch has nothing to change", file=sys.stderr)
    A = _adapters()
    levels = [0.0] if args.quick else list(A.MR_CURRENTS)
    data = _data_dir(args.data, A)
    cases = simulated_cases(1 if args.quick else 3) + mr_cases(data, A, levels)
    cases += [] if args.quick else wire_rope_case(data, A)
    cases = [] if args.across_only else cases
    load0 = os.getloadavg()[0]
    rows: list[dict[str, Any]] = []
    for label, make in cases:
        items = make()
        if not rows:
            timed(items, True)  # warm-up: imports, caches (not counted)
        print(f"{label}: before ...", file=sys.stderr, flush=True)
        wb, cb, vb = timed(items, False)
        print(f"{label}: after ...", file=sys.stderr, flush=True)
        wa, ca, va = timed(items, True)
        rows.append(
            {"case": label, "before_wall": wb, "before_cpu": cb, "after_wall": wa, "after_cpu": ca,
             "same_verdict": vb == va, "before": vb, "after": va}
        )  # fmt: skip
        print(f"{label}: {wb:.1f} s -> {wa:.1f} s, same verdict: {vb == va}", file=sys.stderr, flush=True)
    if not args.no_across:  # the joint selection over the levels (the whole result compared, not the verdict)
        rows.append(across_row(data, A, [0.0, 0.25] if args.quick else list(A.MR_CURRENTS)))
        r = rows[-1]
        took = f"{r['before_wall']:.1f} s -> {r['after_wall']:.1f} s"
        print(f"{r['case']}: {took}", file=sys.stderr, flush=True)
    load1 = os.getloadavg()[0]
    print("| case | before: wall / CPU s | after: wall / CPU s | after/before: wall / CPU | same verdict |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(
            f"| {r['case']} | {r['before_wall']:.1f} / {r['before_cpu']:.1f} | {r['after_wall']:.1f} / "
            f"{r['after_cpu']:.1f} | {r['after_wall'] / r['before_wall']:.2f} / "
            f"{r['after_cpu'] / max(r['before_cpu'], 1e-9):.2f} | {'yes' if r['same_verdict'] else 'NO'} |"
        )
    print(f"\nload average {load0:.1f} at the start, {load1:.1f} at the end; {os.cpu_count()} CPUs")
    for r in rows:
        if not r["same_verdict"]:
            print(f"\n{r['case']}: verdicts differ\n  before: {r['before']}\n  after:  {r['after']}")
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "load": [load0, load1]}, indent=1))
    return 0 if all(r["same_verdict"] for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
