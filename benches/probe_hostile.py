"""Replay a broad, generated set of hostile probes and count the verdicts (issue #9).

Each probe is one call a hostile or careless user could make: value types with absurd fields, oversized
work, bad identify arguments, perturbed data, direct ``_core`` calls with wrong types, mutated and
malicious files, and command lines with bad arguments. Every probe runs in a forked child (the parent has
the package and a set of simulated recordings loaded, so a fork costs milliseconds) under a memory limit
(``resource.setrlimit(RLIMIT_AS)``) and a wall-clock limit, and ends in one verdict:

``named``
    a ``BoucWenIdError`` (or, for the CLI, exit status 2 with one line on stderr and no traceback);
``correct``
    a result that passes the probe's check (finite values; for identify, mu within 10 % of the truth);
``warned``
    a result with a library warning (``IdentifiabilityWarning``, ``ConvergenceWarning``, ...);
``raw``
    any other exception (or a CLI traceback / other exit status), or a crash (killed by a signal);
``silent``
    a result that fails its check, with no warning;
``hang``
    still running at the time limit;
``memory``
    ``MemoryError`` or killed at the memory limit.

Target: zero raw, zero silent, zero hang, zero memory. Run::

    python benches/probe_hostile.py [--seed 0] [--time-limit 60] [--memory-gb 3] [--verbose]

``--hypothesis N`` runs instead the property-based sweep of issue 19: hypothesis draws (seeded) the scalar
and array arguments of ``simulate``, ``simulate_input`` (any term at any place), ``identify``, ``diagnose``
(tiny step budgets), ``plan_experiment``, ``fit_transfer_function`` and ``load`` (a drawn y column), N calls
each, each in its forked child with a 30 s hang limit; ``--quick`` is ``--hypothesis 15`` (about 20 s).

The default budgets of :mod:`bouc_wen_id.budget` are in force: the probe shows they keep every call
inside the limits.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import io
import math
import os
import pickle
import resource
import signal
import sys
import tempfile
import time
import traceback
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

os.environ.setdefault("MPLBACKEND", "Agg")

import bouc_wen_id as bw  # noqa: E402
from bouc_wen_id import _core, cli  # noqa: E402

VERDICTS = ("named", "correct", "warned", "raw", "silent", "hang", "memory")
LIBRARY_WARNINGS = (
    bw.IdentifiabilityWarning,
    bw.DistortedInputWarning,
    bw.ConvergenceWarning,
    bw.errors.TransientWarning,
)
TRUE_MU = 1.6  # demo_plant's mu


@dataclass
class Probe:
    category: str
    name: str
    run: Callable[[], Any]
    #: Judges a returned value: True when it is right.
    check: Callable[[Any], bool]
    cli: bool = False


# --------------------------------------------------------------------------------------------------
# Checks
# --------------------------------------------------------------------------------------------------


def finite_deep(v: Any, depth: int = 0) -> bool:
    """Every float in ``v`` (arrays, tuples, lists, dataclass fields) is finite."""
    if depth > 4:
        return True
    if isinstance(v, (float, np.floating)):
        return math.isfinite(float(v))
    if isinstance(v, np.ndarray):
        return v.dtype.kind not in "fc" or bool(np.all(np.isfinite(v)))
    if isinstance(v, (list, tuple)):
        return all(finite_deep(x, depth + 1) for x in v)
    if hasattr(v, "__dataclass_fields__"):
        return all(finite_deep(getattr(v, f, None), depth + 1) for f in v.__dataclass_fields__)
    return True


def identified(res: Any) -> bool:
    return (
        isinstance(res, bw.IdentificationResult)
        and abs(res.mu - TRUE_MU) <= 0.1 * TRUE_MU
        and all(math.isfinite(x) for x in (res.beta, res.gamma, res.mu))
    )


# --------------------------------------------------------------------------------------------------
# Generators
# --------------------------------------------------------------------------------------------------

HOSTILE = [
    math.nan,
    math.inf,
    -math.inf,
    -1,
    0,
    0.5,
    1e300,
    -1e300,
    1e-320,
    2**70,
    -(2**70),
    "3",
    None,
    True,
    [],
    [1.0, 2.0],
    np.array([[1.0, 2.0]]),
    1 + 1j,
    object(),
    np.float32(2.0),
    np.int64(-5),
]


def value_probes(rng: np.random.Generator) -> list[Probe]:
    out: list[Probe] = []
    base_plan = dict(
        frequencies=[3.0, 5.0],
        amplitudes=1.0,
        settle_periods=5,
        periods=4,
        samples_per_period=32,
        substeps=2,
        noise_sd=0.0,
        seed=0,
    )
    for field in base_plan:
        for v in rng.choice(len(HOSTILE), 5, replace=False):
            kw = dict(base_plan, **{field: HOSTILE[int(v)]})
            out.append(
                Probe(
                    "values",
                    f"SinePlan({field}={HOSTILE[int(v)]!r})",
                    lambda kw=kw: bw.SinePlan(**kw),
                    finite_deep,
                )
            )
    bw_fields = dict(beta=0.8, gamma=0.2, mu=1.6, alpha=1.0, w0=0.0)
    for field in bw_fields:
        for v in rng.choice(len(HOSTILE), 3, replace=False):
            kw = dict(bw_fields, **{field: HOSTILE[int(v)]})
            out.append(
                Probe(
                    "values",
                    f"BoucWen({field}={HOSTILE[int(v)]!r})",
                    lambda kw=kw: bw.BoucWen(**kw),
                    finite_deep,
                )
            )
    for v in rng.choice(len(HOSTILE), 6, replace=False):
        h = HOSTILE[int(v)]
        out.append(
            Probe(
                "values",
                f"TransferFunction(den={h!r})",
                lambda h=h: bw.TransferFunction([1.0], h),
                finite_deep,
            )
        )
        out.append(
            Probe(
                "values",
                f"TransferFunction(delay={h!r})",
                lambda h=h: bw.TransferFunction([1.0], [1.0, 1.0], h),
                finite_deep,
            )
        )
    t = np.arange(64) * 0.1
    rec_fields: dict[str, Any] = dict(
        t=t, u=np.cos(t), y=np.sin(t), amplitude=1.0, frequency=1.0, settle_periods=0
    )
    for field in ("amplitude", "frequency", "settle_periods", "plant", "metadata", "y"):
        for v in rng.choice(len(HOSTILE), 3, replace=False):
            kw = dict(rec_fields, **{field: HOSTILE[int(v)]})
            out.append(
                Probe(
                    "values",
                    f"Recording({field}={HOSTILE[int(v)]!r})",
                    lambda kw=kw: bw.Recording(**kw),
                    finite_deep,
                )
            )

    def pickled() -> bool:
        r = bw.Recording(t, np.cos(t), np.sin(t), 1.0, 1.0)
        back = pickle.loads(pickle.dumps(r))
        return not back.y.flags.writeable

    out.append(Probe("values", "pickle keeps Recording frozen", pickled, lambda ok: bool(ok)))
    return out


def work_probes(rng: np.random.Generator) -> list[Probe]:
    plant = bw.demo_plant()
    out: list[Probe] = []
    sizes = [
        ("samples_per_period", 10**7),
        ("samples_per_period", 10**9),
        ("substeps", 10**12),
        ("substeps", 10**7),
        ("periods", 10**9),
        ("settle_periods", 10**10),
        ("periods", 2**62),
    ]
    for field, v in sizes:
        kw = {**dict(settle_periods=2, periods=2, samples_per_period=32), field: v}
        out.append(
            Probe(
                "work",
                f"simulate({field}={v})",
                lambda kw=kw: bw.simulate(plant, bw.SinePlan([3.0], **kw)),
                finite_deep,
            )
        )
    for beta, amp in [(1e300, 1.0), (1e10, 1e10), (0.8, 1e300), (0.8, 1e150), (1e-300, 1.0), (0.8, 1e-300)]:
        p = bw.WienerPlant(plant.linear, bw.BoucWen(beta, min(0.2, beta), 1.6))
        out.append(
            Probe(
                "work",
                f"simulate(beta={beta:g}, U={amp:g})",
                lambda p=p, amp=amp: bw.simulate(
                    p, bw.SinePlan([3.0], [amp], settle_periods=2, periods=2, samples_per_period=32)
                ),
                finite_deep,
            )
        )
        tt = np.arange(200) * 0.05
        out.append(
            Probe(
                "work",
                f"simulate_input(beta={beta:g}, U={amp:g})",
                lambda p=p, amp=amp, tt=tt: bw.simulate_input(p, tt, amp * np.sin(tt)),
                finite_deep,
            )
        )
    core_sizes = [
        ("steady_loop P=2^40", lambda: _core.steady_loop(1.0, 0.5, 0.1, 2.0, 0.0, 1 << 40, 4)),
        ("steady_loop substeps=2^40", lambda: _core.steady_loop(1.0, 0.5, 0.1, 2.0, 0.0, 64, 1 << 40)),
        (
            "profile grid=10^8",
            lambda: _core.profile_phase_sls(
                np.cos(np.arange(64) / 10), -np.sin(np.arange(64) / 10), 1.0, 1.0, 1.01, 5.0, 1e-8, 10**8
            ),
        ),
        (
            "profile_gain grid=10^12",
            lambda: _core.profile_phase_gain(
                np.cos(np.arange(64) / 10), -np.sin(np.arange(64) / 10), 1.0, 1.0, 0.5, 0.1, 2.0, 10**12
            ),
        ),
        (
            "sls_search max_iter=10^15",
            lambda: _core.sls_search(
                np.cos(np.arange(64) / 10),
                -np.sin(np.arange(64) / 10),
                1.0,
                1.0,
                0.0,
                1.01,
                5.0,
                1e-300,
                10**15,
            ),
        ),
        ("periodic_average periods=2^62", lambda: _core.periodic_average(np.ones(64), 16, 0, 2**62)),
        ("spectral_derivative harmonics=2^62", lambda: _core.spectral_derivative(np.ones(64), 1.0, 2**62)),
    ]
    for name, fn in core_sizes:
        out.append(Probe("work", name, fn, finite_deep))
    return out


def identify_probes(rng: np.random.Generator, recs: list[bw.Recording]) -> list[Probe]:
    out: list[Probe] = []
    args: dict[str, list[Any]] = {
        "reference": [0.5, -1, 3, 10, True, "0", 2**70, None],
        "harmonics": [2**70, 1e3, 0, -3, "bogus", 1, 3, "all", 10**6],
        "tol": [0.0, -1.0, math.nan, 1e-300, 1e3, 1e-2],
        "mu_bracket": [
            (0.5, 2.0),
            (2.0, 1.5),
            (1.0, math.inf),
            (1.0, 1.0 + 1e-12),
            (3.0, 10.0),
            (1.0, 1e300),
            ("a", 3),
        ],
        "phase_grid": [10**8, 0, 2, 3, 2.5, -5, 10**4],
        "max_iter": [1, 0, -1, 10**9, 2.5, 3],
        "settle_periods": [0, -1, 10**6, 2.5, 1],
        "periods": [0, 1, 2, 10**6, -2],
        "confidence": [0.0, 1.0, 1.5, math.nan, 0.999999, "x"],
        "method": ["paper", "profile", "bogus", None],
        "backend": ["numpy", "fortran"],
    }
    for name, values in args.items():
        for v in values:
            kw = {name: v}
            if name == "backend" and v == "numpy":
                kw["method"] = "paper"
            out.append(
                Probe(
                    "identify", f"identify({name}={v!r})", lambda kw=kw: bw.identify(recs, **kw), identified
                )
            )
    return out


def _perturb(recs: list[bw.Recording], fy: Callable[[bw.Recording], Any], **kw: Any) -> list[bw.Recording]:
    out = []
    for r in recs:
        fields = dict(
            t=r.t, u=r.u, y=r.y, amplitude=r.amplitude, frequency=r.frequency, settle_periods=r.settle_periods
        )
        fields.update(kw)
        fields["y"] = fy(r)
        out.append(bw.Recording(**fields))
    return out


def data_probes(rng: np.random.Generator, recs: list[bw.Recording]) -> list[Probe]:
    out: list[Probe] = []
    ys: dict[str, Callable[[bw.Recording], Any]] = {
        "offset 1.0": lambda r: r.y + 1.0,
        "offset 0.01": lambda r: r.y + 0.01,
        "offset -1e3": lambda r: r.y - 1e3,
        "scale 1e-20": lambda r: r.y * 1e-20,
        "scale 1e20": lambda r: r.y * 1e20,
        "scale 1e-200": lambda r: r.y * 1e-200,
        "constant": lambda r: np.full_like(r.y, 2.0),
        "zeros": lambda r: np.zeros_like(r.y),
        "pure noise": lambda r: np.random.default_rng(1).standard_normal(r.y.size),
        "noise x100": lambda r: r.y + 0.5 * np.random.default_rng(2).standard_normal(r.y.size),
        "clipped": lambda r: np.clip(r.y, -0.3, 0.3),
        "sign flipped": lambda r: -r.y,
        "nan injected": lambda r: np.where(np.arange(r.y.size) == 5, np.nan, r.y),
        "drift": lambda r: r.y + 1e-3 * np.arange(r.y.size),
        "shifted by half a period": lambda r: np.roll(r.y, r.samples_per_period // 2),
    }
    for name, fy in ys.items():
        out.append(
            Probe("data", f"recordings: {name}", lambda fy=fy: bw.identify(_perturb(recs, fy)), identified)
        )
    out.append(Probe("data", "settle_periods=0", lambda: bw.identify(recs, settle_periods=0), identified))
    out.append(
        Probe(
            "data",
            "frequency in Hz",
            lambda: bw.identify(
                [_perturb([r], lambda r: r.y, frequency=r.frequency / (2 * math.pi))[0] for r in recs]
            ),
            identified,
        )
    )
    out.append(
        Probe(
            "data",
            "amplitude x2",
            lambda: bw.identify([_perturb([r], lambda r: r.y, amplitude=2 * r.amplitude)[0] for r in recs]),
            identified,
        )
    )
    out.append(
        Probe(
            "data",
            "one recording of 1 period",
            lambda: bw.identify(
                bw.Recording(
                    recs[0].t[:40], recs[0].u[:40], recs[0].y[:40], recs[0].amplitude, recs[0].frequency
                )
            ),
            identified,
        )
    )
    t = np.arange(4000) / 400.0
    u = np.cos(2 * math.pi * 2.0 * t)
    for name, y in (
        ("constant", np.full_like(t, 2.0)),
        ("constant + noise", 2.0 + 1e-3 * np.random.default_rng(3).standard_normal(t.size)),
        ("zero input", None),
    ):
        uu = np.zeros_like(t) if y is None else u
        yy = np.sin(t) if y is None else y
        out.append(
            Probe(
                "data",
                f"measurement: {name}",
                lambda uu=uu, yy=yy: bw.identify(bw.Measurement(t, uu, yy)),
                identified,
            )
        )
    return out


def core_probes(rng: np.random.Generator) -> list[Probe]:
    ok = np.cos(2 * np.pi * np.arange(64) / 64)
    calls: dict[str, tuple[Callable[..., Any], list[Any]]] = {
        "phase_from_max": (_core.phase_from_max, [ok]),
        "spectral_derivative": (_core.spectral_derivative, [ok, 1.0, 3]),
        "periodic_average": (_core.periodic_average, [np.tile(ok, 4), 64, 1, 2]),
        "gain_estimate": (_core.gain_estimate, [ok, -ok, 1.0, 1.0, 0.0, 0.5, 0.1, 2.0]),
        "sls_theta": (_core.sls_theta, [ok, -ok, 1.0, 1.0, 0.0, 1.5]),
        "solve_normal": (_core.solve_normal, [np.eye(3), np.ones(3)]),
        "steady_loop": (_core.steady_loop, [1.0, 0.5, 0.1, 2.0, 0.0, 64, 4]),
        "simulate_sine": (
            _core.simulate_sine,
            [[1.0], [1.0, 1.0], 0.0, 1.0, 0.5, 0.1, 2.0, 0.0, 1.0, 1.0, 0.1, 50, 2],
        ),
    }
    pool = HOSTILE + [
        np.arange(64),
        np.ones(64, dtype=np.float32),
        ok[::2],
        np.ones((8, 8)),
        np.array([]),
        np.array([[1, 2], [3, 4]], dtype=float),
        np.array([[2.0, 1.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]]),
    ]
    out: list[Probe] = []
    for name, (fn, base) in calls.items():
        for _ in range(6):
            i = int(rng.integers(len(base)))
            v = pool[int(rng.integers(len(pool)))]
            a = list(base)
            a[i] = v
            out.append(
                Probe(
                    "core",
                    f"_core.{name}(arg {i} = {type(v).__name__} {str(v)[:30]!r})",
                    lambda fn=fn, a=a: fn(*a),
                    finite_deep,
                )
            )
    return out


def file_probes(rng: np.random.Generator, recs: list[bw.Recording], root: Path) -> list[Probe]:
    out: list[Probe] = []
    good: list[Path] = []
    for suffix in (".csv", ".npz", ".mat"):
        p = root / f"good{suffix}"
        bw.save(p, recs[0])
        good.append(p)

    def load(p: Path) -> Callable[[], Any]:
        return lambda: bw.load(p)

    for i in range(36):
        src = good[i % 3]
        data = bytearray(src.read_bytes())
        kind = ("truncate", "flip", "append", "zero-run")[i % 4]
        if kind == "truncate":
            data = data[: int(rng.integers(1, len(data)))]
        elif kind == "flip":
            for _ in range(int(rng.integers(1, 8))):
                j = int(rng.integers(len(data)))
                data[j] ^= 1 << int(rng.integers(8))
        elif kind == "append":
            data += bytes(rng.integers(0, 256, int(rng.integers(1, 4096)), dtype=np.uint8))
        else:
            j = int(rng.integers(len(data)))
            data[j : j + 64] = b"\0" * 64
        p = root / f"mutant_{i:02d}{src.suffix}"
        p.write_bytes(bytes(data))
        out.append(Probe("files", f"{kind} {src.suffix} #{i}", load(p), finite_deep))
    n = 30_000_000  # 240 MB per array, a few hundred KB compressed: 720 MB inflated
    bomb = root / "bomb.npz"
    np.savez_compressed(bomb, t=np.zeros(n), u=np.zeros(n), y=np.zeros(n))
    out.append(Probe("files", "NPZ bomb (720 MB inflated)", load(bomb), finite_deep))
    liar = root / "liar.npz"
    import zipfile

    with zipfile.ZipFile(liar, "w") as z, z.open("y.npy", "w") as fh:
        np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False, "shape": (10**12,)})
        fh.write(b"\0" * 64)
    out.append(Probe("files", "NPZ header declaring 8 TB", load(liar), finite_deep))
    try:
        import scipy.io

        mat = root / "bomb.mat"
        scipy.io.savemat(mat, {"t": np.zeros(n), "u": np.zeros(n), "y": np.zeros(n)}, do_compression=True)
        out.append(Probe("files", "MAT bomb (720 MB inflated)", load(mat), finite_deep))
    except ImportError:
        pass
    fifo = root / "fifo.csv"
    os.mkfifo(fifo)
    out.append(Probe("files", "FIFO named .csv", load(fifo), finite_deep))
    for suffix in (".csv", ".npz", ".mat"):
        link = root / f"zero{suffix}"
        link.symlink_to("/dev/zero")
        out.append(Probe("files", f"/dev/zero behind {suffix}", load(link), finite_deep))
    d = root / "folder.csv"
    d.mkdir()
    out.append(Probe("files", "folder named .csv", lambda: bw.io.read_csv(d), finite_deep))
    empty = root / "empty.csv"
    empty.write_bytes(b"")
    out.append(Probe("files", "empty .csv", load(empty), finite_deep))
    junk = root / "junk.csv"
    junk.write_bytes(bytes(rng.integers(0, 256, 100_000, dtype=np.uint8)))
    out.append(Probe("files", "binary junk .csv", load(junk), finite_deep))
    long_line = root / "longline.csv"
    long_line.write_text("t,u,y\n" + ",".join(["1"] * 3_000_000) + "\n", encoding="utf-8")
    out.append(Probe("files", "a 6 MB line", load(long_line), finite_deep))
    return out


def cli_probes(rng: np.random.Generator, recs: list[bw.Recording], root: Path) -> list[Probe]:
    data = root / "recs"
    bw.save_recordings(data, recs)
    (root / "bad_plant.json").write_text('{"linear": {"num": [1]}}', encoding="utf-8")
    (root / "not_json.json").write_text("{", encoding="utf-8")
    (root / "occupied").mkdir()
    (root / "occupied" / "old.csv").write_text("x", encoding="utf-8")
    (root / "a_file").write_text("x", encoding="utf-8")
    small = ["--settle-periods", "2", "--periods", "2", "--samples-per-period", "32"]
    out_dir = str(root / "out_{i}")
    argvs = [
        ["demo", "--harmonics", "1e3"],
        ["demo", "--harmonics", str(2**70)],
        ["demo", "--seed", "-1"],
        ["demo", "--samples-per-period", "10000000"],
        ["demo", "--noise", "nan"],
        ["demo", "--mu-bracket", "3", "1"],
        ["demo", "--tol", "-1"],
        ["demo", "--method", "bogus"],
        ["simulate", "--out", out_dir, "--frequencies", "1", "2", "3", "--amplitude", "1", "2", *small],
        ["simulate", "--out", out_dir, "--seed", "-1", *small],
        ["simulate", "--out", out_dir, "--plant", str(root / "bad_plant.json"), *small],
        ["simulate", "--out", out_dir, "--plant", str(root / "not_json.json"), *small],
        ["simulate", "--out", out_dir, "--plant", str(root / "nope.json"), *small],
        ["simulate", "--out", out_dir, "--plant", "/dev/zero", *small],
        ["simulate", "--out", out_dir, "--samples-per-period", "10000000"],
        ["simulate", "--out", out_dir, "--substeps", "1000000000000", *small[:4]],
        ["simulate", "--out", out_dir, "--frequencies", "-1", *small],
        ["simulate", "--out", out_dir, "--frequencies", "inf", *small],
        ["simulate", "--out", out_dir, "--amplitude", "0", *small],
        ["simulate", "--out", out_dir, "--amplitude", "1e300", *small],
        ["simulate", "--out", str(root / "occupied"), *small],
        ["simulate", "--out", str(root / "a_file") + "/sub", *small],
        ["simulate", "--out", out_dir, *small],
        ["simulate", "--out", out_dir + ".npz", *small],
        ["identify", str(data), "--out", str(root / "occupied")],
        ["identify", str(data), "--out", out_dir, "--reference", "99"],
        ["identify", str(data), "--out", out_dir, "--harmonics", "0"],
        ["identify", str(data), "--out", out_dir, "--periods", "0"],
        ["identify", str(data), "--out", out_dir, "--periods", "1000"],
        ["identify", str(data), "--out", out_dir, "--settle-periods", "-1"],
        ["identify", str(data), "--out", out_dir, "--columns", "u"],
        ["identify", str(data), "--out", out_dir, "--sample-rate", "0"],
        ["identify", str(root / "fifo_cli.csv"), "--out", out_dir],
        ["identify", "/dev/null", "--out", out_dir],
        ["identify", str(root / "nowhere"), "--out", out_dir],
        ["identify", str(data), "--out", out_dir, "--method", "paper", "--separately"],
        ["identify", str(data), "--out", out_dir, "--method", "paper"],
        ["bogus-command"],
        [],
    ]
    os.mkfifo(root / "fifo_cli.csv")
    probes = []
    for i, argv in enumerate(argvs):
        a = [x.replace("{i}", str(i)) for x in argv]
        probes.append(
            Probe(
                "cli",
                "bouc-wen-id " + " ".join(x.replace(str(root), "$T") for x in a),
                lambda a=a: cli.main(a),
                lambda code: code == 0,
                cli=True,
            )
        )
    return probes


# --------------------------------------------------------------------------------------------------
# Property-based sweep (issue 19): hypothesis draws the public entry points' scalar and array arguments
# --------------------------------------------------------------------------------------------------


def _draw(strategy: Any, n: int, seed: int) -> list[Any]:
    """``n`` values of a hypothesis strategy, reproducibly from ``seed`` (generation only, no shrinking)."""
    import hypothesis
    from hypothesis import HealthCheck, Phase, given, settings

    out: list[Any] = []

    @hypothesis.seed(seed)
    @settings(
        max_examples=n,
        database=None,
        phases=[Phase.generate],
        suppress_health_check=list(HealthCheck),
        deadline=None,
    )
    @given(strategy)
    def collect(value: Any) -> None:
        out.append(value)

    collect()
    return out[:n]


def _either(default: Any, hostile: Any) -> Any:
    """A field that is its sane default most of the time and a hostile draw otherwise."""
    from hypothesis import strategies as st

    return st.one_of(st.just(default), st.just(default), st.just(default), hostile)


def _scalars() -> Any:
    from hypothesis import strategies as st

    odd = [None, "3", "abc", True, 1 + 1j, [], [1.0, 2.0], np.float32(2.0), np.int64(-5), object()]
    return st.one_of(
        st.floats(allow_nan=True, allow_infinity=True),
        st.floats(min_value=-1e3, max_value=1e3),
        st.integers(min_value=-(2**70), max_value=2**70),
        st.integers(min_value=-3, max_value=600),
        st.sampled_from(odd),
    )


def _arrays(max_size: int = 40) -> Any:
    from hypothesis import strategies as st
    from hypothesis.extra import numpy as hnp

    return st.one_of(
        hnp.arrays(
            np.float64, st.integers(0, max_size), elements=st.floats(allow_nan=True, allow_infinity=True)
        ),
        hnp.arrays(np.float64, st.integers(1, max_size), elements=st.floats(-1e3, 1e3)),
        st.lists(_scalars(), max_size=4),
        _scalars(),
    )


def _pick(kw: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}"[:40] for k, v in kw.items())


def hypothesis_probes(n: int, seed: int, recs: list[bw.Recording], root: Path) -> list[Probe]:
    """``n`` drawn calls per entry point: simulate, simulate_input, identify, diagnose (tiny budgets),
    plan_experiment, fit_transfer_function and load. A result must be finite (NaN or inf is silent)."""
    from bouc_wen_id.terms import TERMS
    from hypothesis import strategies as st

    out: list[Probe] = []
    sc, ar = _scalars(), _arrays()
    # simulate: the plant's and the plan's fields.
    sim = st.fixed_dictionaries(
        {
            "beta": _either(1.0, sc),
            "gamma": _either(0.5, sc),
            "mu": _either(1.5, sc),
            "alpha": _either(1.0, sc),
            "w0": _either(0.0, sc),
            "num": _either([1.0], ar),
            "den": _either([0.3, 1.0], ar),
            "delay": _either(0.02, sc),
            "frequencies": _either([2.0], ar),
            "amplitudes": _either([1.0], ar),
            "samples_per_period": _either(32, sc),
            "periods": _either(2, sc),
            "settle_periods": _either(1, sc),
            "substeps": _either(2, sc),
            "noise_sd": _either(0.01, sc),
            "seed": _either(0, sc),
        }
    )
    for kw in _draw(sim, n, seed):

        def run_sim(kw: dict[str, Any] = kw) -> Any:
            plant = bw.WienerPlant(
                bw.TransferFunction(kw["num"], kw["den"], kw["delay"]),
                bw.BoucWen(kw["beta"], kw["gamma"], kw["mu"], alpha=kw["alpha"], w0=kw["w0"]),
            )
            plan_kw = {k: kw[k] for k in ("samples_per_period", "periods", "settle_periods", "substeps")}
            plan = bw.SinePlan(
                kw["frequencies"], kw["amplitudes"], noise_sd=kw["noise_sd"], seed=kw["seed"], **plan_kw
            )
            return [(r.x, r.w, r.y) for r in bw.simulate(plant, plan)]

        out.append(Probe("h-simulate", _pick(kw), run_sim, finite_deep))
    # simulate_input: the samples, the step, substeps and one term's value (any term, any place).
    terms = st.sampled_from(sorted(TERMS))
    sin = st.fixed_dictionaries(
        {
            "u": _either(np.cos(np.arange(60) * 0.1), ar),
            "dt": _either(0.1, sc),
            "substeps": _either(2, sc),
            "term": terms,
            "value": _either(0.1, sc),
            "output": st.booleans(),
        }
    )
    for kw in _draw(sin, n, seed + 1):

        def run_sin(kw: dict[str, Any] = kw) -> Any:
            cls = TERMS[kw["term"]]
            plant = bw.WienerPlant(
                bw.demo_plant().linear,
                bw.demo_plant().hysteresis,
                (cls.from_dict({cls.symbol: kw["value"]}),),
            )
            u = kw["u"]
            try:  # the time axis of the drawn step; where the draw makes none, the samples themselves
                t = np.arange(len(u)) * float(kw["dt"])
            except (TypeError, ValueError, OverflowError):
                t = u
            return bw.simulate_input(plant, t, u, substeps=kw["substeps"], output=kw["output"])

        out.append(Probe("h-sim_input", _pick(kw), run_sin, finite_deep))
    # identify: the data's scale and offset, and every keyword.
    ident = st.fixed_dictionaries(
        {
            "scale": _either(1.0, st.floats(allow_nan=True, allow_infinity=True)),
            "offset": _either(0.0, st.floats(allow_nan=True, allow_infinity=True)),
            "settle_periods": _either(None, sc),
            "periods": _either(None, sc),
            "harmonics": _either("auto", sc),
            "mu_bracket": _either((1.0, 10.0), ar),
            "tol": _either(1e-8, sc),
            "phase_grid": _either(48, sc),
            "max_iter": _either(30, sc),
            "confidence": _either(0.95, sc),
        }
    )
    for kw in _draw(ident, n, seed + 2):

        def run_id(kw: dict[str, Any] = kw) -> Any:
            data = [
                bw.Recording(
                    r.t,
                    r.u,
                    r.y * kw["scale"] + kw["offset"],
                    r.amplitude,
                    r.frequency,
                    settle_periods=r.settle_periods,
                )
                for r in recs
            ]
            opts = {k: v for k, v in kw.items() if k not in ("scale", "offset")}
            res = bw.identify(data, **opts)
            return (res.beta, res.gamma, res.mu, res.gains)

        out.append(Probe("h-identify", _pick(kw), run_id, finite_deep))
    # diagnose under tiny budgets.
    diag = st.fixed_dictionaries(
        {
            "alpha": _either(0.05, sc),
            "scale": _either(1.0, st.floats(allow_nan=True, allow_infinity=True)),
            "max_steps": st.sampled_from([10**3, 10**5, 10**7]),
            "candidates": _either(None, st.one_of(st.lists(terms, max_size=3), sc)),
            "held_out_test": st.booleans(),
        }
    )
    for kw in _draw(diag, n, seed + 3):

        def run_diag(kw: dict[str, Any] = kw) -> Any:
            data = [
                bw.Recording(
                    r.t, r.u, r.y * kw["scale"], r.amplitude, r.frequency, settle_periods=r.settle_periods
                )
                for r in recs
            ]
            with bw.budget.budget(max_steps=kw["max_steps"]):
                d = bw.diagnose(
                    data, alpha=kw["alpha"], candidates=kw["candidates"], held_out_test=kw["held_out_test"]
                )
            return [t.value for t in d.named]

        out.append(Probe("h-diagnose", _pick(kw), run_diag, finite_deep))
    # plan_experiment: every scalar.
    plan_kw = st.fixed_dictionaries(
        {
            "budget": _either(600.0, sc),
            "band": _either((1.0, 10.0), ar),
            "max_amplitude": _either(2.0, sc),
            "noise_sd": _either(0.01, sc),
            "sample_rate": _either(200.0, sc),
            "n_frequencies": _either(4, sc),
            "n_amplitudes": _either(2, sc),
            "settle_periods": _either(5, sc),
            "max_samples_per_period": _either(128, sc),
            "min_periods": _either(3, sc),
            "substeps": _either(2, sc),
        }
    )
    for kw in _draw(plan_kw, n, seed + 4):

        def run_plan(kw: dict[str, Any] = kw) -> Any:
            opts = dict(kw)
            budget_s = opts.pop("budget")
            res = bw.plan_experiment(bw.demo_plant(), budget_s, **opts)
            return (
                [(e.frequency, e.amplitude) for e in res.experiments] if hasattr(res, "experiments") else res
            )

        out.append(Probe("h-plan", _pick(kw), run_plan, finite_deep))
    # fit_transfer_function on user points.
    tf_kw = st.fixed_dictionaries(
        {
            "omega": _either(np.array([1.0, 2.0, 4.0, 8.0]), ar),
            "re": _either(np.array([1.0, 0.8, 0.5, 0.2]), ar),
            "im": _either(np.array([-0.2, -0.4, -0.5, -0.4]), ar),
            "order": _either(None, sc),
            "delay": _either(None, sc),
            "max_order": _either(4, sc),
        }
    )
    for kw in _draw(tf_kw, n, seed + 5):

        def run_tf(kw: dict[str, Any] = kw) -> Any:
            try:
                response = np.asarray(kw["re"], dtype=float) + 1j * np.asarray(kw["im"], dtype=float)
            except (TypeError, ValueError):
                response = kw["re"]
            fit = bw.fit_transfer_function(
                omega=kw["omega"],
                response=response,
                order=kw["order"],
                delay=kw["delay"],
                max_order=kw["max_order"],
            )
            g = fit.transfer_function  # candidates may hold an inf AICc (no dof): not a result
            return (g.num, g.den, g.delay, fit.parameters, fit.chi2)

        out.append(Probe("h-tfit", _pick(kw), run_tf, finite_deep))
    # load: a recording file whose y column is drawn, with drawn keywords.
    ld = st.fixed_dictionaries(
        {"y": _either(None, _arrays(200)), "sample_rate": _either(None, sc), "skiprows": _either(None, sc)}
    )
    src = recs[0]
    for i, kw in enumerate(_draw(ld, n, seed + 6)):
        path = root / f"h_{i}.csv"
        y = src.y if kw["y"] is None else kw["y"]
        try:
            col = np.resize(np.asarray(y, dtype=float).ravel(), src.t.size) if np.size(y) else np.zeros(0)
        except (TypeError, ValueError):
            col = src.y
        n_rows = min(src.t.size, col.size) if col.size else 0
        lines = [f"# amplitude: {src.amplitude}", f"# frequency: {src.frequency}", "t,u,y"]
        lines += [f"{float(src.t[k])!r},{float(src.u[k])!r},{float(col[k])!r}" for k in range(n_rows)]
        path.write_text("\n".join(lines) + "\n")

        def run_load(kw: dict[str, Any] = kw, path: Path = path) -> Any:
            items = bw.load(path, sample_rate=kw["sample_rate"], skiprows=kw["skiprows"])
            return [(getattr(it, "t", None), getattr(it, "u", None), getattr(it, "y", None)) for it in items]

        out.append(Probe("h-load", _pick(kw), run_load, finite_deep))
    return out


# --------------------------------------------------------------------------------------------------
# Running a probe in a forked child
# --------------------------------------------------------------------------------------------------


def _child(probe: Probe, memory_bytes: int, wfd: int) -> None:
    resource.setrlimit(resource.RLIMIT_AS, (memory_bytes, memory_bytes))
    detail = ""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            if probe.cli:
                err = io.StringIO()
                with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                    try:
                        code = probe.run()
                    except SystemExit as exc:  # argparse
                        code = exc.code if isinstance(exc.code, int) else 2
                text = err.getvalue()
                lines = [line for line in text.splitlines() if line.strip() and not line.startswith("[")]
                detail = lines[-1][:160] if lines else ""
                if code == 0:
                    verdict = "correct"
                elif code == 2 and "Traceback" not in text and len(lines) <= 1:
                    verdict = "named"
                else:
                    verdict = "raw"
                    detail = f"exit {code}: {text.strip()[-300:]}"
            else:
                result = probe.run()
                lib = [w for w in caught if issubclass(w.category, LIBRARY_WARNINGS)]
                if lib:
                    verdict, detail = "warned", f"{lib[0].category.__name__}: {str(lib[0].message)[:120]}"
                elif probe.check(result):
                    verdict = "correct"
                else:
                    verdict, detail = "silent", repr(result)[:160]
    except bw.BoucWenIdError as exc:
        verdict, detail = "named", f"{type(exc).__name__}: {str(exc)[:120]}"
    except MemoryError:
        verdict, detail = "memory", "MemoryError"
    except BaseException as exc:  # noqa: BLE001 - the point is to see every other exception
        verdict = "raw"
        detail = (
            f"{type(exc).__name__}: {str(exc)[:160]} @ {traceback.extract_tb(exc.__traceback__)[-1].name}"
        )
    os.write(wfd, f"{verdict}\t{detail}".encode("utf-8", "replace")[:4000])
    os.close(wfd)
    os._exit(0)


def run_probe(probe: Probe, time_limit: float, memory_bytes: int, cwd: Path) -> tuple[str, str, float]:
    rfd, wfd = os.pipe()
    t0 = time.monotonic()
    pid = os.fork()
    if pid == 0:  # the child
        os.close(rfd)
        os.chdir(cwd)
        try:
            _child(probe, memory_bytes, wfd)
        finally:
            os._exit(1)
    os.close(wfd)
    status = None
    while time.monotonic() - t0 < time_limit:
        done, status = os.waitpid(pid, os.WNOHANG)
        if done:
            break
        time.sleep(0.01)
    else:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        os.close(rfd)
        return "hang", f"still running after {time_limit:g} s", time.monotonic() - t0
    with os.fdopen(rfd, "rb") as fh:
        msg = fh.read().decode("utf-8", "replace")
    elapsed = time.monotonic() - t0
    if not msg:
        sig = os.WTERMSIG(status) if status is not None and os.WIFSIGNALED(status) else None
        # Killed at the memory limit (an allocation abort) or any other crash.
        if sig in (signal.SIGABRT, signal.SIGSEGV, signal.SIGBUS, signal.SIGKILL):
            return (
                "memory" if sig in (signal.SIGABRT, signal.SIGKILL) else "raw",
                f"killed by signal {sig}",
                elapsed,
            )
        return "raw", f"child ended without a verdict (status {status})", elapsed
    verdict, _, detail = msg.partition("\t")
    return verdict, detail, elapsed


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--time-limit", type=float, default=60.0, help="seconds per probe (a hang beyond)")
    ap.add_argument("--memory-gb", type=float, default=3.0, help="address-space limit per probe")
    ap.add_argument("--only", default=None, help="run only this category")
    ap.add_argument("--verbose", action="store_true", help="print every probe, not only the misses")
    ap.add_argument(
        "--hypothesis",
        type=int,
        default=0,
        metavar="N",
        help="only the property-based sweep: N drawn calls per public entry point (--quick: 15)",
    )
    ap.add_argument("--quick", action="store_true", help="the sweep with 15 draws per entry point (< 2 min)")
    args = ap.parse_args()
    if args.quick and not args.hypothesis:
        args.hypothesis = 15
    rng = np.random.default_rng(args.seed)
    plan = bw.SinePlan(
        [3.0, 5.0, 7.0],
        [1.0, 0.8, 1.2],
        settle_periods=10,
        periods=8,
        samples_per_period=64,
        noise_sd=0.005,
        seed=args.seed,
    )
    recs = bw.simulate(bw.demo_plant(), plan)
    with tempfile.TemporaryDirectory(prefix="probe_hostile_") as tmp:
        root = Path(tmp)
        (root / "files").mkdir()
        (root / "cli").mkdir()
        probes = (
            hypothesis_probes(args.hypothesis, args.seed, recs, root / "files")
            if args.hypothesis
            else value_probes(rng)
            + work_probes(rng)
            + identify_probes(rng, recs)
            + data_probes(rng, recs)
            + core_probes(rng)
            + file_probes(rng, recs, root / "files")
            + cli_probes(rng, recs, root / "cli")
        )
        if args.hypothesis:
            args.time_limit = min(args.time_limit, 30.0)  # the sweep's hang limit (issue 19: > 30 s)
        if args.only:
            probes = [p for p in probes if p.category == args.only]
        counts: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
        misses = []
        t_start = time.monotonic()
        for i, probe in enumerate(probes):
            verdict, detail, elapsed = run_probe(
                probe, args.time_limit, int(args.memory_gb * 2**30), root / "cli"
            )
            counts[probe.category][verdict] += 1
            head = f"[{i + 1:3d}/{len(probes)}] {verdict:<7} {elapsed:6.2f}s {probe.category:<8}"
            line = f"{head} {probe.name[:70]:<70} {detail[:150]}"
            if args.verbose:
                print(line, flush=True)
            if verdict in ("raw", "silent", "hang", "memory"):
                misses.append(line)
        total: collections.Counter[str] = collections.Counter()
        for c in counts.values():
            total.update(c)
        print(
            f"\n{len(probes)} probes in {time.monotonic() - t_start:.0f} s (seed {args.seed}, "
            f"{args.time_limit:g} s and {args.memory_gb:g} GiB per probe, default budgets)\n"
        )
        header = f"{'category':<10}" + "".join(f"{v:>9}" for v in VERDICTS) + f"{'total':>9}"
        print(header)
        for cat, c in counts.items():
            print(f"{cat:<10}" + "".join(f"{c[v]:>9}" for v in VERDICTS) + f"{sum(c.values()):>9}")
        print(f"{'all':<10}" + "".join(f"{total[v]:>9}" for v in VERDICTS) + f"{sum(total.values()):>9}")
        print(
            f"{'target':<10}"
            + "".join(f"{'-' if v in ('named', 'correct', 'warned') else 0:>9}" for v in VERDICTS)
        )
        if misses:
            print("\nmisses:")
            for line in misses:
                print("  " + line)
        return 1 if misses else 0


if __name__ == "__main__":
    sys.exit(main())
