"""Review 48's driver. Each case: sim48.py makes the recordings, and ``bw.diagnose`` (defaults) judges them
in a child process (review 45's ``diagnose_child`` through review 46's runner: ``nice -n 15``,
OMP_NUM_THREADS=1, a 180 s limit), so a case's record has review 45's fields.

From the repository root, with PYTHONPATH=python:

    drive48.py run OUT [ID ...]   each planned case (or those named) missing from OUT, one JSON line each
    drive48.py --one ID           one case here, in this process; the record printed (a reproduction)
    drive48.py --list             the planned ids
    drive48.py --write ID DIR     the case's recordings as CSV (t, u, y), one file an experiment
    drive48.py --cli ID           the command line ``bouc-wen-id diagnose`` on those files: cli48_ID.txt

An id reads ``effect-size-config-seed``; the seed changes the noise draw and nothing else.
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
for extra_path in (HERE, HERE.parent / "review46", HERE.parent / "review45"):
    sys.path.insert(0, str(extra_path))
import drive46 as dv46  # noqa: E402
import sim48 as s  # noqa: E402
from drive45 import TRUTH_TERM as TRUTH45  # noqa: E402

SD = 0.01  # times w_u (the white part; the ADC configs add or are their quantisation)
LOW3 = ((20.0,), (1.0, 20.0))  # 1 / (0.05 s + 1)
RES = np.polymul([0.05, 1.0], [1.0 / 900.0, 2 * 0.05 / 30.0, 1.0])  # and a resonance at 30 rad/s, zeta 0.05
GS = {
    "delay3": s.Plant(*LOW3, delay=0.4 * 2 * math.pi / 3.0),  # lags 0.4 period at 3 rad/s
    "delay10": s.Plant((1 / 0.03,), (1.0, 1 / 0.03), delay=0.4 * 2 * math.pi / 10.0),  # 0.4 period at 10
    "third": s.Plant((1.0,), tuple(RES)),
    "lead": s.Plant((0.5, 1.0), (0.05, 1.0)),  # zero at 2 rad/s below the pole at 20
}
ELEMENTS = {
    "e1": (("beta", 0.6), ("gamma", 0.4), ("mu", 1.5)),
    "mu5": (("beta", 0.5), ("gamma", 0.5), ("mu", 5.0)),
    "e2": (("beta", 0.8), ("gamma", 0.2), ("mu", 1.2)),
}
F3 = (1.5, 4.0, 10.0)
DESIGNS = {
    "F4A": s.Design((3.0,) * 4, (0.5, 0.9, 1.4, 2.2), (8,) * 4, (10,) * 4, 128),  # one f at 4 amplitudes
    "P3": s.Design(F3 * 2, (0.7,) * 3 + (1.4,) * 3, (3,) * 6, (10,) * 6, 128),  # 3 periods a record
    "P40": s.Design(F3, (1.0,) * 3, (40,) * 3, (10,) * 3, 64),  # 40 periods a record
    "THD": s.Design(F3 * 2, (0.7,) * 3 + (1.4,) * 3, (8,) * 6, (10,) * 6, 128, h3=0.02),  # 2 % 3rd harmonic
    "DC": s.Design(F3 * 2, (0.7,) * 3 + (1.4,) * 3, (8,) * 6, (10,) * 6, 128, dc=0.3),  # DC offset 0.3 U
    "S6": s.Design(F3 * 2, (0.7,) * 3 + (1.4,) * 3, (8,) * 6, (10,) * 6, 128),  # THD with a pure sine
    "UNEQ": s.Design((1.0, 2.0, 4.0, 8.0, 12.0), (1.0,) * 5, (4, 16, 6, 24, 10), (8,) * 5, 96),
}
#: config -> (design, G, noise, element)
CONFIGS: dict[str, tuple[str, ...]] = dict(
    A=("F4A", "delay3", "q10", "e1"),
    B=("P3", "third", "t3", "mu5"),
    C=("P40", "lead", "hum", "e2"),
    D=("THD", "delay10", "pink", "e1"),
    E=("DC", "lead", "white", "e1"),
    F=("UNEQ", "third", "q12", "mu5"),
    Dn=("S6", "delay10", "pink", "e1"),  # follow-up: D without the input's third harmonic
    Fe=("UNEQ", "third", "q12", "e1"),  # follow-up: F's pure 12-bit ADC on a mu = 1.5 element
)
#: effect -> the library's term (None: physics outside the library); the simulator's key is in KEY.
_SAME = (
    "stiffness stiffness_x viscous viscous_x coulomb coulomb_x inertia_x offset play lag delta pinch nu eta"
)
TRUTH_TERM: dict[str, str | None] = {k: TRUTH45[k] for k in _SAME.split()}
TRUTH_TERM |= {"rho": "series_dashpot"}
# outside the library: a second Bouc-Wen element in parallel (beta 2, gamma -1, mu 1); beta and gamma growing
# linearly over each record (temperature); Dahl on u with exponent 0.5; a Preisach operator of five relays
TRUTH_TERM |= dict.fromkeys(("bw2", "drift", "dahl_half", "preisach"))
KEY = {"lag": "lag", "delta": "delta", "pinch": "pinch", "nu": "nu", "eta": "eta", "rho": "rho"}
KEY |= {"play": "play", "drift": "drift", "dahl_half": "dahl_half"}
LINEAR = {k: v or k for k, v in TRUTH_TERM.items() if k not in KEY}  # y linear in the value: scaled exactly
ORDER = tuple(
    "stiffness_x nu coulomb bw2 viscous play lag preisach delta stiffness eta drift inertia_x offset pinch"
    " dahl_half coulomb_x rho viscous_x".split()
)


def base(cfg: str) -> tuple[s.Plant, s.Design, str]:
    """The config's plant and design, U scaled so that the median latent amplitude is 2.5 w_u."""
    dn, gn, nn, en = CONFIGS[cfg]
    d, p = DESIGNS[dn], replace(GS[gn], par=ELEMENTS[en])
    lat = np.abs([p.at(w) for w in d.omegas]) * np.array(d.amps)
    k = 2.5 * p.w_u / float(np.median(lat))
    return p, replace(d, amps=tuple(float(a * k) for a in d.amps)), nn


def noise_sd(nn: str, plain: list[tuple[np.ndarray, ...]], w_u: float) -> tuple[float, float, float]:
    """(the white sd, the ADC's half range, the total sd: white and quantisation) of a config."""
    adc = 1.25 * max(float(np.max(np.abs(y))) for _, _, y in plain)
    lsb = {"q10": 2 * adc / 1024, "q12": 2 * adc / 4096}.get(nn, 0.0)
    white = {"q10": 0.3 * lsb, "q12": 0.0}.get(nn, SD * w_u)
    return white, adc, math.sqrt(white**2 + lsb**2 / 12.0)


def size(
    runs: list[tuple[np.ndarray, ...]], plain: list[tuple[np.ndarray, ...]], d: s.Design, sd: float
) -> float:
    """RMS over the recorded samples of (effect minus plain) / (sd / sqrt(the record's periods))."""
    diff = np.concatenate(
        [
            (a[2][st * d.samples :] - b[2][st * d.samples :]) * math.sqrt(n) / sd
            for a, b, st, n in zip(runs, plain, d.settles, d.periods)
        ]
    )
    return float(np.sqrt(np.mean(diff**2)))


def start(eff: str, p: s.Plant, d: s.Design) -> float:
    """A first value of a nonlinear effect (sized again from its result)."""
    wu, om = p.w_u, max(d.omegas)
    lat = min(abs(p.at(w)) * a for w, a in zip(d.omegas, d.amps))
    return {
        "lag": 0.002 / om,
        "delta": 0.03 * (p.get("beta") + p.get("gamma")),
        "pinch": 0.1,
        "nu": 0.003 / wu**2,
        "eta": 0.003 / wu**2,
        "rho": 0.05 * om,
        "play": 0.03 * lat,
        "drift": 0.02,
        "dahl_half": 0.01 * wu / max(d.amps),
    }[eff]


_PLAIN: dict[str, Any] = {}


def plain_of(cfg: str) -> list[tuple[np.ndarray, ...]]:
    if cfg not in _PLAIN:
        p, d, _ = base(cfg)
        _PLAIN[cfg] = s.simulate(p, d)
    return _PLAIN[cfg]


def build(eff: str, target: float, cfg: str) -> tuple[list[Any], dict[str, float], float]:
    """The effect's noise-free runs, its truth (the library's name -> value) and the size it reached."""
    p, d, nn = base(cfg)
    plain = plain_of(cfg)
    sd = noise_sd(nn, plain, p.w_u)[2]
    if eff == "null":
        return plain, {}, 0.0
    if eff in LINEAR:  # y linear in the value: one run at a unit value, scaled exactly
        unit = s.simulate(p.with_(LINEAR[eff], 1.0), d)
        k = target / size(unit, plain, d, sd)
        runs = [(t, u, y0 + k * (y1 - y0)) for (t, u, y1), (_, _, y0) in zip(unit, plain)]
        truth = {LINEAR[eff]: k} if TRUTH_TERM[eff] else {}
        return runs, truth, size(runs, plain, d, sd)
    v = start(eff, p, d)
    runs = s.simulate(p.with_(KEY[eff], v), d)
    got = size(runs, plain, d, sd)
    last: tuple[float, float] | None = None
    for _ in range(3):  # a log-log secant to within 20 %
        if abs(got / target - 1.0) < 0.2:
            break
        slope = math.log(got / last[1]) / math.log(v / last[0]) if last else 1.0
        last = (v, got)
        v *= (target / got) ** (1.0 / min(max(slope, 0.3), 3.0))
        v = min(v, 0.95) if eff == "pinch" else v
        runs = s.simulate(p.with_(KEY[eff], v), d)
        got = size(runs, plain, d, sd)
    name = TRUTH_TERM[eff]
    return runs, ({name: v} if name else {}), got


def case_ids() -> list[str]:
    """Every effect at 10x and 30x, the config cycling over A B C D; nulls on every config spread among
    them; a few effects on E and F."""
    cfgs = "ABCD"
    out: list[str] = []
    nulls = [f"null-0-{c}-{k}" for k in (1, 2, 3) for c in "ABCDEF"][:16]
    extra = "stiffness_x-30-E-1 nu-30-F-1 delta-30-E-1 play-30-F-1".split()
    for j, eff in enumerate(ORDER):
        out += [f"{eff}-10-{cfgs[j % 4]}-1", f"{eff}-30-{cfgs[(j + 2) % 4]}-1"]
        out += [nulls.pop(0)] if nulls else []
        out += [extra.pop(0)] if extra and j % 4 == 3 else []
    return out + nulls + extra


def prepare(cid: str) -> tuple[list[Any], dict[str, Any]]:
    eff, sz, cfg, seed = cid.split("-")
    c0 = time.process_time()
    runs, truth, got = build(eff, float(sz), cfg)
    p, d, nn = base(cfg)
    white, adc, sd = noise_sd(nn, plain_of(cfg), p.w_u)
    recs = s.recordings(runs, d, nn, white, adc, int(seed))
    keys = ("design", "g", "noise", "bw")
    head = dict(id=cid, effect=eff, size_target=float(sz), size=got, config=cfg, seed=int(seed), truth=truth)
    return recs, head | dict(zip(keys, CONFIGS[cfg])) | {"sd": sd, "sim_cpu": time.process_time() - c0}


def run_case(cid: str, in_process: bool = False) -> dict[str, Any]:
    """The case's recordings pickled for review 46's runner of review 45's child; its answer scored."""
    recs, head = prepare(cid)
    fd, path = tempfile.mkstemp(suffix=".pkl")
    try:
        with os.fdopen(fd, "wb") as f:
            pickle.dump(recs, f)
        answer = dv46.diagnosed(path, in_process)
    finally:
        os.unlink(path)
    return head | dv46.scored(answer, head["truth"])


def write_csv(cid: str, folder: str) -> None:
    Path(folder).mkdir(parents=True, exist_ok=True)
    for r in prepare(cid)[0]:
        table = np.column_stack([r.t, r.u, r.y])
        np.savetxt(
            Path(folder) / f"{r.metadata['name']}.csv", table, delimiter=",", header="t,u,y", comments=""
        )


def cli(cid: str) -> None:
    """The command line on the case's CSV files (no amplitude, no frequency given): its output, the
    temporary folder's name masked, into cli48_ID.txt beside this file."""
    bin_ = os.environ.get("BIN", str(Path(sys.executable).with_name("bouc-wen-id")))
    with tempfile.TemporaryDirectory() as tmp:
        write_csv(cid, f"{tmp}/data")
        files = sorted(str(f) for f in Path(f"{tmp}/data").glob("*.csv"))
        cmd = ["nice", "-n", "15", bin_, "diagnose", *files, "--no-figures", "--out", f"{tmp}/out"]
        env = os.environ | {"OMP_NUM_THREADS": "1"}
        cp = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
        said = (cp.stdout + cp.stderr).replace(tmp, "TMP")
    head = f"$ bouc-wen-id diagnose DATA/*.csv --no-figures --out OUT    # DATA: drive48.py --write {cid}\n"
    (HERE / f"cli48_{cid}.txt").write_text(head + said + f"(exit {cp.returncode})\n")


def main(argv: list[str]) -> None:
    what, rest = argv[1], argv[2:]
    if what == "--list":
        print("\n".join(case_ids()))
        return
    if what == "--one":
        print(json.dumps(run_case(rest[0], in_process=True), indent=1, default=str))
        return
    if what == "--write":
        write_csv(rest[0], rest[1])
        return
    if what == "--cli":
        cli(rest[0])
        return
    run_all(Path(rest[0]), rest[1:] or case_ids())


def done(out: Path) -> set[str]:
    return {json.loads(x)["id"] for x in (out.read_text() if out.exists() else "").splitlines() if x.strip()}


def run_all(out: Path, ids: list[str]) -> None:
    """Each id not yet in OUT (read again before each case: an id listed twice runs once), one JSON line
    appended as it finishes and one line of progress printed."""
    for cid in ids:
        if cid in done(out):
            continue
        rec = run_case(cid)
        out.open("a").write(json.dumps(rec, default=str) + "\n")
        said = (rec.get("headline") or rec.get("error", ""))[:150]
        print(
            f"{cid} {rec.get('status')} {rec.get('seconds') or 0:.0f} s, sim {rec['sim_cpu']:.0f} s: {said}",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv)
