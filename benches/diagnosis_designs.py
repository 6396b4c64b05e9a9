"""The diagnosis on other experiment designs and other noise (issue 18: "test every claim on data made another
way than the bench that shaped the code").

``benches/diagnosis.py`` always uses one design: five frequencies x two saturating amplitudes, 16 averaged
periods, white Gaussian noise at 1 % of the saturation level. Here the plants, G shapes and hysteresis are
those of ``benches/generator.py`` (its ``make_plant`` per seed: first-order, resonant with a delay, near-flat
G; its exact G, its own RK4 of the hysteresis, its effects), but the experiment plan and the noise are this
file's:

- designs (white noise): ``base`` (the bench's own: 5 f x 2 A, 16 periods), ``3f x 1A``, ``2f x 4A``,
  ``8f x 1A``, ``below-sat`` (3 f x {0.4, 2.0}: one amplitude per frequency below saturation, from rest),
  ``4 periods`` and ``64 periods`` (the base plan);
- noise (base plan): ``ar1`` (AR(1) output noise, phi = 0.8, the same marginal sd), ``ar1 slow`` (phi = 0.99:
  correlated over about a period, so neighbouring periods are correlated too), ``t3`` (Student t with 3
  degrees of freedom scaled to the same sd), ``quant`` (white noise, then the output rounded to ADC steps of
  0.5 noise sd), ``u-noise`` (white noise on the measured input too, 1 % of its amplitude), ``pink`` (1/f
  noise shaped in the frequency domain, the same sd), ``walk`` (white noise plus a random-walk baseline,
  steps of 0.05 noise sd per sample: 2.5 noise sd of wander over the record).

Effects: nulls (nothing hidden), viscous damping on x, stiffness on u, stiffness on x, output offset, play,
strength degradation, each sized as in the bench (RMS of its noise-free contribution over the averaged
periods in averaged-noise sd, ``sd / sqrt(periods)``, at 10x and 30x; achieved size printed).

Per row: n, right name (+ place), wrong name, "unexplained", bad (status "explained" while the final model
fails its adequacy test), crashes (any exception: named = a ``BoucWenIdError``, else "other"), seconds per
diagnosis. With ``--cli K`` the first K cases of every row are also written with the library's writer
(``bw.io.save``, a folder of CSV files) and diagnosed by ``bouc-wen-id diagnose`` in a subprocess: the row
counts CLI crashes and verdicts that differ from the API's.

Usage: ``python benches/diagnosis_designs.py [--quick] [--cases N] [--null N] [--workers 2] [--seed S]
[--only designs] [--effects names] [--cli K] [--json out.json]``. ``--quick``: base, 3f x 1A, ar1 and quant,
nulls and viscous on x at 10x, 2 cases each (<= 2 min on two idle cores).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
import warnings
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Optional

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import generator as gen  # noqa: E402  (benches/ on the path first)

FloatArray = gen.FloatArray
NOISE_SD = gen.NOISE_SD


@dataclass(frozen=True)
class Design:
    """An experiment plan: frequency factors (times the plant's centre), latent levels |x| per frequency,
    averaged and settle periods, and the noise."""

    name: str
    factors: tuple[float, ...] = gen.FREQ_FACTORS
    levels: tuple[float, ...] = gen.X_LEVELS
    periods: int = gen.PERIODS
    settle: int = gen.SETTLE
    noise: str = "white"  # white, ar1, t3, quant, u-noise, pink, walk
    phi: float = 0.8  # the AR(1) coefficient (noise "ar1")


DESIGNS = {
    d.name: d
    for d in (
        Design("base"),
        Design("3f x 1A", factors=(0.5, 1.0, 2.0), levels=(2.0,)),
        Design("2f x 4A", factors=(0.75, 1.4), levels=(1.2, 1.8, 2.4, 3.0)),
        Design("8f x 1A", factors=tuple(float(v) for v in np.geomspace(0.4, 2.5, 8)), levels=(2.0,)),
        Design("below-sat", factors=(0.5, 1.0, 2.0), levels=(0.4, 2.0)),
        Design("4 periods", periods=4),
        Design("64 periods", periods=64),
        Design("ar1", noise="ar1"),
        Design("ar1 slow", noise="ar1", phi=0.99),
        Design("t3", noise="t3"),
        Design("quant", noise="quant"),
        Design("u-noise", noise="u-noise"),
        Design("pink", noise="pink"),
        Design("walk", noise="walk"),
    )
}
T_DOF = 3
QUANT_STEP = 0.5  # ADC step in noise sd
U_NOISE = 0.01  # input noise sd, relative to the input amplitude
WALK_STEP = 0.05  # the random walk's step sd per sample, in noise sd (2.5 noise sd after 2560 samples)

#: (name, place) of the effects; place "" for effects that have one place.
EFFECTS = (
    ("viscous", "x"),
    ("stiffness", "u"),
    ("stiffness", "x"),
    ("offset", ""),
    ("play", ""),
    ("degradation", ""),
)


def plant_for(design: Design, seed: int) -> gen.Plant:
    """The generator's seeded plant (G, delay, hysteresis), re-planned to ``design``."""
    p = gen.make_plant(seed)
    centre = float(p.omegas[2 * list(gen.FREQ_FACTORS).index(1.0)])
    om = np.repeat(centre * np.asarray(design.factors), len(design.levels))
    levels = np.tile(np.asarray(design.levels, dtype=float), len(design.factors))
    q = replace(p, omegas=om, amplitudes=levels, levels=levels, w0=None)
    g = np.abs(q.freqresp(om))
    return replace(q, amplitudes=levels / g)


def _steady_rms(y: FloatArray, plain: FloatArray, design: Design) -> FloatArray:
    """RMS of ``y - plain`` over the averaged periods, in averaged-noise sd (trials)."""
    s = design.settle * gen.P
    rms = np.sqrt(np.mean((y[..., s:] - plain[..., s:]) ** 2, axis=(-2, -1)))
    return np.asarray(rms / (NOISE_SD / math.sqrt(design.periods)))


def outputs(p: gen.Plant, design: Design, name: Optional[str], place: str, size: float) -> tuple[Any, ...]:
    """Noise-free outputs (experiments x samples) with the effect sized to ``size``; (y, value, achieved)."""
    total = (design.settle + design.periods) * gen.P
    b = gen.base(p, total)
    plain = gen.run(p, gen.Effect(), total, b)
    if name is None:
        return plain[0], 0.0, 0.0
    if name in gen.LINEAR:
        unit = float(_steady_rms(gen.run(p, gen.Effect(name, place, np.ones(1)), total, b), plain, design)[0])
        v = size / unit
        y = gen.run(p, gen.Effect(name, place, np.array([v])), total, b)
        return y[0], v, float(_steady_rms(y, plain, design)[0])
    hi = gen.upper_value(p, name)
    vals = hi * np.logspace(-3.0, 0.0, 7)
    c = _steady_rms(gen.run(p, gen.Effect(name, place, vals), total, b), plain, design)
    ok = np.isfinite(c) & (c > 0)
    lv, lc = np.log(vals[ok]), np.log(c[ok])
    order = np.argsort(lc)
    v = float(np.exp(np.interp(math.log(size), lc[order], lv[order])))
    y = gen.run(p, gen.Effect(name, place, np.array([v])), total, b)
    return y[0], v, float(_steady_rms(y, plain, design)[0])


def noise(design: Design, rng: np.random.Generator, n: int) -> FloatArray:
    """Output noise of marginal sd ``NOISE_SD`` of the design's kind (before any quantisation)."""
    if design.noise == "ar1":
        phi = design.phi
        z = rng.normal(0.0, NOISE_SD * math.sqrt(1.0 - phi**2), n)
        e = np.empty(n)
        e[0] = rng.normal(0.0, NOISE_SD)  # stationary start
        for k in range(1, n):
            e[k] = phi * e[k - 1] + z[k]
        return e
    if design.noise == "pink":  # 1/f noise shaped in the frequency domain, no AR recursion
        f = np.fft.rfftfreq(n)
        amp = np.zeros(f.size)
        amp[1:] = 1.0 / np.sqrt(f[1:])
        x = np.fft.irfft(amp * (rng.normal(size=f.size) + 1j * rng.normal(size=f.size)), n)
        return np.asarray(x * NOISE_SD / x.std())
    if design.noise == "walk":  # a random-walk baseline wander plus white noise
        walk = np.cumsum(rng.normal(0.0, WALK_STEP * NOISE_SD, n))
        return np.asarray(walk + rng.normal(0.0, NOISE_SD, n))
    if design.noise == "t3":
        return np.asarray(rng.standard_t(T_DOF, n) * NOISE_SD / math.sqrt(T_DOF / (T_DOF - 2.0)))
    return np.asarray(rng.normal(0.0, NOISE_SD, n))


def recordings(p: gen.Plant, design: Design, y: FloatArray, seed: int) -> list[Any]:
    """``bw.Recording`` objects of ``y`` with the design's noise, as a user's files."""
    import bouc_wen_id as bw

    rng = np.random.default_rng([seed, 29])
    out = []
    for i in range(p.omegas.size):
        n = y.shape[-1]
        dt = gen.TWO_PI / float(p.omegas[i]) / gen.P
        t = np.arange(n) * dt
        u = float(p.amplitudes[i]) * np.cos(float(p.omegas[i]) * t)
        yy = y[i] + noise(design, rng, n)
        if design.noise == "quant":
            q = QUANT_STEP * NOISE_SD
            yy = np.round(yy / q) * q
        if design.noise == "u-noise":
            u = u + rng.normal(0.0, U_NOISE * float(p.amplitudes[i]), n)
        out.append(
            bw.Recording(
                t,
                u,
                yy,
                float(p.amplitudes[i]),
                float(p.omegas[i]),
                settle_periods=design.settle,
                metadata={"name": f"exp{i}", "source": "benches/diagnosis_designs.py"},
            )
        )
    return out


def _cli(recs: list[Any]) -> dict[str, Any]:
    """Write ``recs`` with the library's writer and run ``bouc-wen-id diagnose`` on the folder."""
    import bouc_wen_id as bw

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "recs"
        bw.io.save(folder, recs)
        out = Path(tmp) / "diag"
        env = dict(os.environ)
        cmd = [sys.executable, "-m", "bouc_wen_id", "diagnose", str(folder), "--out", str(out)]
        cmd.append("--no-figures")
        r = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=900)
        res: dict[str, Any] = {"cli_rc": r.returncode}
        js = out / "diagnosis.json"
        if r.returncode == 0 and js.exists():
            res["cli_status"] = json.loads(js.read_text()).get("status")
        else:
            res["cli_error"] = (r.stderr.strip().splitlines() or ["(no stderr)"])[-1][:300]
        return res


def run_case(job: tuple[str, Optional[str], str, float, int, bool]) -> dict[str, Any]:
    """Generate one case, diagnose it (and, with ``cli``, through the CLI too), score it."""
    import bouc_wen_id as bw
    import diagnosis as bench

    dname, name, place, size, seed, cli = job
    design = DESIGNS[dname]
    row: dict[str, Any] = {"design": dname, "term": name, "place": place, "size": size, "seed": seed}
    try:
        p = plant_for(design, seed)
        y, value, got = outputs(p, design, name, place, size)
        recs = recordings(p, design, y, seed)
    except Exception as exc:  # the generator's own failure, not the diagnosis's
        row["gen_error"] = f"{type(exc).__name__}: {exc}"
        return row
    row.update(shape=p.shape, value=value, achieved=got)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            d = bw.diagnose(recs)
        except bw.BoucWenIdError as exc:
            row["error"] = f"named {type(exc).__name__}: {exc}"[:300]
            return row
        except Exception as exc:  # a crash is a finding
            row["error"] = f"other {type(exc).__name__}: {exc}"[:300]
            return row
    row["seconds"] = time.perf_counter() - t0
    kind = "null" if name is None else "library"
    row.update(bench._score(d, kind, name, place))
    row["final_chi2_dof"] = float(d.final.cost / max(d.final.dof, 1))
    row["plain_p"] = float(d.plain.p_value)
    row["notes"] = list(d.notes)
    if cli:
        row.update(_cli(recs))
        if "cli_status" in row:
            row["cli_differs"] = row["cli_status"] != row["status"]
    return row


def jobs(args: argparse.Namespace) -> list[tuple[str, Optional[str], str, float, int, bool]]:
    """Every (design, effect, size) cell's cases; the seeds of a cell do not depend on the other cells."""
    out = []
    designs = [d for d in DESIGNS if not args.only or d in args.only.split(",")]
    keep = args.effects.split(",") if args.effects else []
    effects = [e for e in EFFECTS if not keep or f"{e[0]}@{e[1]}".rstrip("@") in keep]
    sizes = [float(s) for s in args.sizes.split(",")]
    for d in designs:
        cells: list[tuple[Optional[str], str, float, int, int]] = [(None, "", 0.0, args.null, 0)]
        for n, pl in effects:  # seeds by the effect's index in EFFECTS: the same whatever is filtered
            k = EFFECTS.index((n, pl))
            cells += [(n, pl, sz, args.cases, 100 * (k + 1) + int(sz)) for sz in sizes]
        for name, place, size, count, off in cells:
            for s in range(count):
                seed = args.seed + 100_000 + 1000 * off + s  # a case's plant depends on its cell and index
                out.append((d, name, place, size, seed, s < args.cli))
    return out


def summarise(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    groups: dict[tuple[str, str, float], list[dict[str, Any]]] = {}
    for r in rows:
        what = "null" if r["term"] is None else (r["term"] + (f"@{r['place']}" if r["place"] else ""))
        groups.setdefault((r["design"], what, r["size"]), []).append(r)
    out = []
    for (design, what, size), rs in groups.items():
        ok = [r for r in rs if "error" not in r and "gen_error" not in r]

        def rate(key: str, ok: list[dict[str, Any]] = ok) -> float:
            return float(np.mean([bool(r.get(key)) for r in ok])) if ok else math.nan

        secs = [r["seconds"] for r in ok]
        cli = [r for r in rs if "cli_rc" in r]
        out.append(
            {
                "design": design,
                "effect": what,
                "size": size,
                "n": len(rs),
                "right": rate("right"),
                "right_place": rate("right_place"),
                "wrong": rate("wrong"),
                "unexplained": rate("unexplained"),
                "adequate": float(np.mean([r.get("status") == "adequate" for r in ok])) if ok else math.nan,
                "bad": rate("bad_explained"),
                "named_err": sum(str(r.get("error", "")).startswith("named") for r in rs),
                "other_err": sum(str(r.get("error", "")).startswith("other") for r in rs),
                "gen_err": sum("gen_error" in r for r in rs),
                "seconds": float(np.median(secs)) if secs else math.nan,
                "achieved": float(np.median([r["achieved"] for r in ok])) if ok else math.nan,
                "cli": len(cli),
                "cli_fail": sum(r["cli_rc"] != 0 for r in cli),
                "cli_differs": sum(bool(r.get("cli_differs")) for r in cli),
            }
        )
    return out


def print_table(lines: list[dict[str, Any]]) -> None:
    head = (
        f"{'design/noise':<11} {'effect':<14} {'n':>3} {'name':>5} {'+place':>6} {'wrong':>5} {'unexpl':>6} "
        f"{'adeq':>5} {'bad':>4} {'crash':>7} {'s/diag':>6} {'size':>5} {'cli':>7}"
    )
    print(head)
    print("-" * len(head))
    for ln in lines:
        eff = ln["effect"] + (f" {ln['size']:g}x" if ln["size"] else "")
        crash = f"{ln['named_err']}n/{ln['other_err']}o"
        cli = f"{ln['cli_fail']}f/{ln['cli_differs']}d" if ln["cli"] else "-"
        print(
            f"{ln['design']:<11} {eff:<14} {ln['n']:>3} {ln['right']:5.2f} {ln['right_place']:6.2f} "
            f"{ln['wrong']:5.2f} {ln['unexplained']:6.2f} {ln['adequate']:5.2f} {ln['bad']:4.2f} {crash:>7} "
            f"{ln['seconds']:6.2f} {ln['achieved']:5.1f} {cli:>7}"
        )
    print(
        "\nname/+place: the hidden term named (at its place); wrong: a term named that is not the hidden one "
        "(on nulls: any term); unexpl: status 'unexplained'; adeq: status 'adequate'; bad: 'explained' "
        "while the final model fails its adequacy test; crash: named (BoucWenIdError) / other exceptions; "
        "cli: of the cases also run through `bouc-wen-id diagnose` on CSV files, f = failed, d = status "
        "differs from the API's"
    )


def print_compact(rows: list[dict[str, Any]]) -> None:
    """One line per design/noise: nulls (named, unexplained) and the effect rows pooled (right name at its
    place, right name at the other place with that place listed as its alternative, wrong, unexplained)."""
    print(
        f"\n{'design/noise':<11} {'nulls':>5} {'named':>5} {'unexpl':>6} | {'cases':>5} {'+place':>6} "
        f"{'alt':>4} {'wrong':>5} {'unexpl':>6} {'bad':>4} {'crash':>5} {'s/diag':>6}"
    )
    for design in dict.fromkeys(r["design"] for r in rows):
        rs = [r for r in rows if r["design"] == design]
        ok = [r for r in rs if "status" in r]
        nul = [r for r in ok if r["term"] is None]
        eff = [r for r in ok if r["term"] is not None]
        alt = [
            r
            for r in eff
            if r["right"] and not r["right_place"] and r["term"] in {a for a in r["alternatives"]}
        ]

        def n(rr: list[dict[str, Any]], key: str) -> int:
            return sum(bool(r.get(key)) for r in rr)

        secs = float(np.median([r["seconds"] for r in ok])) if ok else math.nan
        print(
            f"{design:<11} {len(nul):>5} {n(nul, 'wrong'):>5} {n(nul, 'unexplained'):>6} | {len(eff):>5} "
            f"{n(eff, 'right_place'):>6} {len(alt):>4} {n(eff, 'wrong'):>5} {n(eff, 'unexplained'):>6} "
            f"{n(ok, 'bad_explained'):>4} {len(rs) - len(ok):>5} {secs:6.2f}"
        )


def main(argv: Optional[list[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--cases", type=int, default=5)
    ap.add_argument("--null", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--only", default="", help="comma-separated designs (" + ", ".join(DESIGNS) + ")")
    ap.add_argument("--effects", default="", help="comma-separated effects, e.g. viscous@x,offset")
    ap.add_argument("--sizes", default="10,30")
    ap.add_argument("--cli", type=int, default=0, help="cases per cell also run through the CLI")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--table", type=Path, default=None, help="re-print the table of a saved --json run")
    args = ap.parse_args(argv)
    if args.table:
        saved = json.loads(args.table.read_text())["rows"]
        print_table(summarise(saved))
        print_compact(saved)
        return 0
    if args.quick:
        args.only = args.only or "base,3f x 1A,ar1,quant"
        args.effects = args.effects or "viscous@x"
        args.sizes, args.cases, args.null = "10", min(args.cases, 2), min(args.null, 2)
    todo = jobs(args)
    t0 = time.perf_counter()
    rows: list[Optional[dict[str, Any]]] = [None] * len(todo)
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        futs = {pool.submit(run_case, j): k for k, j in enumerate(todo)}
        for done, fut in enumerate(as_completed(futs), 1):
            r = fut.result()
            rows[futs[fut]] = r
            where = "@" + r["place"] if r["place"] else ""
            what = f"{r['design']} {r['term'] or 'null'}{where} {r['size']:g}x"
            status = r.get("status", r.get("error", r.get("gen_error")))
            print(f"[{done}/{len(todo)}] {what} seed {r['seed']}: {status}", file=sys.stderr, flush=True)
    got = [r for r in rows if r is not None]
    print_table(summarise(got))
    print_compact(got)
    print(f"\n{len(got)} diagnoses in {time.perf_counter() - t0:.0f} s wall on {args.workers} workers")
    if args.json:
        args.json.write_text(json.dumps({"rows": got, "table": summarise(got)}, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
