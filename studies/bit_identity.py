"""Bit-identity of two builds of the extension on the public `_core` functions of the augmented
model and the simulation with terms (`augmented_output`, `augmented_refine`, `simulate_sine` and
`simulate_sampled` with `terms=`): random inputs from a fixed seed, bad values among them so that
the error messages are compared too. Written for the split of `rust/augmented.rs` and
`rust/simulate/with_terms.rs` into folders (a refactor that must not move a bit); `orders 0-7` (G of
order 0-7 with and without terms: every integrator's RK4 scratch, rust/simulate/rk4.rs) was added for
the RK4 scratch's move into one helper.

Each build runs in its own process (one `_core` per interpreter):

    cp python/bouc_wen_id/_core.abi3.so /tmp/before.so      # before the change
    python studies/bit_identity.py run /tmp/before.so /tmp/before.pkl
    python studies/bit_identity.py run python/bouc_wen_id/_core.abi3.so /tmp/after.pkl
    python studies/bit_identity.py compare /tmp/before.pkl /tmp/after.pkl
"""

import importlib.machinery
import importlib.util
import pickle
import sys

import numpy as np

SEED = 20261126
N_AUG, N_SIM, N_REF, N_ORDER = 420, 360, 30, 160

USUAL = [
    "offset",
    "stiffness",
    "viscous",
    "inertia",
    "coulomb",
    "sensor_lag",
    "asymmetry",
    "play",
    "pinching",
    "series_dashpot",
    "distortion",
    "degradation",
    "stiffness_degradation",
]
ON_X = ["stiffness@x", "viscous@x", "inertia@x", "coulomb@x"]


def load(so):
    loader = importlib.machinery.ExtensionFileLoader("_core", so)
    spec = importlib.util.spec_from_file_location("_core", so, loader=loader)
    mod = importlib.util.module_from_spec(spec)
    loader.exec_module(mod)
    return mod


def value(rng, name, beta, gamma):
    base = name.split("@")[0]
    return {
        "offset": rng.normal(0, 0.3),
        "stiffness": rng.normal(0, 0.5),
        "viscous": rng.normal(0, 0.1),
        "inertia": rng.normal(0, 0.01),
        "coulomb": rng.normal(0, 0.2),
        "sensor_lag": rng.uniform(0, 0.1),
        "asymmetry": rng.uniform(-0.8, 0.8) * (beta + gamma),
        "play": rng.uniform(0, 0.3),
        "pinching": rng.uniform(0, 0.8),
        "series_dashpot": rng.uniform(0, 1.0),
        "distortion": rng.normal(0, 0.3),
        "degradation": rng.uniform(0, 0.3),
        "stiffness_degradation": rng.uniform(0, 0.3),
        "dahl": rng.uniform(0, 0.3),
        "dahl_sigma": rng.uniform(0.1, 3.0),
    }[base]


def bad(rng, v):
    """Sometimes a bad value, so that the error paths are compared too."""
    r = rng.uniform()
    return np.nan if r < 0.03 else (-abs(v) - 0.1 if r < 0.08 else v)


def capture(f, *args, **kwargs):
    try:
        out = f(*args, **kwargs)
        return (
            "ok",
            [
                np.asarray(o, dtype=float) if not isinstance(o, (str, list, bool, int, float)) else o
                for o in (out if isinstance(out, tuple) else (out,))
            ],
        )
    except Exception as e:  # noqa: BLE001 - the message is what is compared
        return ("err", type(e).__name__, str(e))


def aug_cases(core, rng):
    res = []
    for _ in range(N_AUG):
        beta, gamma, mu = rng.uniform(0.3, 1.0), rng.uniform(-0.2, 0.3), rng.uniform(1.0, 2.5)
        pool = USUAL + ON_X
        names = list(rng.choice(pool, size=rng.integers(0, 5), replace=False))
        if rng.uniform() < 0.3:
            place = "@x" if rng.uniform() < 0.5 else ""
            names += ["dahl" + place, "dahl_sigma" + place]
        shared = [beta, gamma, mu] + [bad(rng, value(rng, n, beta, gamma)) for n in names]
        p = int(rng.integers(8, 80))
        wf = rng.normal(0, 0.05, 2 * int(rng.integers(1, 3))) if "distortion" in names else None
        amp = rng.choice([1.0, -1.0]) * rng.uniform(0.3, 2.0) if rng.uniform() > 0.02 else 0.0
        args = (
            p,
            amp,
            rng.uniform(0.5, 5.0),
            rng.uniform(-3, 3),
            names,
            np.array(shared),
            rng.uniform(-1.5, 1.5),
            rng.uniform(-3, 3),
            int(rng.integers(1, 6)),
        )
        res.append(capture(core.augmented_output, *args, waveform=wf))
    return res


def sim_cases(core, rng):
    res = []
    for i in range(N_SIM):
        beta, gamma, mu = rng.uniform(0.3, 1.0), rng.uniform(-0.2, 0.3), rng.uniform(1.0, 2.5)
        kind = i % 3
        if kind == 0:
            num, den = [rng.uniform(0.5, 2)], [rng.uniform(0.05, 0.5), 1.0]
        elif kind == 1:
            wn, z = rng.uniform(2, 10), rng.uniform(0.05, 0.5)
            num, den = [wn * wn], [1.0, 2 * z * wn, wn * wn]
        else:
            num, den = [rng.uniform(0.5, 2)], [1.0]
        delay = rng.uniform(0, 0.1) if rng.uniform() < 0.5 else 0.0
        names = list(rng.choice(USUAL + ON_X, size=rng.integers(0, 5), replace=False))
        if rng.uniform() < 0.1 and "distortion" not in names:
            # One term without a time-domain form at most: the binding reads the terms through a
            # hash map, so with two the message names either (the same on main).
            names.append("dahl")
        terms = {n: bad(rng, value(rng, n, beta, gamma)) for n in names}
        if rng.uniform() < 0.2:
            terms["coulomb_smoothing"] = rng.uniform(0.005, 0.6)
        bw = (1.0, beta, gamma, mu, rng.normal(0, 0.1))
        dt, sub = rng.uniform(0.005, 0.03), int(rng.integers(1, 4))
        if rng.uniform() < 0.5:
            args = (num, den, delay, *bw, rng.uniform(0.3, 2), rng.uniform(0.5, 6), dt, 300, sub)
            res.append(capture(core.simulate_sine, *args, terms=terms))
        else:
            u = np.cumsum(rng.normal(0, 0.1, 300))
            args = (num, den, delay, *bw, u, dt, sub)
            res.append(capture(core.simulate_sampled, *args, terms=terms))
    return res


def order_cases(core, rng):
    """G of order 0-7 (above 4 the plain path steps vectors, below it fixed arrays; the path with terms
    always vectors), without terms (the plain integrator) and with them (Dahl friction among them, the
    linear part's own pass for a friction on x with samples): the RK4 scratch of every integrator."""
    res = []
    for i in range(N_ORDER):
        order = i % 8
        poles = -rng.uniform(0.5, 8.0, order)
        den = np.real(np.poly(poles)) * rng.uniform(0.5, 2.0) if order else np.array([rng.uniform(0.5, 2)])
        num = rng.uniform(0.5, 2.0, int(rng.integers(0, order + 1)) + 1)
        num *= rng.uniform(0.5, 2.0) * den[-1] / num.sum() / max(1.0, float(np.max(num / den[0])))
        delay = rng.uniform(0, 0.1) if rng.uniform() < 0.5 else 0.0
        beta, gamma, mu = rng.uniform(0.3, 1.0), rng.uniform(-0.2, 0.3), rng.uniform(1.0, 2.5)
        bw = (1.0, beta, gamma, mu, rng.normal(0, 0.1))
        dt, sub = rng.uniform(0.005, 0.03), int(rng.integers(1, 4))
        kwargs = {}
        if (i // 8) % 2:
            names = list(rng.choice(USUAL[:-3] + ON_X, size=rng.integers(1, 5), replace=False))
            names = [n for n in names if n != "distortion"]
            if rng.uniform() < 0.5:
                names += ["dahl", "dahl_sigma", "dahl@x", "dahl_sigma@x"]
            kwargs["terms"] = {n: abs(value(rng, n, beta, gamma)) for n in names}
        if rng.uniform() < 0.5:
            args = (num, den, delay, *bw, rng.uniform(0.3, 2), rng.uniform(0.5, 6), dt, 300, sub)
            res.append(capture(core.simulate_sine, *args, **kwargs))
        else:
            u = np.cumsum(rng.normal(0, 0.1, 300))
            args = (num, den, delay, *bw, u, dt, sub)
            res.append(capture(core.simulate_sampled, *args, **kwargs))
    return res


def refine_cases(core, rng):
    res = []
    for _ in range(N_REF):
        names = list(
            rng.choice(
                ["offset", "viscous", "sensor_lag", "stiffness@x", "asymmetry", "play"],
                size=rng.integers(1, 4),
                replace=False,
            )
        )
        if rng.uniform() < 0.3:
            names += ["dahl", "dahl_sigma"]
        beta, gamma, mu = 0.8, 0.2, 1.6
        truth = np.array([beta, gamma, mu] + [abs(value(rng, n, beta, gamma)) * 0.5 for n in names])
        m = 3
        ybars, amps, freqs, phs = [], [], [], []
        for i in range(m):
            p, a, w, ph = 32, 1.0 + 0.5 * i, 1.0 + i, 0.3 * i
            y = core.augmented_output(p, a, w, ph, names, truth, 1.0, 0.5, 4)[0]
            ybars.append(y + rng.normal(0, 1e-3, p))
            amps.append(a), freqs.append(w), phs.append(ph)
        start = truth * rng.uniform(0.9, 1.1, truth.size)
        res.append(
            capture(
                core.augmented_refine,
                ybars,
                amps,
                freqs,
                phs,
                [1e6] * m,
                names,
                start,
                [1.05] * m,
                [0.45] * m,
                max_iter=30,
            )
        )
    return res


def run(so, out):
    core = load(so)
    rng = np.random.default_rng(SEED)
    data = {
        "augmented_output": aug_cases(core, rng),
        "simulate": sim_cases(core, rng),
        "augmented_refine": refine_cases(core, rng),
        "orders 0-7": order_cases(core, np.random.default_rng(SEED + 1)),
    }
    with open(out, "wb") as fh:
        pickle.dump(data, fh)


def diff(a, b):
    if a[0] != b[0] or len(a) != len(b):
        return np.inf, 1
    if a[0] == "err":
        return 0.0, int(a != b)
    worst, mism = 0.0, 0
    for x, y in zip(a[1], b[1]):
        if isinstance(x, np.ndarray):
            if x.shape != y.shape:
                return np.inf, 1
            if x.size:
                both_nan = np.isnan(x) & np.isnan(y)
                d = np.where(both_nan, 0.0, np.abs(x - y))
                worst = max(worst, float(np.max(d)))
                mism += int(not np.array_equal(x.view(np.int64), y.view(np.int64)))
        elif isinstance(x, list) and x and isinstance(x[0], np.ndarray):
            for xx, yy in zip(x, y):
                worst = max(worst, float(np.max(np.abs(xx - yy))))
                mism += int(not np.array_equal(xx.view(np.int64), yy.view(np.int64)))
        else:
            mism += int(x != y)
    return worst, mism


def compare(pa, pb):
    with open(pa, "rb") as fa, open(pb, "rb") as fb:
        a, b = pickle.load(fa), pickle.load(fb)
    total_bad = 0
    for key in a:
        ok = sum(r[0] == "ok" for r in a[key])
        errs = len(a[key]) - ok
        worst, mism = 0.0, 0
        for x, y in zip(a[key], b[key], strict=True):
            d, m = diff(x, y)
            worst, mism = max(worst, d), mism + m
        total_bad += mism
        emsgs = len({r[2] for r in a[key] if r[0] == "err"})
        print(
            f"{key:18s} cases {len(a[key]):4d}  ok {ok:4d}  errors {errs:3d} ({emsgs} distinct messages)"
            f"  max|diff| {worst:.1e}  bitwise mismatches {mism}"
        )
    print("IDENTICAL" if total_bad == 0 else f"DIFFERENT in {total_bad} places")


if __name__ == "__main__":
    if sys.argv[1] == "run":
        run(sys.argv[2], sys.argv[3])
    else:
        compare(sys.argv[2], sys.argv[3])
