"""Which cases can the session-30 changes move? A case's verdict can change only when (a) the zero-drift test
fires beside a trending loop (loop_centre.resolved runs) or (b) the old and new pooled decay tests give the
zero-drift test different answers. Each case's items, the wander test first as diagnose runs it.

Usage: ``python studies/zero_drift_moves.py only=asymmetry,degradation,offset,null noise=drift`` (the blind
bench's cases, its defaults seed 2026, 6 cases, 20 nulls, sizes 10,30) or ``python studies/zero_drift_moves.py
ours degradation,asymmetry,null 6 20`` (benches/diagnosis.py's cases, sizes 10 and 30, its seeds); one line
per case: key, noise, what fired (wander / drift / none), whether the loop-centre check runs,
whether the pools differ.
"""

import math
import sys
import tempfile
from pathlib import Path

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import baseline
from bouc_wen_id.diagnosis import zero_drift as Z
from scipy.special import ndtr, ndtri

NEW = Z._pooled


def OLD(decays, slow=()):
    if not decays:
        return math.nan
    z = ndtri(1.0 - np.clip(np.asarray(decays, float), 1e-300, 1 - 1e-16))
    z = np.minimum(z, float(ndtri(1.0 - Z.SLOWING_LEVEL / len(decays))))
    return float(ndtr(-float(np.sum(z)) / math.sqrt(len(decays))))


def check(items, level):
    if baseline.detect(items, level) is not None:
        return "wander", False, False
    Z._pooled = OLD
    a = Z.detect(items, level)
    Z._pooled = NEW
    b = Z.detect(items, level)
    fires = b is not None and b.loop_trends
    differs = (a is None) != (b is None)
    return ("drift" if b is not None else "none"), fires, differs


def blind(argv):
    sys.path.insert(0, "benches")
    import blind as B

    args = B.argparse.Namespace(
        **{
            "seed": 2026,
            "cases": 6,
            "null": 20,
            "outside": 0,
            "sizes": "10,30",
            "only": None,
            "noise": None,
            "drift": B.DRIFT,
        }
    )
    for kv in argv:
        k, v = kv.split("=")
        setattr(args, k, type(getattr(args, k))(v) if getattr(args, k) is not None else v)
    from bouc_wen_id.terms import DIAGNOSIS_CANDIDATES as DC

    for case in B.cases(args):
        made = B.make_case(case)
        with tempfile.TemporaryDirectory() as tmp:
            paths = []
            for i, (e, u, y) in enumerate(zip(made["exps"], made["u"], made["y"])):
                paths.append(Path(tmp) / f"run_{i:02d}.csv")
                B.write_csv(paths[-1], e, u, y)
            items = bw.load(paths)
            n = len(DC)
            got = check(items, 0.05 / n)
        print(case.key, made["info"].get("noise", ""), *got, flush=True)


def ours(only, cases, null):
    sys.path.insert(0, "benches")
    import diagnosis as DB
    import generator as gen
    from bouc_wen_id.terms import DIAGNOSIS_CANDIDATES as DC

    args = DB.argparse.Namespace(quick=False, cases=cases, null=null, seed=0)
    jobs = [j for j in DB.new_jobs(args) if (j[1] or "null") in set(only.split(","))]
    jobs = [j for j in jobs if j[3] in (10.0, 30.0) or j[0] == "null"]
    for kind, name, place, size, seed in jobs:
        case = gen.cached_case(kind, name, place, size, seed, None)
        print(kind, name, size, seed, *check(case.recordings, 0.05 / len(DC)), flush=True)


if __name__ == "__main__":
    if sys.argv[1] == "ours":
        ours(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
    else:
        blind(sys.argv[1:])
