"""Time columns that are not in seconds (bouc_wen_id/timeunits.py).

A declared unit (``t [ms]``, ``Time (us)``, ``time_ms``) is converted with a UnitWarning and a note; an
undeclared time column 1000x off what a stated sample rate, a Recording's omega or a Measurement's nominal
frequency needs is a TimeUnitError ("the time looks like ms"): before, the first was refused or not found,
the second a generic mismatch, the third a silent fit at frequencies 1000x too low.
"""

from __future__ import annotations

import math
import warnings
from pathlib import Path

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.cli import main
from bouc_wen_id.errors import FrequencyMismatchError, TimeUnitError, UnitMismatchError, UnitWarning

TWO_PI = 2.0 * math.pi


def _recordings(seed: int = 5) -> list[bw.Recording]:
    """Sine experiments of a first-order plant with a delay (not the resonant one of test_units.py)."""
    plant = bw.WienerPlant(bw.TransferFunction([12.0], [1.0, 12.0], 0.01), bw.BoucWen(0.5, 0.5, 2.2))
    plan = bw.SinePlan(
        [3.0, 7.0, 15.0], 0.8, settle_periods=3, periods=6, samples_per_period=80, noise_sd=0.004, seed=seed
    )
    return bw.simulate(plant, plan)


def _write(path: Path, t: np.ndarray, u: np.ndarray, y: np.ndarray, names: str, head: str = "") -> None:
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(head)
        np.savetxt(fh, np.column_stack([t, u, y]), delimiter=",", header=names, comments="", fmt="%.17g")


@pytest.mark.parametrize(
    ("name", "factor"), [("t [ms]", 1e3), ("Time (us)", 1e6), ("time_ms", 1e3), ("t_us", 1e6)]
)
def test_a_declared_time_unit_is_converted_to_seconds(tmp_path: Path, name: str, factor: float) -> None:
    r = _recordings()[0]
    path = tmp_path / "lab.csv"
    _write(path, r.t * factor, r.u, r.y, f"{name},Displacement (mm),Force (N)")
    with pytest.warns(UnitWarning, match="as seconds"):
        (m,) = bw.load(path)
    assert isinstance(m, bw.Measurement)
    np.testing.assert_allclose(m.t, r.t, rtol=1e-12, atol=1e-15)
    assert m.units["t"] == "s" and m.metadata["units_converted"].startswith("t: ")


def test_the_conversion_is_in_the_notes_of_a_fit(tmp_path: Path) -> None:
    recs = _recordings(6)
    paths = []
    for i, r in enumerate(recs):
        paths.append(tmp_path / f"e{i}.csv")
        _write(paths[-1], r.t * 1e3, r.u, r.y, "t [ms],u,y", head=f"# nominal_frequency: {r.frequency!r}\n")
    with pytest.warns(UnitWarning):
        ms = bw.load(paths)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = bw.identify(ms)
        ref = bw.identify(recs)
    assert any("read the time column of e0 in ms as seconds" in n for n in res.warnings)
    np.testing.assert_allclose(res.frequencies, ref.frequencies, rtol=1e-3)


def test_a_time_column_in_a_unit_that_is_not_a_time_is_refused(tmp_path: Path) -> None:
    r = _recordings()[0]
    path = tmp_path / "odd.csv"
    _write(path, r.t, r.u, r.y, "Time (mm),u,y")
    with pytest.raises(UnitMismatchError, match="not a unit of time"):
        bw.load(path)


def test_an_undeclared_ms_column_beside_a_sample_rate_is_named(tmp_path: Path) -> None:
    """A hand-made sine (not the simulator) at 2 kHz, its t column written in ms."""
    rate = 2000.0
    t = np.arange(4000) / rate
    path = tmp_path / "daq.csv"
    _write(path, t * 1e3, np.cos(TWO_PI * 5 * t), np.sin(TWO_PI * 5 * t), "t,u,y", f"# sample_rate: {rate}\n")
    with pytest.raises(TimeUnitError, match="looks like ms") as err:
        bw.load(path)
    assert "daq.csv" in str(err.value)
    # Not every disagreement is a time unit: 3 % off stays the plain mismatch.
    _write(path, t * 1.5, np.cos(TWO_PI * 5 * t), np.sin(TWO_PI * 5 * t), "t,u,y", f"# sample_rate: {rate}\n")
    with pytest.raises(bw.FileFormatError) as plain:
        bw.load(path)
    assert not isinstance(plain.value, TimeUnitError) and "not at the stated sample rate" in str(plain.value)


def test_a_recording_in_ms_is_named_not_a_generic_mismatch() -> None:
    r = _recordings()[1]
    bad = bw.Recording(r.t * 1e3, r.u, r.y, r.amplitude, r.frequency, r.settle_periods)
    with pytest.raises(TimeUnitError, match="looks like ms") as err:
        bw.identify([bad])
    assert isinstance(err.value, FrequencyMismatchError)  # what callers caught before still catches it
    with pytest.raises(TimeUnitError, match="looks like ms"):
        bw.diagnose([bad])
    hz = bw.Recording(r.t, r.u, r.y, r.amplitude, r.frequency / TWO_PI, r.settle_periods)
    with pytest.raises(FrequencyMismatchError) as other:  # omega in Hz: not a time unit
        bw.identify([hz])
    assert not isinstance(other.value, TimeUnitError)


@pytest.mark.parametrize("factor", [1e3, 1e6])
def test_a_measurement_in_ms_with_a_nominal_frequency_is_not_fitted(factor: float) -> None:
    recs = _recordings(7)
    ms = [
        bw.Measurement(r.t * factor, r.u, r.y, nominal_frequency=r.frequency, name=f"m{i}")
        for i, r in enumerate(recs)
    ]
    unit = "ms" if factor == 1e3 else "us"
    with pytest.raises(TimeUnitError, match=f"looks like {unit}"):
        bw.identify(ms)
    with pytest.raises(TimeUnitError, match="m0"):
        bw.diagnose(ms)


def test_cli_identify_names_a_time_column_in_ms(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    r = _recordings(8)[2]
    path = tmp_path / "lab_ms.csv"
    _write(path, r.t * 1e3, r.u, r.y, "Time,u,y", head=f"# nominal_frequency: {r.frequency!r}\n")
    assert main(["identify", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "TimeUnitError" in err and "looks like ms" in err
    declared = tmp_path / "lab_declared.csv"
    _write(declared, r.t * 1e3, r.u, r.y, "Time (ms),u,y", head=f"# nominal_frequency: {r.frequency!r}\n")
    with warnings.catch_warnings():
        warnings.simplefilter("always")
        code = main(["identify", str(declared), "--out", str(tmp_path / "out2")])
    assert code == 0, capsys.readouterr().err
    assert "read the time column in ms as seconds" in capsys.readouterr().err


def test_a_frame_s_time_column_declared_in_ms_is_converted() -> None:
    pd = pytest.importorskip("pandas")
    r = _recordings(9)[0]
    frame = pd.DataFrame({"time_ms": r.t * 1e3, "disp": r.u, "force": r.y})
    with pytest.warns(UnitWarning, match="'time_ms' in ms as seconds"):
        m = bw.Measurement.from_dataframe(frame, input="disp", output="force", time="time_ms")
    np.testing.assert_allclose(m.t, r.t, rtol=1e-12, atol=1e-15)
    indexed = frame.set_index("time_ms").rename_axis("t [ms]")
    with pytest.warns(UnitWarning):
        m2 = bw.Measurement.from_dataframe(indexed, input="disp", output="force")
    np.testing.assert_allclose(m2.t, r.t, rtol=1e-12, atol=1e-15)
