"""The diagnosis's speed switches (issue 18 item 4; diagnosis/speed.py) change its speed, never its findings.

Data from ``benches/generator.py`` (G solved exactly, its own RK4 of the hysteresis, its own noise: made
another way than the library's simulator).
"""

from __future__ import annotations

import importlib
import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bouc_wen_id.diagnosis import fitting, speed
from bouc_wen_id.diagnosis.data import prepare

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")
bench: Any = importlib.import_module("diagnosis")


def _scaled_case(seed: int) -> tuple[list[Any], Any]:
    case = gen.make_case("library", "coulomb", "x", 30.0, seed)
    exps = prepare(case.recordings)
    s = fitting.scale_of(exps)
    return exps, fitting.scaled(exps, s)


@pytest.mark.parametrize("seed", [3, 8])
def test_screening_all_levels_from_one_loop_per_offset_matches_one_screen_per_level(seed: int) -> None:
    exps, sx = _scaled_case(seed)
    s = fitting.scale_of(exps)
    plain = fitting.plain_start(exps, sx, s)[0]
    rng = np.random.default_rng(seed)
    # Phases off by up to 0.3 rad (the bias a plain fit has beside a 30x friction on x), several levels.
    base = replace(plain.with_term("coulomb@x", 0.0), phases=plain.phases + rng.uniform(-0.3, 0.3, len(sx)))
    peak = max(float(np.max(np.abs(e.ybar))) for e in sx)
    levels = [0.0, *(peak * rng.uniform(0.01, 0.4, 3))]
    pars = [replace(base, values=np.append(base.values[:-1], v)) for v in levels]
    substeps = fitting.substeps_for([e.ybar.size for e in sx])
    one = [fitting.screen_phases(sx, p, substeps) for p in pars]
    once = fitting.screen_phases_linear(sx, pars, substeps)
    for (pa, ca), (pb, cb) in zip(one, once):
        assert np.array_equal(pa.phases, pb.phases)
        assert cb == pytest.approx(ca, rel=1e-10)
    # The screen moved some phase (else the comparison would say nothing).
    assert any(not np.array_equal(pa.phases, base.phases) for pa, _ in one)


def test_a_level_the_core_refuses_keeps_its_phases_at_cost_inf(monkeypatch: pytest.MonkeyPatch) -> None:
    from bouc_wen_id.errors import InvalidParameterError

    exps, sx = _scaled_case(4)
    plain = fitting.plain_start(exps, sx, fitting.scale_of(exps))[0]
    base = plain.with_term("coulomb@x", 0.0)
    refused = 0.123
    from bouc_wen_id.augmented import augmented_output as real

    def output(e: Any, par: Any, i: int, **kw: Any) -> Any:
        if float(par.values[-1]) == refused:  # as the core refuses a value outside a term's range
            raise InvalidParameterError("refused level")
        return real(e, par, i, **kw)

    monkeypatch.setattr(fitting, "augmented_output", output)
    pars = [replace(base, values=np.append(base.values[:-1], v)) for v in (0.0, refused, 0.05)]
    substeps = fitting.substeps_for([e.ybar.size for e in sx])
    one = [fitting.screen_phases(sx, p, substeps) for p in pars]
    once = fitting.screen_phases_linear(sx, pars, substeps)
    assert once[1][1] == math.inf and np.array_equal(once[1][0].phases, base.phases)
    for (pa, ca), (pb, cb) in zip(one, once):
        assert np.array_equal(pa.phases, pb.phases)
        assert cb == pytest.approx(ca, rel=1e-10)


def test_diagnosis_is_the_same_with_the_speed_switches_off(monkeypatch: pytest.MonkeyPatch) -> None:
    import bouc_wen_id as bw

    case = gen.make_case("library", "coulomb", "x", 30.0, 5)
    cands = ["offset", "coulomb", "coulomb@x"]
    fast = bw.diagnose(case.recordings, candidates=cands)
    monkeypatch.setattr(speed, "ONE_BLAS_THREAD", False)
    monkeypatch.setattr(speed, "SCREEN_ONCE", False)
    monkeypatch.setattr(speed, "MEMO_REFITS", False)
    slow = bw.diagnose(case.recordings, candidates=cands)
    assert fast.status == slow.status
    assert fast.verdict == slow.verdict
    assert [t.term for t in fast.named] == [t.term for t in slow.named]
    assert fast.final.cost == pytest.approx(slow.final.cost, rel=1e-9)


def test_diagnose_runs_on_one_blas_thread_and_restores_the_callers(monkeypatch: pytest.MonkeyPatch) -> None:
    threadpoolctl = pytest.importorskip("threadpoolctl")
    import bouc_wen_id as bw

    for v in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "OMP_NUM_THREADS", "BLIS_NUM_THREADS"):
        monkeypatch.delenv(v, raising=False)
    np.linalg.svd(np.eye(3))  # NumPy's BLAS loaded
    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        before = [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]
        seen: list[int] = []

        def progress(stage: str, done: int, total: int) -> None:
            seen.extend(p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas")

        case = gen.make_case("null", None, "", 0.0, 2)
        bw.diagnose(case.recordings, candidates=["offset"], progress=progress)
        after = [p["num_threads"] for p in threadpoolctl.threadpool_info() if p["user_api"] == "blas"]
    assert seen and set(seen) == {1}
    assert after[: len(before)] == before
    assert max(before) == 2 or min(before) == 1  # a one-core machine has nothing to limit


@pytest.mark.parametrize(
    ("term", "place", "kind"),
    [("viscous", "x", "viscous@x"), ("viscous", "u", "viscous"), ("offset", "", "offset"), (None, "", None)],
)
def test_the_bench_compares_with_the_hidden_term_at_its_place(term: Any, place: str, kind: Any) -> None:
    assert bench.true_kind(term, place) == kind


def test_the_bench_refuses_a_place_the_registry_does_not_have() -> None:
    with pytest.raises(ValueError):
        bench.true_kind("viscous", "nowhere")
