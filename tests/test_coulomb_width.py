"""The dry friction's smoothing width: a setting of the core (parity with the NumPy reference), carried by
the fits, and profiled by the diagnosis (diagnosis/coulomb_width.py) - checked on recordings of a simulator
written here (not the bench's generator), at widths other than the default 1 %: review 40's bolted joint
was "unexplained" at 0.1-0.5 % and 4 %."""

from __future__ import annotations

import math
import warnings
from typing import Any, cast

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import _core
from bouc_wen_id.augmented import AugParams
from bouc_wen_id.diagnosis import coulomb_width
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.reference import augmented as ref


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_core_and_the_reference_agree_at_any_width(seed: int) -> None:
    """Same formulas in both (tanh of the velocity over eps times its peak): agreement to rounding, 1e-12
    of the output's scale (measured 2e-16)."""
    rng = np.random.default_rng([seed, 41])
    eps = float(np.exp(rng.uniform(math.log(0.001), math.log(0.5))))
    terms = ["coulomb@x", "coulomb", "viscous@x"]
    sh = np.r_[0.6, 0.2, 1.4, rng.uniform(0.01, 0.1, 3)]
    args = (64, 1.3, 2.0, rng.uniform(0, 6), terms, sh, 0.8, rng.uniform(0, 6), 8)
    a = _core.augmented_output(*args, coulomb_smoothing=eps)
    b = ref.augmented_output(*args, coulomb_smoothing=eps)
    d = ref.augmented_output(*args)
    for x, y in zip(a, b):
        assert np.max(np.abs(np.asarray(x) - np.asarray(y))) < 1e-12
    if abs(eps - 0.01) > 1e-3:  # the width is used: the default's output differs
        assert np.max(np.abs(np.asarray(a[0]) - np.asarray(d[0]))) > 1e-6


def test_a_width_outside_its_range_is_refused_by_name() -> None:
    for eps in (0.0, -0.01, 0.6, math.nan):
        with pytest.raises(bw.BoucWenIdError, match="smoothing"):
            AugParams(0.5, 0.1, 1.5, (), np.zeros(0), np.ones(1), np.zeros(1), eps)
        with pytest.raises(bw.BoucWenIdError, match="smoothing"):
            _core.augmented_output(8, 1.0, 1.0, 0.0, ["coulomb"], np.r_[0.5, 0.1, 1.5, 0.1], 1.0, 0.0, 2,
                                   coulomb_smoothing=eps)  # fmt: skip
    assert issubclass(InvalidParameterError, bw.BoucWenIdError)


def test_the_profile_finds_the_width_of_the_smallest_cost() -> None:
    """coulomb_width.profile on a cost whose minimum is at eps = 0.3 % (between the grid's 0.25 % and 1 %):
    the grid then the golden steps land within 25 % of it, and never keep a worse fit than the one given."""

    class _Fit:
        def __init__(self, eps: float) -> None:
            self.params = AugParams(0.5, 0.1, 1.5, ("coulomb",), np.r_[0.1], np.ones(1), np.zeros(1), eps)
            self.cost = (math.log(eps) - math.log(0.003)) ** 2

    seen: list[float] = []

    def refit(start: AugParams) -> Any:
        seen.append(start.smoothing)
        return _Fit(start.smoothing)

    best = coulomb_width.profile(cast(Any, _Fit(0.01)), refit)
    assert abs(math.log(best.params.smoothing / 0.003)) < math.log(1.25), best.params.smoothing
    assert len(seen) <= len(coulomb_width.WIDTHS) + coulomb_width.REFINE_STEPS + 2
    start = _Fit(0.003)
    assert coulomb_width.profile(cast(Any, start), refit) is cast(Any, start)  # nothing better: itself


def test_a_cost_still_falling_at_the_widest_width_keeps_the_fit_given() -> None:
    """Session 42: a cost that falls all the way to the widest width (no turn found) keeps the fit given,
    not the search's edge; a minimum inside the range near it (10 %) is still found within 25 %."""

    class _Fit:
        def __init__(self, eps: float, low: float) -> None:
            self.params = AugParams(0.5, 0.1, 1.5, ("coulomb@x",), np.r_[0.1], np.ones(1), np.zeros(1), eps)
            self.cost = (math.log(eps) - math.log(low)) ** 2

    for low, kept in ((1.0, False), (0.1, True)):
        start = _Fit(0.01, low)

        def refit(st: AugParams, low: float = low) -> Any:
            return _Fit(st.smoothing, low)

        best = coulomb_width.profile(cast(Any, start), refit)
        if kept:
            assert abs(math.log(best.params.smoothing / low)) < math.log(1.25), best.params.smoothing
        else:
            assert best is cast(Any, start)


_WN, _ZETA, _DELAY, _TAU = 2 * math.pi * 6.0, 0.3, 0.004, 0.02


def _rhs(g: str, amp: float, om: float, t: float, s: tuple[float, ...]) -> tuple[float, ...]:
    """``(xdot, vdot, wdot)`` of G (``"resonant"``: 6 Hz, zeta 0.3, 4 ms delay; ``"first"``: tau 0.02 s)
    driven by ``amp cos(om t)`` and a Bouc-Wen element (alpha 1, beta 0.5, gamma 0.3, mu 1.5) on x."""
    x, v, w = s
    if g == "resonant":
        xd, vd = v, _WN * _WN * (amp * math.cos(om * (t - _DELAY)) - x) - 2 * _ZETA * _WN * v
    else:
        xd, vd = (amp * math.cos(om * t) - x) / _TAU, 0.0
    aw = abs(w)
    return xd, vd, xd - 0.5 * abs(xd) * aw**0.5 * w - 0.3 * xd * aw**1.5


def _one(g: str, amp: float, om: float, periods: int) -> tuple[Any, Any, Any]:
    """``(t, xdot, w)`` sampled at 128 per period, RK4 at 4 substeps per sample, from rest."""
    p, sub = 128, 4
    h = 2 * math.pi / om / p / sub
    s: tuple[float, ...] = (0.0, 0.0, 0.0)
    t, xds, ws = 0.0, [], []
    for k in range(periods * p * sub):
        k1 = _rhs(g, amp, om, t, s)
        if k % sub == 0:
            xds.append(k1[0])
            ws.append(s[2])
        k2 = _rhs(g, amp, om, t + h / 2, tuple(a + h / 2 * b for a, b in zip(s, k1)))
        k3 = _rhs(g, amp, om, t + h / 2, tuple(a + h / 2 * b for a, b in zip(s, k2)))
        k4 = _rhs(g, amp, om, t + h, tuple(a + h * b for a, b in zip(s, k3)))
        s = tuple(a + h / 6 * (b1 + 2 * b2 + 2 * b3 + b4) for a, b1, b2, b3, b4 in zip(s, k1, k2, k3, k4))
        t += h
    return np.arange(len(ws)) * h * sub, np.asarray(xds), np.asarray(ws)


def _records(g: str, place: str, f: float, eps: float, seed: int, c: float = 0.0) -> list[Any]:
    """Four sine experiments (1 and 3 Hz x U 0.6 and 2) of :func:`_rhs`'s plant with dry friction
    ``f tanh(v / (eps Vmax))`` on ``place`` (``"x"`` or ``"u"``) and a damper ``c`` on x; 1 % white output
    noise; 4 settling periods then 14."""
    rng = np.random.default_rng([seed, 4141])
    out = []
    settle, p = 4, 128
    for hz in (1.0, 3.0):
        for amp in (0.6, 2.0):
            om = 2 * math.pi * hz
            tt, xd, w = _one(g, amp, om, 18)
            if place == "x":
                vel, vmax = xd, float(np.max(np.abs(xd[settle * p :])))
            else:
                vel, vmax = -amp * om * np.sin(om * tt), amp * om
            y = w + f * np.tanh(vel / (eps * vmax)) + c * xd
            y = y + rng.normal(0.0, 0.01 * float(np.std(y[settle * p :])), y.size)
            out.append(
                bw.Recording(tt, amp * np.cos(om * tt), y, amplitude=amp, frequency=om, settle_periods=settle)
            )
    return out


@pytest.mark.parametrize(
    ("g", "place", "eps", "c"),
    [("resonant", "x", 0.003, 0.0), ("first", "u", 0.04, 0.0), ("first", "x", 0.002, 0.002)],
)
def test_dry_friction_at_another_width_is_named_at_its_place(
    g: str, place: str, eps: float, c: float
) -> None:
    """Dry friction f = 0.02 at 0.3 % (resonant G + delay, on x), 4 % (first-order G, on u) and 0.2 % beside a
    damper on x (review 40's joint): "explained" (the final model passes its test), named at its place with f
    within 3 standard errors of 0.02, and the fitted width said. With the width fixed at 1 % (session 40's
    code) the 4 % case was "explained in part" with f = 0.01933 +- 0.00015 (4.5 standard errors low)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(_records(g, place, 0.02, eps, 7, c))
    term = "coulomb@x" if place == "x" else "coulomb"
    named = {t.term: t for t in d.named}
    assert d.status == "explained", d.verdict
    assert term in named, d.verdict
    t = named[term]
    assert abs(t.value - 0.02) < 3 * t.standard_error, (t.value, t.standard_error)
    assert "the dry friction's turn: smoothing eps = " in d.verdict
    assert "coulomb_smoothing" in d.settings


@pytest.mark.parametrize(("eps", "named"), [(0.1, True), (0.25, False)])
def test_a_wide_turn_is_fitted_inside_the_search_and_no_stand_in_beyond_it(eps: float, named: bool) -> None:
    """Resonant G with its delay, dry friction f = 0.02 on x: at 10 % (inside the search) named, its width
    said between 5 and 16 %; at 25 % (the cost still falling at the search's 16 % edge) the width is not
    freed and nothing false is named beside it. Measured before session 42's rule: 25 % was "explained in
    part" by coulomb@x (f = 0.013), coulomb on u, stiffness on x and sensor lag (three terms the plant lacks);
    now "unexplained"; 10 %: explained, f = 0.0191 +- 0.00024, eps 9.4 %."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = bw.diagnose(_records("resonant", "x", 0.02, eps, 7))
    assert set(d.named_terms) <= {"coulomb@x"}, d.verdict
    if named:
        assert "coulomb@x" in d.named_terms, d.verdict
        assert 0.05 < d.settings["coulomb_smoothing"] < coulomb_width.WIDTHS[-1], d.settings
