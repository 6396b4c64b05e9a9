"""Review 47's driver: a case built by sim47.py, then ``bw.diagnose`` (its defaults) in a process of its own.

Run from the repository root with PYTHONPATH=python; the first argument says what:

* ``run OUT [ID ...]``: every planned case (or the ids given) not yet in the JSON-lines file OUT;
* ``--one ID``: one case in this process, its record printed;
* ``--list``: the planned ids;  ``--write ID DIR``: the case's recordings as CSV files (t, u, y).

An id is ``effect-size-config-seed`` (the seed drives the noise only). The child (``nice -n 15``,
OMP_NUM_THREADS=1, 180 s) is review 46's runner of review 45's ``diagnose_child`` (the same record fields).
"""

from __future__ import annotations

import json
import math
import pickle
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "review46"))
import drive46 as dv46  # noqa: E402
import sim47 as s  # noqa: E402

SD = 0.01  # times w_u: the noise is sized to the element's saturation level
G2 = s.two_mode(2.2, 0.08, 7.0, 0.06)
SWEEP = tuple(float(w) for w in np.geomspace(0.7, 11.0, 12))
PLANS = {
    # 3 frequencies only, one amplitude each (not shared), unequal settle
    "A3": s.Plan((1.0, 3.0, 9.0), (0.6, 1.0, 1.7), 6, (8, 15, 30), (200.0,) * 3),
    # a sweep: 12 frequencies, 4 periods each
    "SW12": s.Plan(SWEEP, (1.0,) * 12, 4, (6,) * 12, (128.0,) * 12),
    # 4 f x 2 U, settle unequal
    "U8": s.Plan((1.2, 2.5, 5.0, 10.0) * 2, (0.5,) * 4 + (1.0,) * 4, 8, (5, 10, 20, 40) * 2, (160.0,) * 8),
    # samples per period not whole: bw.Measurement (the library finds the frequency)
    "NP": s.Plan(
        (1.3, 4.1) * 2,
        (0.6,) * 2 + (1.2,) * 2,
        10,
        (12,) * 4,
        (2 * math.pi / 1.3 / 0.0237, 2 * math.pi / 4.1 / 0.0237) * 2,
    ),
}
GS = {
    "2mode": G2,
    "nmp": s.nonmin(4.0, 0.1),
    "integ": s.integrator(2.0, 0.3, 0.05),
    "lp": s.lowpass(0.08),
}
ELEMENTS = {
    "b.7g.3mu2": s.Element(1.0, 0.7, 0.3, 2.0),
    "soft": s.Element(1.0, 1.0, -0.9, 1.5),  # gamma/beta = -0.9: softening
    "mu1a4": s.Element(4.0, 0.5, 0.5, 1.0),  # n = mu = 1 with alpha 4
    "mu.75": s.Element(1.0, 0.5, 0.5, 0.75),  # outside the library (mu >= 1)
}
CONFIGS: dict[str, tuple[str, ...]] = {
    row.split(":")[0]: tuple(row.split(":")[1].split())
    for row in (
        "J: A3 2mode hetero b.7g.3mu2; K: SW12 nmp outliers soft; L: U8 integ drift mu1a4; "
        "M: U8 lp ar1 mu.75; N: NP 2mode ar1 b.7g.3mu2; "
        "Lw: U8 integ white mu1a4; Mw: U8 lp white mu.75; Mm: U8 lp ar1 b.7g.3mu2"
    ).split("; ")
}
#: effect -> the library's term (None: physics outside the library)
TRUTH_TERM: dict[str, str | None] = {
    "stiffness": "stiffness",
    "stiffness_x": "stiffness@x",
    "viscous": "viscous",
    "viscous_x": "viscous@x",
    "inertia": "inertia",
    "inertia_x": "inertia@x",
    "coulomb": "coulomb",
    "coulomb_x": "coulomb@x",
    "offset": "offset",
    "nu": "degradation",
    "eta": "stiffness_degradation",
    "pinch": "pinching",
    "delta": "asymmetry",
    "dahl2": None,  # Dahl on u with exponent 2: the library's dahl (exponent 1) is of the same family
    "pi_x": None,
    "rate": None,
    "backlash": None,
}
ORDER = tuple(
    "stiffness_x nu coulomb pi_x viscous eta inertia_x backlash offset delta stiffness dahl2 coulomb_x pinch"
    " viscous_x rate inertia".split()
)
LINEAR = ("stiffness", "viscous", "inertia", "coulomb", "offset")


def base(cfg: str) -> tuple[s.System, s.Plan, str]:
    """The config's plant and plan, U scaled so that the median latent amplitude is 2.5 w_u; on A3 each
    frequency's U is its relative amplitude over |G| (amplitudes not shared)."""
    pn, gn, nn, en = CONFIGS[cfg]
    pl, g, el = PLANS[pn], GS[gn], ELEMENTS[en]
    rel = np.array(pl.amps) / (np.abs([g.at(w) for w in pl.omegas]) if pn == "A3" else 1.0)
    lat = np.abs([g.at(w) for w in pl.omegas]) * rel * el.alpha
    k = 2.5 * el.w_u / float(np.median(lat))
    return s.System(g, el), replace(pl, amps=tuple(float(a * k) for a in rel)), nn


def size(
    runs: list[tuple[np.ndarray, ...]], plain: list[tuple[np.ndarray, ...]], pl: s.Plan, sd: float
) -> float:
    """RMS of (effect minus plain) over the recorded samples / (sd / sqrt(periods))."""
    diff = np.concatenate(
        [
            a[2][int(round(st * p)) :] - b[2][int(round(st * p)) :]
            for a, b, st, p in zip(runs, plain, pl.settles, pl.samples)
        ]
    )
    return float(np.sqrt(np.mean(diff**2)) / (sd / math.sqrt(pl.periods)))


def start(eff: str, sy: s.System, pl: s.Plan) -> tuple[str, float]:
    """The simulator's key and a first value of a nonlinear effect (sized again from its result)."""
    wu, el = sy.el.w_u, sy.el
    return {
        "nu": ("nu", 0.003 / wu**2),
        "eta": ("eta", 0.003 / wu**2),
        "pinch": ("pinch", 0.1),
        "delta": ("delta", 0.03 * (el.beta + el.gamma)),
        "rate": ("rate", 0.1),
        "pi_x": ("pi_x", 0.01 * wu),
        "backlash": ("backlash", 0.003 * wu),
        "dahl2": ("dahl_sigma", 0.01 * wu / max(pl.amps)),
    }[eff]


def library_truth(name: str, v: float, el: s.Element) -> float:
    """The value in the library's alpha = 1 convention (G -> alpha G)."""
    return v / el.alpha if name.endswith("@x") or name in ("degradation", "stiffness_degradation") else v


def build(
    eff: str, target: float, cfg: str
) -> tuple[list[tuple[np.ndarray, ...]], s.Plan, str, dict[str, float], float]:
    sy, pl, nn = base(cfg)
    sd = SD * sy.el.w_u
    plain = s.simulate(sy, pl)
    if eff == "null":
        return plain, pl, nn, {}, 0.0
    name = TRUTH_TERM[eff] or eff
    if eff == "rate":
        vmax = max(abs(sy.g.at(w)) * a * w * sy.el.alpha for w, a in zip(pl.omegas, pl.amps))
        sy = s.with_effect(sy, "vref", float(vmax))
    if eff == "dahl2":
        sy = s.with_effect(sy, "dahl_fc", 0.05 * sy.el.w_u)
    if eff.split("_")[0] in LINEAR:  # linear in the value: scaled exactly
        runs = s.simulate(s.with_effect(sy, name, 1e-3), pl)
        k = target / size(runs, plain, pl, sd)
        runs = [(t, u, y0 + k * (y1 - y0)) for (t, u, y1), (_, _, y0) in zip(runs, plain)]
        return runs, pl, nn, {name: library_truth(name, 1e-3 * k, sy.el)}, size(runs, plain, pl, sd)
    key, v = start(eff, sy, pl)
    runs = s.simulate(s.with_effect(sy, key, v), pl)
    got = size(runs, plain, pl, sd)
    tried: list[tuple[float, float]] = []  # (value, size) so far: a log-log secant to within 10 %
    while abs(got / target - 1.0) >= 0.1 and len(tried) < 4:
        last = tried[-1] if tried else None
        slope = math.log(got / last[1]) / math.log(v / last[0]) if last else 1.0
        tried.append((v, got))
        v *= (target / got) ** (1.0 / min(max(slope, 0.3), 3.0))
        if eff == "pinch":
            v = min(v, 0.95)
        runs = s.simulate(s.with_effect(sy, key, v), pl)
        got = size(runs, plain, pl, sd)
    return runs, pl, nn, {name: library_truth(name, v, sy.el)}, got


#: Added after the first results (FINDINGS.md says why): L without its gain drift (white noise); M's nulls
#: named stiffness@x: with white noise instead of AR(1), or with J's element (mu = 2) instead of mu = 0.75.
FOLLOW_UPS = tuple("null-0-Lw-4 stiffness_x-30-Lw-1 null-0-Mw-4 null-0-Mm-4 stiffness_x-30-Mm-1".split())


def case_ids() -> list[str]:
    """Every effect at 10x and 30x, the config cycling over J K L M; 4 nulls after each 4 effects; N: 4."""
    cfgs = "JKLM"
    out = []
    for j, eff in enumerate(ORDER):
        out += [f"{eff}-10-{cfgs[j % 4]}-1", f"{eff}-30-{cfgs[(j + 2) % 4]}-1"]
        out += [f"null-0-{c}-{j + 1}" for c in cfgs] if j % 4 == 3 else []
    out += ["null-0-N-1", "null-0-N-2", "stiffness_x-30-N-1", "nu-30-N-1"]
    return out + list(FOLLOW_UPS)


def prepare(cid: str) -> tuple[list[Any], dict[str, Any]]:
    eff, sz, cfg, seed = cid.split("-")
    c0 = time.process_time()
    runs, pl, nn, truth, got = build(eff, float(sz), cfg)
    sy = base(cfg)[0]
    recs = s.recordings(runs, pl, nn, SD * sy.el.w_u, int(seed))
    pn, gn, _, en = CONFIGS[cfg]
    head = {"id": cid, "effect": eff, "size_target": float(sz), "size": got, "config": cfg, "design": pn}
    head |= {"g": gn, "noise": nn, "bw": en, "seed": int(seed), "truth": truth}
    return recs, head | {"sim_cpu": time.process_time() - c0}


def run_case(cid: str, in_process: bool = False) -> dict[str, Any]:
    """Review 46's child runner (review 45's ``diagnose_child``, nice 15, 180 s) on this case's recordings."""
    recs, head = prepare(cid)
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "recs.pkl")
        Path(path).write_bytes(pickle.dumps(recs))
        return head | dv46.scored(dv46.diagnosed(path, in_process), head["truth"])


def write_csv(recs: list[Any], folder: str) -> None:
    """Recordings as CSV files (t, u, y), one per experiment, as a lab would hand them to the command line."""
    Path(folder).mkdir(parents=True, exist_ok=True)
    for r in recs:
        name = r.metadata.get("name", getattr(r, "name", "x"))
        np.savetxt(f"{folder}/{name}.csv", np.c_[r.t, r.u, r.y], delimiter=",", header="t,u,y", comments="")


def main(argv: list[str]) -> None:
    """run OUT [IDS]: each case not yet in OUT, appended as one JSON line as it goes."""
    what, rest = argv[1], argv[2:]
    if what == "--list":
        print("\n".join(case_ids()))
        return
    if what in ("--one", "--write"):
        if what == "--one":
            print(json.dumps(run_case(rest[0], in_process=True), indent=1, default=str))
        else:
            write_csv(prepare(rest[0])[0], rest[1])
        return
    out = Path(rest[0])
    seen = {json.loads(x)["id"] for x in (out.read_text() if out.exists() else "").splitlines() if x.strip()}
    for cid in (c for c in (rest[1:] or case_ids()) if c not in seen):
        r = run_case(cid)
        with out.open("a") as f:
            print(json.dumps(r, default=str), file=f)
        print(
            cid,
            r.get("status"),
            f"{r.get('seconds') or 0:.0f} s:",
            (r.get("headline") or r.get("error", ""))[:150],
        )


if __name__ == "__main__":
    main(sys.argv)
