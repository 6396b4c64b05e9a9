"""MR damper: Spencer's model in the library's terms, the place of the viscous term, and 0.25 A (issue 18).

Three questions, answered with the library's own fits (``diagnosis.fitting.fit_with`` from the diagnosis's
own starts, held out as the diagnosis holds out: physics fitted on five files, the sixth's |G| and phase
refitted):

1. **Spencer's model as the library draws it.** Spencer, Dyke, Sain & Carlson (1997) with its inner spring
   k0 = 0 is, term for term, ``offset`` (-k1 x0) + ``stiffness@x`` (k1) + ``series_dashpot`` (rho = 1/c1)
   + a dashpot across the whole damper (c0; ``viscous@x`` in the library's map, ``terms/_hysteretic.py``;
   ``viscous`` on u is the same dashpot when x = u). Forced at every level, with and without the MR loop's
   asymmetry: held-out NRMSE per file, cost over the plain fit's, the values per level. (k0 has no library
   term; ``studies/mr_spencer.py`` fits the full model outside the library and finds k0 -> 0.)
2. **Why the viscous term sits on x at 0 A and on u at 0.5-1 A.** With a free |G_i| and phase per file,
   ``viscous`` on u is one dashpot on the rod's velocity, ``viscous@x`` one on ``x_i = |G_i| u`` shifted by
   phi_i, i.e. a dashpot ``c |G_i|`` on the rod velocity that differs per file. The two places differ only
   as much as the gains do. Per level: each place forced alone and with the offset (cost, held-out), and the
   plain fit's spread of |G_i| (max / min) and of phi_i.
3. **Is 0.25 A's "unexplained" the data or the physics?** The level diagnosed with each file left out in
   turn (``bw.diagnose`` on five files): which file, if any, turns the verdict into the other levels'.

Nothing is random; a rerun prints the same tables. Usage:
``python studies/mr_place.py [--data DIR] [--levels 0,0.25] [--no-leave-out] [--json OUT]``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path
from typing import Any, Optional

import bouc_wen_id as bw
import numpy as np

HERE = Path(__file__).resolve().parent
if str(HERE) not in sys.path:  # the sibling modules import by name (studies/ is not a package)
    sys.path.insert(0, str(HERE))

import mr_what_is_left as L  # noqa: E402

#: Spencer with k0 = 0 in the library's terms (c0 across the whole damper on x, as the registry maps it),
#: the same with c0 on u, and each with the MR loop's asymmetry.
SPENCER = ("offset", "stiffness@x", "series_dashpot", "viscous@x")
SPENCER_U = ("offset", "stiffness@x", "series_dashpot", "viscous")
#: The joint selection's candidates: every term of the forced sets, at both places.
ACROSS = ("offset", "viscous", "viscous@x", "stiffness", "stiffness@x", "asymmetry", "series_dashpot")
SETS: tuple[tuple[str, ...], ...] = (
    ("viscous",),
    ("viscous@x",),
    ("offset", "viscous"),
    ("offset", "viscous@x"),
    SPENCER,
    SPENCER_U,
    SPENCER + ("asymmetry",),
    SPENCER_U + ("asymmetry",),
)


def gain_spread(lv: Any) -> dict[str, float]:
    """The plain fit's |G_i| max / min and phi_i spread (degrees) over the level's files."""
    p = lv.diagnosis.plain_fit.params
    g = np.abs(np.asarray(p.gains, dtype=np.float64))
    ph = np.unwrap(np.asarray(p.phases, dtype=np.float64))
    spread = float(np.degrees(ph.max() - ph.min()))
    return {"gain_ratio": float(g.max() / g.min()), "phase_spread_deg": spread}


def on_rod(lv: Any, fit: Any) -> dict[str, list[float]]:
    """A term on x as the rod sees it, per file: ``value |G_i|`` with ``|G_i|`` in N/mm (x in N), so a
    dashpot on x in s becomes N s/mm on the rod and a spring on x (dimensionless) N/mm: one value for all
    files only if the gains are one."""
    g = np.abs(np.asarray(fit.params.gains, dtype=np.float64)) * lv.scale.y / lv.scale.u
    on_x = [t for t in fit.params.terms if t.endswith("@x")]
    return {t: [L.physical(fit, lv.scale, t)[0] * float(gi) for gi in g] for t in on_x}


def across(levels: list[tuple[str, list[Any]]], candidates: list[str]) -> dict[str, Any]:
    """``bw.diagnose_across`` on the levels with ``candidates`` (Spencer's terms among them): the joint
    structure, each step's shares, and whether the chosen term's other place was said as an alternative."""
    a = L._quiet(
        bw.diagnose_across,
        [ms for _, ms in levels],
        [float(lab.split()[0]) for lab, _ in levels],
        labels=[lab for lab, _ in levels],
        candidates=candidates,
        y_unit="N",
        u_unit="mm",
    )
    steps = [
        {
            "chosen": st.chosen,
            "shares": {t.term: t.share for t in st.trials},
            "passed": [t.term for t in st.trials if t.passed],
            "rivals": list(st.rivals),
            "alternatives": [(x.term, x.rival) for x in st.alternatives],
        }
        for st in a.steps
    ]
    ho = [c.held_out_joint for c in a.conditions]
    unsettled = {str(k): v for k, v in dict(a.settings.get("not_settled", {})).items()}
    return {
        "verdict": a.verdict,
        "named": list(a.named),
        "steps": steps,
        "seconds": a.seconds,
        "not_settled": unsettled,
        "held_out": ho,
    }


def run_sets(lv: Any) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for terms in SETS:
        t0 = time.perf_counter()
        f = L.forced(lv, terms)
        key = "+".join(terms)
        out[key] = None if f is None else L._set_result(lv, f)
        if f is not None:
            g = np.abs(np.asarray(f.params.gains, dtype=np.float64))
            out[key]["gain_ratio"] = float(g.max() / g.min())
            out[key]["on_rod"] = on_rod(lv, f)
        print(f"  {lv.label} {key}: {time.perf_counter() - t0:.0f} s", file=sys.stderr, flush=True)
    return out


def leave_out(lv: Any) -> list[dict[str, Any]]:
    """The level diagnosed with each file left out: named terms, status, held-out median."""
    rows = []
    for i, m in enumerate(lv.ms):
        rest = [x for j, x in enumerate(lv.ms) if j != i]
        d = L._quiet(bw.diagnose, rest, y_unit="N", u_unit="mm")
        ho = tuple(d.held_out.nrmse_after) if d.held_out else ()
        rows.append(
            {
                "left_out": m.name if hasattr(m, "name") else str(i),
                "status": d.status,
                "named": list(d.final_fit.params.terms),
                "held_out": ho,
                "chi2dof": float(d.final_chi2_dof) if hasattr(d, "final_chi2_dof") else math.nan,
            }
        )
        print(f"  {lv.label} without file {i}: {d.status} {rows[-1]['named']}", file=sys.stderr, flush=True)
    return rows


def _f(v: float, nd: int = 3) -> str:
    return "-" if v is None or not math.isfinite(v) else f"{v:.{nd}g}"


def _ho(r: Optional[dict[str, Any]]) -> str:
    if r is None or not r["held_out"]:
        return "failed"
    h = r["held_out"]
    return f"{L._median(h):.3f} ({max(h):.3f}); {r['cost_ratio']:.3f}"


def print_tables(res: dict[str, Any]) -> None:
    levels = list(res)
    print("\n| term set | " + " | ".join(levels) + " |")
    print("|---|" + "---|" * len(levels))
    for terms in SETS:
        key = "+".join(terms)
        print(f"| {key} | " + " | ".join(_ho(res[lv]["sets"][key]) for lv in levels) + " |")
    print(
        "\n| level | plain |G_i| max/min | plain phi_i spread (deg) | viscous: c (N s/mm) | viscous@x: c (s) "
        "|"
    )
    print("|---|---|---|---|---|")
    for lv in levels:
        r = res[lv]
        vu = r["sets"]["viscous"]
        vx = r["sets"]["viscous@x"]
        cu = _f(vu["values"]["viscous"][0], 4) if vu else "-"
        cx = _f(vx["values"]["viscous@x"][0], 4) if vx else "-"
        sp = r["spread"]
        print(f"| {lv} | {sp['gain_ratio']:.2f} | {sp['phase_spread_deg']:.1f} | {cu} | {cx} |")
    for key in ("+".join(SPENCER), "+".join(SPENCER_U), "+".join(SPENCER + ("asymmetry",))):
        print(f"\nValues, {key} (value ± se, physical units):\n")
        names = [t for t in key.split("+")]
        print("| level | beta | gamma | mu | F_sat (N) | " + " | ".join(names) + " | held-out per file |")
        print("|---|---|---|---|---|" + "---|" * len(names) + "---|")
        for lv in levels:
            r = res[lv]["sets"][key]
            if r is None:
                print(f"| {lv} | failed |")
                continue
            vals = " | ".join(f"{_f(r['values'][t][0], 4)} ± {_f(r['values'][t][1], 2)}" for t in names)
            ho = ", ".join(f"{h:.3f}" for h in r["held_out"])
            print(
                f"| {lv} | {r['beta']:.4g} | {r['gamma']:.4g} | {r['mu']:.3f} | {r['f_sat']:.0f} | {vals} "
                f"| {ho} |"
            )
    key = "+".join(SPENCER + ("asymmetry",))
    print(f"\nTerms on x as the rod sees them (value |G_i|, per file, {key}):\n")
    print("| level | stiffness@x (N/mm): median, min-max | viscous@x (N s/mm): median, min-max |")
    print("|---|---|---|")
    for lv in levels:
        r = res[lv]["sets"][key]
        if r is None:
            continue
        cells = []
        for t in ("stiffness@x", "viscous@x"):
            v = r["on_rod"].get(t, [])
            cells.append(f"{L._median(v):.3g}, {min(v):.3g} to {max(v):.3g}" if v else "-")
        print(f"| {lv} | " + " | ".join(cells) + " |")
    for lv in levels:
        if "leave_out" in res[lv]:
            print(f"\n{lv}, each file left out in turn:\n")
            print("| left out | status | named | held-out median (max) |")
            print("|---|---|---|---|")
            for row in res[lv]["leave_out"]:
                h = row["held_out"]
                hs = f"{L._median(h):.3f} ({max(h):.3f})" if h else "-"
                print(f"| {row['left_out']} | {row['status']} | {', '.join(row['named']) or 'none'} | {hs} |")


def print_across(a: dict[str, Any]) -> None:
    print(f"\nAcross the levels (bw.diagnose_across): {a['verdict']}\n")
    print("held-out NRMSE of the joint structure (median): " + ", ".join(f"{h:.3f}" for h in a["held_out"]))
    print(f"experiments left out as not settled, per level: {a['not_settled'] or 'none'}")
    for k, st in enumerate(a["steps"], 1):
        top = sorted(st["shares"].items(), key=lambda kv: -kv[1])[:4]
        shares = ", ".join(f"{t} {v:.3f}{'' if t in st['passed'] else ' (failed)'}" for t, v in top)
        print(
            f"- step {k}: chosen {st['chosen']}; shares {shares}; rivals {st['rivals'] or 'none'}; "
            f"said as alternatives {st['alternatives'] or 'none'}"
        )


def main(argv: Optional[list[str]] = None) -> int:
    A = L._adapters()
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=A.default_data_dir())
    ap.add_argument("--levels", default=None, help="coil currents, e.g. 0,0.5 (default: all five)")
    ap.add_argument("--leave-out-levels", default="0.25", help="levels diagnosed with each file left out")
    ap.add_argument("--no-leave-out", action="store_true")
    ap.add_argument("--no-across", action="store_true")
    ap.add_argument("--across-candidates", default=",".join(ACROSS), help="the joint selection's candidates")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args(argv)
    levels = None if args.levels is None else [float(c) for c in args.levels.split(",")]
    lo = [] if args.no_leave_out else [float(c) for c in args.leave_out_levels.split(",")]
    t0 = time.perf_counter()
    res: dict[str, Any] = {}
    loaded = L.load_levels(args.data, levels)
    for label, ms in loaded:
        lv = L.prepare_level(label, ms, diagnose=False)
        r: dict[str, Any] = {"spread": gain_spread(lv), "sets": run_sets(lv)}
        if any(abs(float(label.split()[0]) - c) < 1e-9 for c in lo):
            r["leave_out"] = leave_out(lv)
        res[label] = r
    print_tables(res)
    if not args.no_across and len(loaded) > 1:
        t1 = time.perf_counter()
        res["across"] = across(loaded, args.across_candidates.split(","))
        print_across(res["across"])
        print(f"(diagnose_across: {time.perf_counter() - t1:.0f} s wall)")
    print(f"\n{time.perf_counter() - t0:.0f} s wall")
    if args.json is not None:
        args.json.write_text(json.dumps(res, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
