"""Dump the real-data diagnosis of every group of ``studies/diagnose_real.py`` (main run) to JSON:
the full ``Diagnosis.to_dict()`` of each group plus its seconds, so that a speed change can be checked
verdict-neutral (``--compare before.json``: statuses, named terms and places, alternatives exact; values to a
relative tolerance). Same inputs as the study (its ``groups`` and ``_diagnose``, imported, not copied).

Usage: ``python benches/real_verdicts.py [--data DIR] [--groups 'mr-damper 0 A,wire-rope all files']
[--json out.json] [--compare before.json] [--rtol 1e-3] [--profile out.prof] [--across]``.

``--across``: also the MR damper's current levels diagnosed with one structure (``bw.diagnose_across``, as
the study's ``across_levels``: each level's own diagnosis reused, the study's candidates), stored under
``"across"`` and compared by its verdict, named terms and their values per level.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "studies"))  # the study and its adapters, imported by name


def _study() -> Any:
    import diagnose_real

    return diagnose_real


def _numbers(v: Any, path: str = "") -> dict[str, float]:
    out: dict[str, float] = {}
    if isinstance(v, dict):
        for k, x in v.items():
            if k in ("seconds",):
                continue
            out.update(_numbers(x, f"{path}/{k}"))
    elif isinstance(v, list):
        for i, x in enumerate(v):
            out.update(_numbers(x, f"{path}[{i}]"))
    elif isinstance(v, (int, float)) and not isinstance(v, bool):
        out[path] = float(v)
    return out


def _strings(v: Any, path: str = "") -> dict[str, str]:
    out: dict[str, str] = {}
    if isinstance(v, dict):
        for k, x in v.items():
            out.update(_strings(x, f"{path}/{k}"))
    elif isinstance(v, list):
        for i, x in enumerate(v):
            out.update(_strings(x, f"{path}[{i}]"))
    elif isinstance(v, str):
        out[path] = v
    return out


def compare(before: dict[str, Any], after: dict[str, Any], rtol: float) -> list[str]:
    """Differences: exact for statuses, terms, places, alternatives' terms; ``rtol`` for the named values."""
    bad: list[str] = []
    for g, b in before["groups"].items():
        a = after["groups"].get(g)
        if a is None:
            bad.append(f"{g}: missing after")
            continue
        db, da = b["diagnosis"], a["diagnosis"]
        for key in ("status", "named", "partial", "alternatives"):
            sb = json.dumps(_strip(db.get(key)), sort_keys=True)
            sa = json.dumps(_strip(da.get(key)), sort_keys=True)
            if sb != sa:
                bad.append(f"{g}: {key} differs:\n   before {sb[:600]}\n   after  {sa[:600]}")
        for key in ("named", "partial"):
            nb, na = _numbers(db.get(key)), _numbers(da.get(key))
            for p, x in nb.items():
                y = na.get(p)
                if y is None or abs(x - y) > rtol * max(abs(x), abs(y), 1e-300):
                    bad.append(f"{g}: {key}{p}: {x!r} -> {y!r}")
    return bad


def _across(S: Any, mr: list[tuple[str, Any, Any]]) -> dict[str, Any]:
    """The MR damper's levels across (the study's ``mr_across``, its inputs as there): ``to_dict()``."""
    a = S.mr_across(mr, progress=False)
    print(f"mr-damper across levels: {a.verdict} ({a.seconds:.1f} s)", file=sys.stderr)
    return {"seconds": a.seconds, "diagnosis": S.clean(a.to_dict())}


def compare_across(before: dict[str, Any], after: dict[str, Any], rtol: float) -> list[str]:
    """Differences of the across run: its verdict and named terms exact, their values to ``rtol``."""
    db, da = before.get("diagnosis", {}), after.get("diagnosis", {})
    bad = [f"across: verdict differs:\n   before {db.get('verdict')}\n   after  {da.get('verdict')}"]
    if db.get("verdict") == da.get("verdict"):
        bad = []
    tb = {t["term"]: t for t in db.get("terms", [])}
    ta = {t["term"]: t for t in da.get("terms", [])}
    if list(tb) != list(ta):
        bad.append(f"across: named {list(tb)} -> {list(ta)}")
    for k in set(tb) & set(ta):
        for i, (x, y) in enumerate(zip(tb[k]["values"], ta[k]["values"])):
            if x is None or y is None or abs(x - y) > rtol * max(abs(x), abs(y), 1e-300):
                bad.append(f"across: {k} value [{i}]: {x!r} -> {y!r}")
    return bad


def identical(before: dict[str, Any], after: dict[str, Any], group: str) -> bool:
    """Whether a group's whole diagnosis (every number, bit for bit) is the same, its seconds aside."""

    def timeless(v: Any) -> Any:
        if isinstance(v, dict):
            return {k: timeless(x) for k, x in v.items() if k not in ("seconds", "wall", "cpu")}
        if isinstance(v, list):
            return [timeless(x) for x in v]
        return v

    a = after["groups"].get(group)
    b = before["groups"][group]
    return a is not None and json.dumps(timeless(b), sort_keys=True) == json.dumps(
        timeless(a), sort_keys=True
    )


def _strip(v: Any) -> Any:
    """The non-numeric skeleton (names, places, flags) of a term list or status."""
    if isinstance(v, dict):
        return {k: _strip(x) for k, x in v.items() if not isinstance(x, float)}
    if isinstance(v, list):
        return [_strip(x) for x in v]
    return v


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=Path("/work/shared/data/real"))
    ap.add_argument("--groups", default="", help="comma-separated 'dataset label' names (default: all)")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--compare", type=Path)
    ap.add_argument("--rtol", type=float, default=1e-3)
    ap.add_argument("--profile", type=Path)
    ap.add_argument("--across", action="store_true", help="also the MR damper's levels across (see above)")
    args = ap.parse_args(argv)
    S = _study()
    datasets = "mr-damper,friction-damper,wire-rope,bh-microwire".split(",")
    want = [g.strip() for g in args.groups.split(",") if g.strip()]
    out: dict[str, Any] = {"load_start": os.getloadavg()[0], "groups": {}}
    prof = None
    if args.profile:
        import cProfile

        prof = cProfile.Profile()
    t0 = time.perf_counter()
    mr: list[tuple[str, Any, Any]] = []  # (label, measurements, own diagnosis) of the MR damper's levels
    for dataset, label, ms in S.groups(args.data, datasets):
        name = f"{dataset} {label}"
        if want and name not in want:
            continue
        t = time.perf_counter()
        c = time.process_time()
        if prof is not None:
            prof.enable()
        try:
            d = S._diagnose(ms, ms[0].units, False)
        except Exception as exc:  # noqa: BLE001 - recorded, compared
            out["groups"][name] = {"error": f"{type(exc).__name__}: {exc}", "diagnosis": {}}
            continue
        finally:
            if prof is not None:
                prof.disable()
        wall = time.perf_counter() - t
        cpu = time.process_time() - c
        if dataset == "mr-damper":
            mr.append((label, ms, d))
        out["groups"][name] = {
            "seconds": d.seconds,
            "wall": wall,
            "cpu": cpu,
            "diagnosis": S.clean(d.to_dict()),
        }
        print(
            f"{name}: {d.status} {[t.term for t in d.named]} {d.seconds:.1f} s, CPU {cpu:.1f} s",
            file=sys.stderr,
        )
    if args.across and len(mr) >= 2:
        out["across"] = _across(S, mr)
    out["total"] = time.perf_counter() - t0
    out["load_end"] = os.getloadavg()[0]
    if prof is not None:
        prof.dump_stats(str(args.profile))
    if args.json:
        args.json.write_text(json.dumps(out, indent=1, allow_nan=True))
    if args.compare:
        before = json.loads(args.compare.read_text())
        bad = compare(before, out, args.rtol)
        if "across" in before or "across" in out:
            bad += compare_across(before.get("across", {}), out.get("across", {}), args.rtol)
        print("\n".join(bad) if bad else "verdict-neutral: no differences", file=sys.stderr)
        same = [g for g in before["groups"] if identical(before, out, g)]
        print(
            f"whole Diagnosis.to_dict() identical but seconds: {len(same)} of {len(before['groups'])}",
        )
        return 1 if bad else 0
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
