"""Review 32's usability findings: a term instance's ``.at``, swapped input and output channels, a dead output
channel, and the joint verdict's "explained in part" clause."""

from __future__ import annotations

import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import bouc_wen_id as bw
import bouc_wen_id.io
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import across_verdict
from bouc_wen_id.errors import FileFormatError, InvalidParameterError, ZeroAmplitudeError

TWO_PI = 2.0 * math.pi


def _recs(seed: int = 3) -> list[bw.Recording]:
    om = TWO_PI * np.array([0.5, 1.5, 4.0])
    lin = bw.TransferFunction([1.0], [0.05, 1.0])
    plan = bw.SinePlan(
        om,
        1.0 / lin.gain_phase(om)[0],
        settle_periods=4,
        periods=8,
        samples_per_period=64,
        noise_sd=0.01,
        seed=seed,
    )
    return bw.simulate(bw.WienerPlant(lin, bw.BoucWen(0.7, 0.3, 1.8)), plan)


def test_an_instance_at_a_place_keeps_its_value() -> None:
    # Before: at was a classmethod, and Viscous(0.03).at(Place.X) returned the class, the 0.03 dropped.
    v = T.Viscous(0.03).at(T.Place.X)
    assert isinstance(v, T.Viscous.at(T.Place.X)) and v.value == 0.03 and v.place == T.Place.X
    back = v.at(T.Viscous.acts_on)
    assert type(back) is T.Viscous and back.value == 0.03
    on_x: Any = T.Viscous.at(T.Place.X)  # on the class: the class, as before
    assert on_x(0.02).value == 0.02
    with pytest.raises(InvalidParameterError, match="cannot act on the measured output"):
        T.Viscous(0.03).at(T.Place.OUTPUT)


def test_swapped_channels_are_named_and_the_phase_sign_is_printed_once() -> None:
    rs = _recs()
    swapped = [
        bw.Recording(
            r.t, r.y, r.u, amplitude=r.amplitude, frequency=r.frequency, settle_periods=r.settle_periods
        )
        for r in rs
    ]
    with pytest.raises(InvalidParameterError) as err:
        bw.diagnose(swapped)
    text = str(err.value)
    assert "- -" not in text and "+ -" not in text
    assert "check the channels" in text and "swapped" in text and "shift the time column" not in text, text


@pytest.mark.parametrize("shift", [0.05, -0.05])
def test_a_shifted_time_column_gets_the_phase_with_one_sign_and_no_swap_hint(shift: float) -> None:
    r = _recs()[0]
    period = TWO_PI / r.frequency
    moved = bw.Recording(
        r.t + shift * period / TWO_PI, r.u, r.y, amplitude=r.amplitude, frequency=r.frequency
    )
    with pytest.raises(InvalidParameterError) as err:
        bw.diagnose([moved, *_recs()[1:]])
    text = str(err.value)
    # u = U cos(omega t) read on t' = t + shift / omega is U cos(omega t' - shift): "- 0.05" for a positive
    # shift, "+ 0.05" for a negative one (before: "- -0.05").
    assert f"omega t {'-' if shift > 0 else '+'} 0.05)" in text, text
    assert "- -" not in text and "+ -" not in text
    assert "shift the time column" in text and "swapped" not in text


def test_a_dead_output_channel_is_a_zero_amplitude_error() -> None:
    # The README: ZeroAmplitudeError for a constant signal; before, "no noise floor" (InsufficientDataError).
    rs = _recs()
    dead = [bw.Recording(rs[0].t, rs[0].u, 0.0 * rs[0].y, amplitude=1.0, frequency=rs[0].frequency), *rs[1:]]
    with pytest.raises(ZeroAmplitudeError, match="dead or wrong channel"):
        bw.diagnose(dead)


def test_explained_in_part_across_says_what_the_share_is_and_what_remains(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Before: "explained in part (100 % of the summed excess)", with a condition still failing its test.
    fits = ((0.0, 0.4, 90.0), (1.0, 1e-6, 130.0), (2.0, 0.3, 101.0))  # condition, p, cost (dof 100)
    groups = [
        SimpleNamespace(label=str(c), sx=None, current=SimpleNamespace(p=p, cost=k)) for c, p, k in fits
    ]
    monkeypatch.setattr(across_verdict, "p_of", lambda g, fit: fit.p)
    monkeypatch.setattr(across_verdict, "dof_of", lambda sx, fit: 100)
    monkeypatch.setattr(across_verdict, "explained_fraction", lambda gs: 1.0)
    text = across_verdict.partly_text(groups, 0.05)
    assert "100 % of the plain models' excess over the noise floor, summed over the conditions" in text
    assert "fails the adequacy test at condition 1.0 (p = 1e-06)" in text
    assert "below their noise floor at condition 0.0, the fits there offset what remains" in text
    assert "condition 2.0" not in text
    g: Any = groups[1]
    g.current.p = 0.2
    assert "fails" not in across_verdict.partly_text(groups, 0.05)


def test_a_unit_written_as_the_names_last_part_is_read(tmp_path: Path) -> None:
    # Before: "force_N", "disp_mm" mapped with columns= carried no unit (the reports said [y], [u]).
    k = np.arange(64)
    rows = "".join(f"{i * 0.002!r},{math.cos(i / 5)!r},{math.sin(i / 5)!r}\n" for i in k.tolist())
    path = tmp_path / "lab.csv"
    path.write_text("time_s,disp_mm,force_kN\n" + rows, encoding="utf-8")
    (m,) = bw.io.load(path, columns={"t": "time_s", "u": "disp_mm", "y": "force_kN"})
    assert isinstance(m, bw.Measurement)
    assert dict(m.units) == {"t": "s", "u": "mm", "y": "kN"}
    # It labels a chosen column only: the roles are not read from such names (as before).
    with pytest.raises(FileFormatError, match="which column is the input u"):
        bw.io.load(path)
    # A last part that is no unit symbol stays part of the name: no unit.
    path.write_text("time_s,disp_raw,force_2\n" + rows, encoding="utf-8")
    (m,) = bw.io.load(path, columns={"t": "time_s", "u": "disp_raw", "y": "force_2"})
    assert isinstance(m, bw.Measurement)
    assert "u" not in m.units and "y" not in m.units
    # A time column in ms is read as ms, as "Time (ms)" is: converted to seconds, with a UnitWarning (it was
    # refused before session 34; bouc_wen_id.timeunits).
    ms = "".join(f"{2 * i},{math.cos(i / 5)!r},{math.sin(i / 5)!r}\n" for i in k.tolist())
    path.write_text("time_ms,disp_mm,force_N\n" + ms, encoding="utf-8")
    with pytest.warns(bw.errors.UnitWarning, match="time column in ms as seconds"):
        (m,) = bw.io.load(path, columns={"t": "time_ms", "u": "disp_mm", "y": "force_N"})
    assert isinstance(m, bw.Measurement) and np.allclose(m.t, 0.002 * k) and m.units["t"] == "s"
