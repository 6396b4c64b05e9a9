"""Review 46's driver: build a case with sim46.py, run ``bw.diagnose`` (defaults) in a process of its own.

    PYTHONPATH=python python studies/review46/drive46.py run studies/review46/results46.jsonl [ID ...]
    PYTHONPATH=python python studies/review46/drive46.py --one CASE_ID    # one case, in process: the record
    PYTHONPATH=python python studies/review46/drive46.py --list           # the planned case ids
    PYTHONPATH=python python studies/review46/drive46.py --write CASE_ID DIR   # its recordings as CSV files

A case id is ``effect-size-config-seed``; the seed drives the noise only. The child (``nice -n 15``,
OMP_NUM_THREADS=1, 180 s) is review 45's ``diagnose_child`` (the same record fields).
"""

from __future__ import annotations

import json
import math
import os
import pickle
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "review45"))
import sim46 as s  # noqa: E402
from drive45 import TRUTH_TERM as TRUTH_TERM45  # noqa: E402
from drive45 import diagnose_child  # noqa: E402

TIMEOUT = 180.0
SD = 0.01
PLANS = {
    "2f5a": s.Plan((1.5,) * 5 + (6.0,) * 5, tuple(np.geomspace(0.4, 2.5, 5)) * 2, 8, 30, 200),
    "5per": s.Plan((1.0, 2.5, 5.0, 10.0) * 2, (0.5,) * 4 + (1.0,) * 4, 5, 10, 200),
    "p1000": s.Plan((2.0, 8.0) * 2, (0.5,) * 2 + (1.0,) * 2, 6, 5, 1000),
    "p40": s.Plan((1.5, 3.0, 6.0, 12.0) * 2, (0.5,) * 4 + (1.0,) * 4, 20, 30, 40),
}
GS = {
    "iso": s.isolator(4.0, 0.05, 0.04),
    "act": s.actuator(0.05, math.pi / 10.0),  # half a period at the top frequency (10 rad/s)
    "gain": s.Gs(),
    "iso5": s.isolator(5.0, 0.05, 0.03),
}
ELEMENTS = {
    "g/b.1": s.Element(1.0, 0.1, 1.5),
    "mu3.5": s.Element(0.5, 0.5, 3.5),
    "mu4": s.Element(0.6, 0.4, 4.0),
    "mu3g/b.1": s.Element(0.9, 0.1, 3.0),
    "mu2": s.Element(0.6, 0.4, 2.0),  # follow-up: G's element with mu = 2
}
#: config -> plan, G, noise, element; Gw, Gm, Hw are follow-ups (FINDINGS.md says why): white noise
#: instead, or G's element with mu = 2.
CONFIGS: dict[str, tuple[str, ...]] = {
    row.split(":")[0]: tuple(row.split(":")[1].split())
    for row in (
        "E: 2f5a iso ar2 g/b.1; F: 5per act quant mu3.5; G: p1000 gain hum mu4; H: p40 iso5 ar2 mu3g/b.1; "
        "Gw: p1000 gain white mu4; Gm: p1000 gain hum mu2; Hw: p40 iso5 white mu3g/b.1"
    ).split("; ")
}
#: effect -> the library's term (None: physics outside the library), review 45's without Dahl on x
TRUTH_TERM: dict[str, str | None] = {k: v for k, v in TRUTH_TERM45.items() if k != "dahl_x"}
#: The effects in the order they are run (the config cycles with it).
ORDER = tuple(
    "stiffness_x play slack nu coulomb eta pi_u lag viscous_x delta rate inertia offset pinch stiffness"
    " coulomb_x viscous inertia_x".split()
)


def base(cfg: str) -> tuple[s.System, s.Plan, str]:
    """The config's plant and its plan with U scaled so that the median latent amplitude is 2.5 w_u."""
    pn, gn, nn, en = CONFIGS[cfg]
    pl, g, el = PLANS[pn], GS[gn], ELEMENTS[en]
    lat = np.array([abs(g.at(w)) * a for w, a in zip(pl.omegas, pl.amps)])
    k = 2.5 * el.w_u / float(np.median(lat))
    return s.System(g, el), replace(pl, amps=tuple(float(a * k) for a in pl.amps)), nn


def size(runs: list[tuple[np.ndarray, ...]], plain: list[tuple[np.ndarray, ...]], pl: s.Plan) -> float:
    """RMS of (effect minus plain) over the recorded samples / (SD / sqrt(periods))."""
    cut = pl.settle * pl.samples
    diff = np.concatenate([a[2][cut:] - b[2][cut:] for a, b in zip(runs, plain)])
    return float(np.sqrt(np.mean(diff**2)) / (SD / math.sqrt(pl.periods)))


def start(eff: str, sy: s.System, pl: s.Plan) -> float:
    """A first value of an effect (sized again from its result)."""
    lat = min(abs(sy.g.at(w)) * a for w, a in zip(pl.omegas, pl.amps))
    wu = sy.el.w_u
    return {
        "play": 0.03 * lat,
        "slack": 0.03 * lat,
        "nu": 0.003 / wu**2,
        "eta": 0.003 / wu**2,
        "pinch": 0.1,
        "delta": 0.03 * (sy.el.beta + sy.el.gamma),
        "lag": 0.003 / max(pl.omegas),
        "rate": 0.1,
        "pi_u": 0.01 * wu,
    }.get(eff, 1e-3)


LINEAR = ("stiffness", "viscous", "inertia", "coulomb", "offset", "pi_u")


def build(
    eff: str, target: float, cfg: str
) -> tuple[list[tuple[np.ndarray, ...]], s.Plan, str, dict[str, float], float]:
    sy, pl, nn = base(cfg)
    plain = s.simulate(sy, pl)
    if eff == "null":
        return plain, pl, nn, {}, 0.0
    name = TRUTH_TERM[eff] or eff
    if eff == "rate":
        vmax = max(abs(sy.g.at(w)) * a * w for w, a in zip(pl.omegas, pl.amps))
        sy = s.with_effect(sy, "vref", float(vmax))
    key = name if eff.split("_")[0] in LINEAR[:5] else eff
    v = start(eff, sy, pl)
    runs = s.simulate(s.with_effect(sy, key, v), pl)
    got = size(runs, plain, pl)
    if eff.split("_")[0] in LINEAR:  # linear in the value: scaled exactly
        k = target / got
        runs = [(t, u, y0 + k * (y1 - y0)) for (t, u, y1), (_, _, y0) in zip(runs, plain)]
        return runs, pl, nn, {name: v * k}, size(runs, plain, pl)
    prev = None
    for _ in range(3):  # log-log secant
        if abs(got / target - 1.0) < 0.1:
            break
        slope = 1.0 if prev is None else math.log(got / prev[1]) / math.log(v / prev[0])
        slope = min(max(slope, 0.3), 3.0)
        prev = (v, got)
        v = v * (target / got) ** (1.0 / slope)
        if eff == "pinch":
            v = min(v, 0.95)
        runs = s.simulate(s.with_effect(sy, key, v), pl)
        got = size(runs, plain, pl)
    return runs, pl, nn, {name: v}, got


#: Added after the first results, each to separate a cause (FINDINGS.md says which): the two G cases first
#: run on an earlier, larger G plan (3 f x 2 U, settle 10), again on this one; G's null false alarm: the hum
#: (white instead), mu = 4 (mu = 2 instead), or the seed?; H's nu miss (records left out as drifting): the
#: AR(2) noise?, and H's "disturbance" lines on a null.
FOLLOW_UPS = (
    "stiffness_x-30-G-1 slack-10-G-1 null-0-Gw-4 null-0-Gm-4 null-0-G-5 nu-10-Hw-1 null-0-Hw-4".split()
)


def case_ids() -> list[str]:
    """Every effect at 10x and 30x, the config cycling; 4 nulls after every 4 effects."""
    cfgs = "EFGH"
    out = []
    for j, eff in enumerate(ORDER):
        out += [f"{eff}-10-{cfgs[j % 4]}-1", f"{eff}-30-{cfgs[(j + 2) % 4]}-1"]
        out += [f"null-0-{c}-{j + 1}" for c in cfgs] if j % 4 == 3 else []
    return out + FOLLOW_UPS


def prepare(cid: str) -> tuple[list[Any], dict[str, Any]]:
    eff, sz, cfg, seed = cid.split("-")
    c0 = time.process_time()
    runs, pl, nn, truth, got = build(eff, float(sz), cfg)
    recs = s.recordings(runs, pl, nn, SD, int(seed))
    pn, gn, _, en = CONFIGS[cfg]
    head = {"id": cid, "effect": eff, "size_target": float(sz), "size": got, "config": cfg, "design": pn}
    head |= {"g": gn, "noise": nn, "bw": en, "seed": int(seed), "truth": truth}
    return recs, head | {"sim_cpu": time.process_time() - c0}


def diagnosed(path: str, in_process: bool) -> dict[str, Any]:
    """Review 45's child on the pickled recordings: here, or in a process of its own (nice 15, 180 s)."""
    if in_process:
        return diagnose_child(path)
    cmd = ["nice", "-n", "15", sys.executable, __file__, "--child", path]
    env = os.environ | {"OMP_NUM_THREADS": "1"}
    try:
        cp = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, env=env)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout {TIMEOUT:g} s", "seconds": TIMEOUT}
    last = (cp.stdout.strip().splitlines() or [""])[-1]
    return json.loads(last) if cp.returncode == 0 and last else {"error": "crash: " + cp.stderr[-400:]}


def scored(r: dict[str, Any], truth: dict[str, float]) -> dict[str, Any]:
    """Each named or partial term that is a true one gets its truth and z = (value - truth) / se."""
    for n in r.get("named", []) + r.get("partial", []):
        t = truth.get(n["term"])
        if t is not None:
            usable = bool(n["se"]) and math.isfinite(n["se"])
            n |= {"truth": t, "z": (n["value"] - t) / n["se"] if usable else None}
    return r


def run_case(cid: str, in_process: bool = False) -> dict[str, Any]:
    recs, head = prepare(cid)
    fd, path = tempfile.mkstemp(suffix=".pkl")
    with os.fdopen(fd, "wb") as f:
        pickle.dump(recs, f)
    try:
        r = diagnosed(path, in_process)
    finally:
        os.unlink(path)
    return head | scored(r, head["truth"])


def write_csv(recs: list[Any], folder: str) -> None:
    """Recordings as CSV files (t, u, y), one per experiment, as a lab would hand them to the command line."""
    Path(folder).mkdir(parents=True, exist_ok=True)
    for r in recs:
        table = np.column_stack([r.t, r.u, r.y])
        np.savetxt(f"{folder}/{r.metadata['name']}.csv", table, delimiter=",", header="t,u,y", comments="")


def run_all(out: Path, ids: list[str]) -> None:
    """Each case not yet in ``out``, one JSON line each, appended as it goes."""
    old = out.read_text().splitlines() if out.exists() else []
    done = {json.loads(x)["id"] for x in old if x.strip()}
    for cid in [c for c in ids if c not in done]:
        r = run_case(cid)
        with out.open("a") as f:
            f.write(json.dumps(r, default=str) + "\n")
        said = (r.get("headline") or r.get("error", ""))[:150]
        print(f"{cid} {r.get('status')} {r.get('seconds') or 0:.0f} s: {said}", flush=True)


def main(argv: list[str]) -> None:
    what = argv[1]
    if what == "--child":
        print(json.dumps(diagnose_child(argv[2]), default=str))
    elif what == "--list":
        print("\n".join(case_ids()))
    elif what == "--one":
        print(json.dumps(run_case(argv[2], in_process=True), indent=1, default=str))
    elif what == "--write":
        write_csv(prepare(argv[2])[0], argv[3])
    else:
        run_all(Path(argv[2]), argv[3:] or case_ids())


if __name__ == "__main__":
    main(sys.argv)
