"""diagnose_across reuses its conditions' own candidate fits (diagnosis/fit_share.py), reads their stability
checks (diagnosis/across_stable.py), and Ctrl-C during the drift correction's threaded simulations reaches
the caller without waiting for them (drift._run_all).

The conditions are made by the bench's independent generator (benches/generator.py), as in
test_diagnosis_shared.py.
"""

from __future__ import annotations

import importlib
import os
import pickle
import signal
import sys
import threading
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.diagnosis import drift, fitting, select, speed, stability
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.terms import Distortion

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
G: Any = importlib.import_module("generator")

CANDS = ["offset", "stiffness", "viscous", "viscous@x", "asymmetry"]


def _groups(seed: int, sizes: tuple[float, ...]) -> list[list[Any]]:
    """Recordings of one plant with viscous damping on u sized ``sizes`` averaged-noise sd per condition."""
    p = G.make_plant(seed)
    b = G.base(p)
    plain = G.run(p, G.Effect(), shared=b)
    one = float(G.contribution(p, G.Effect("viscous", "u", np.ones(1)), plain, b)[0])
    y = G.run(p, G.Effect("viscous", "u", np.asarray(sizes) / one), shared=b)
    return [G.recordings(p, y[k], 100 * seed + 50 + k, noise_sd=G.NOISE_SD) for k in range(len(sizes))]


@pytest.fixture(scope="module")
def levels() -> tuple[list[list[Any]], list[bw.Diagnosis]]:
    groups = _groups(5, (0.5, 0.8))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g, candidates=CANDS) for g in groups]
    return groups, own


def _across(groups: list[list[Any]], per_condition: Any) -> bw.AcrossDiagnosis:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose_across(groups, [0.0, 1.0], candidates=CANDS, per_condition=per_condition)


def _result(a: bw.AcrossDiagnosis) -> dict[str, Any]:
    out = a.to_dict()
    out.pop("seconds")
    return out


def test_across_reuses_the_conditions_own_candidate_fits_and_finds_the_same(
    levels: tuple[list[list[Any]], list[bw.Diagnosis]], monkeypatch: pytest.MonkeyPatch
) -> None:
    groups, _ = levels
    calls = {"n": 0}
    real = fitting.fit_with  # the function select calls

    def counted(*args: Any, **kw: Any) -> Any:
        calls["n"] += 1
        return real(*args, **kw)

    monkeypatch.setattr(select, "fit_with", counted)  # before the conditions' own diagnoses: one key
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        own = [bw.diagnose(g, candidates=CANDS) for g in groups]
    assert all(d.fits for d in own)  # each diagnosis kept its candidate fits
    calls["n"] = 0
    shared = _across(groups, own)
    with_sharing = calls["n"]
    monkeypatch.setattr(speed, "SHARE_FITS", False)
    calls["n"] = 0
    fresh = _across(groups, own)
    assert calls["n"] > 0 and with_sharing < calls["n"], (with_sharing, calls["n"])
    assert _result(shared) == _result(fresh)  # the stored fits are the ones a refit gives, bit for bit
    assert shared.named == ("viscous",), shared.verdict


def test_a_diagnosis_pickles_without_its_fits(levels: tuple[list[list[Any]], list[bw.Diagnosis]]) -> None:
    d = levels[1][0]
    assert d.fits
    back = pickle.loads(pickle.dumps(d))
    assert not back.fits and back.verdict == d.verdict


def _unstable(d: bw.Diagnosis) -> stability.Stability:
    """``d`` checked against a variant that named nothing and could have seen every term (limit 0)."""
    silent = replace(d, named=(), partial=(), limits=())
    return stability.stability(d, {"early": silent})


def test_a_conditions_alternative_is_not_listed_as_its_term(
    levels: tuple[list[list[Any]], list[bw.Diagnosis]],
) -> None:
    from bouc_wen_id.diagnosis import across_stable

    groups, own = levels
    assert [t.term for t in own[0].named] == ["viscous"], own[0].verdict
    check = _unstable(own[0])
    assert check.alternatives == ("viscous",)
    a = _across(groups, [check, own[1]])
    c0, c1 = a.conditions
    assert c0.per_level_terms == () and c0.per_level_alternatives == ("viscous",)
    assert c0.per_level_text == "none; viscous: an alternative, not a finding", c0.per_level_text
    assert c1.per_level_terms == tuple(t.term for t in own[1].named) and c1.per_level_alternatives == ()
    assert a.to_dict()["conditions"][0]["per_level_alternatives"] == ["viscous"]
    # Read afterwards (no refit), the same conditions.
    plain = _across(groups, own)
    assert plain.conditions[0].per_level_terms == ("viscous",)
    assert across_stable.checked(plain, [check, None]).conditions == a.conditions
    # A check of another diagnosis is refused, by name.
    other = _unstable(replace(own[0], named=own[0].named * 2))
    with pytest.raises(InvalidParameterError, match="condition 0"):
        across_stable.checked(plain, [other, None])
    with pytest.raises(InvalidParameterError, match="per_condition"):
        _across(groups, ["not a diagnosis", own[1]])


def test_ctrl_c_does_not_wait_for_the_running_drift_simulations(monkeypatch: pytest.MonkeyPatch) -> None:
    """The simulations run on worker threads, where a signal does not reach the core: Ctrl-C must reach the
    caller at once, not after they end (here they end only when released, after the interrupt is seen)."""
    monkeypatch.setattr(speed, "THREAD_DRIFT_SIMS", True)
    monkeypatch.setattr(os, "cpu_count", lambda: 2)
    # Python's own Ctrl-C handler, whatever an earlier test (the CLI's, run in this process) left installed.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    started, release = threading.Barrier(3), threading.Event()

    def sim(*job: Any) -> np.ndarray:
        started.wait(timeout=30)
        release.wait(timeout=30)
        return np.zeros(1)

    def interrupt() -> None:
        started.wait(timeout=30)  # both simulations are running
        os.kill(os.getpid(), signal.SIGINT)

    threading.Thread(target=interrupt, daemon=True).start()
    safety = threading.Timer(30.0, release.set)  # without the fix the call returns only once they end
    safety.start()
    released_at_interrupt = None
    try:
        drift._run_all(sim, [(0,), (1,)])
    except KeyboardInterrupt:
        released_at_interrupt = release.is_set()
    finally:
        release.set()  # the running simulations end now
        safety.cancel()
        signal.signal(signal.SIGINT, previous)
    assert released_at_interrupt is False, "Ctrl-C waited for the running simulations"


def test_the_settled_experiments_alone_are_diagnosed_without_the_whole_set_first(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Three of six records from a degrading loop, degradation not a candidate: those three still drift and
    are left out. The whole set's selection used to run first and be thrown away; the verdict is the same
    without it (speed.LEAVE_OUT_EARLY), and one selection runs instead of two."""
    from bouc_wen_id.diagnosis import after_named

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    B: Any = importlib.import_module("test_degradation_beside_drift")
    steady, degrading = B._records(1, 0.0, 0.0), B._records(1, 3 * B.RATE, 0.0)
    recs = [*steady[:3], *degrading[3:]]
    calls = {"n": 0}
    real = select.forward_select  # the function run calls (through after_named.select)

    def counted(*args: Any, **kw: Any) -> Any:
        calls["n"] += 1
        return real(*args, **kw)

    monkeypatch.setattr(after_named, "forward_select", counted)
    got = {}
    for early in (True, False):
        monkeypatch.setattr(speed, "LEAVE_OUT_EARLY", early)
        calls["n"] = 0
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = bw.diagnose(recs, candidates=["offset", "viscous", "stiffness"])
        out = d.to_dict()
        out.pop("seconds")
        got[early] = (out, calls["n"])
    assert "left out (not settled, or a drifting sensor)" in got[True][0]["verdict"], got[True][0]["verdict"]
    assert got[True][0] == got[False][0]
    assert got[True][1] < got[False][1], (got[True][1], got[False][1])


def test_the_lab_noise_levels_share_each_periods_averaged_values_exactly() -> None:
    """lab_colour.levels and harmonic_levels take the averaged period out of the same periods of a stretch:
    computed once (``models``), both return what each returns alone, bit for bit. AR(1) noise, so that the
    colour check gets past its early returns."""
    from bouc_wen_id.diagnosis import data, lab_colour

    rng = np.random.default_rng(7)
    p = 100.37  # samples a period, not whole (a fixed sampling rate)
    n = int(24 * p)
    th = np.asarray(2.0 * np.pi * np.arange(n) / p, dtype=np.float64)
    k = np.floor(th / (2.0 * np.pi)).astype(np.int64)
    e = np.zeros(n)
    for i in range(1, n):
        e[i] = 0.8 * e[i - 1] + 0.05 * rng.standard_normal()
    y = np.cos(th) + 0.3 * np.abs(np.cos(th)) ** 3 + e
    grid = 2.0 * np.pi * np.arange(64) / 64
    ybar = np.cos(grid) + 0.3 * np.abs(np.cos(grid)) ** 3
    kept = list(range(int(k.max())))
    white = float(np.var(np.diff(e))) / 2.0
    rules = (data.COLOUR_BAND, data.COLOUR_ALPHA, data.cross_period_inflation)
    inflation = data.cross_period_inflation
    hrules = (data._harmonics_of(ybar.size), data.COLOUR_BAND, data.HARMONIC_FLOOR, inflation)
    alone = lab_colour.levels(k, th, y, kept, white, n, ybar, rules)
    alone_h = lab_colour.harmonic_levels(k, th, y, kept, white, ybar, hrules)
    models: dict[int, Any] = {}
    shared = lab_colour.levels(k, th, y, kept, white, n, ybar, rules, models)
    assert len(models) >= len(kept) - 1  # every whole period's values kept for the other
    shared_h = lab_colour.harmonic_levels(k, th, y, kept, white, ybar, hrules, models)
    assert alone is not None and shared == alone
    assert alone_h.size and np.array_equal(shared_h, alone_h)


def test_a_waveform_is_no_input_of_a_fit_without_the_distortion_term(
    levels: tuple[list[list[Any]], list[bw.Diagnosis]],
) -> None:
    """diagnose carries the inputs' waveforms through G and diagnose_across does not: the key of a fit leaves
    the waveform out unless the distortion term is in the model, which holds only because the fit does not
    read it then (checked here bit for bit), and keeps it when the term is there."""
    from bouc_wen_id.diagnosis import across, fit_share

    groups, _ = levels
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        g = across._group(groups[0], "0", 0.0, CANDS, None)
    wavy = [replace(e, waveform=np.array([0.05, -0.02, 0.01, 0.003])) for e in g.sx]
    a = fitting.fit_with(g.sx, g.plain, "viscous", g.substeps)
    b = fitting.fit_with(wavy, g.plain, "viscous", g.substeps)
    assert a is not None and b is not None
    assert a.cost == b.cost and np.array_equal(a.params.values, b.params.values)
    assert all(np.array_equal(x, y) for x, y in zip(a.outputs, b.outputs))
    key, n = fit_share._key, g.substeps
    assert key(g.sx, g.plain, "viscous", n, ()) == key(wavy, g.plain, "viscous", n, ())
    assert key(g.sx, g.plain, Distortion.kind, n, ()) != key(wavy, g.plain, Distortion.kind, n, ())
    assert key(g.sx, g.plain, "viscous", n, ()) != key(g.sx, g.plain, "offset", n, ())
