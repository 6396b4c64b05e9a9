"""A fitted model meets new recordings in the units it was fitted in (bouc_wen_id/units.py ``against_model``).

Before, ``validate`` took the records' arrays as they were: a model fitted in mm/N simulated on a record
in m/kN gave a confident NRMSE of a simulation 1000x off.  Now the model carries its units
(``WienerPlant.units``, ``IdentificationResult.units``, the model document's ``units``), records in other
units of the same quantities are converted (UnitWarning, notes) and unrelated units are refused
(UnitMismatchError).
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.cli import main
from bouc_wen_id.errors import UnitMismatchError, UnitWarning

#: A first-order G with a delay and a stiffness term (not the resonant plant of test_units.py).
_PLANT = bw.WienerPlant(
    bw.TransferFunction([25.0], [1.0, 25.0], 0.004),
    bw.BoucWen(0.6, 0.4, 1.5),
    (bw.terms.Stiffness(0.2),),
    units={"u": "mm", "y": "N"},
)


def _record(seed: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A swept, noisy record in mm and N (a chirp, not a sine plan)."""
    rng = np.random.default_rng(seed)
    t = np.arange(3000) / 500.0
    u = 1.2 * np.sin(2 * math.pi * (0.5 + 0.6 * t) * t) * np.minimum(t, 1.0)
    _, _, y = bw.simulate_input(_PLANT, t, u, output=True)
    return t, u, y + 0.01 * float(np.std(y)) * rng.standard_normal(t.size)


def test_a_record_in_other_units_is_converted_to_the_model_s() -> None:
    t, u, y = _record()
    ref = bw.validate(_PLANT, t, u, y, data_units={"u": "mm", "y": "N"})
    assert ref.nrmse < 0.05 and not ref.notes and ref.units == "N"
    with pytest.warns(UnitWarning) as caught:
        rep = bw.validate(_PLANT, t, u / 1000.0, y / 1000.0, data_units={"u": "m", "y": "kN"}, name="r.csv")
    said = [str(w.message) for w in caught]
    assert any("from m to the model's mm" in s for s in said) and any(
        "from kN to the model's N" in s for s in said
    )
    assert rep.nrmse == pytest.approx(ref.nrmse, rel=1e-9)
    assert rep.rmse == pytest.approx(ref.rmse, rel=1e-9) and rep.units == "N"
    assert any("r.csv" in n and "kN" in n for n in rep.notes)
    # The old reading (the arrays taken as they are) is what the conversion prevents: far off.
    assert bw.validate(
        bw.WienerPlant(_PLANT.linear, _PLANT.hysteresis, _PLANT.terms), t, u / 1e3, y / 1e3
    ).nrmse > (5 * ref.nrmse)


def test_a_measurement_brings_its_own_units_and_name() -> None:
    t, u, y = _record(4)
    m = bw.Measurement(t, u * 0.1, y, units={"u": "cm", "y": "N"}, name="rig_b")
    with pytest.warns(UnitWarning, match="rig_b"):
        rep = bw.validate(_PLANT, m)
    assert rep.nrmse == pytest.approx(bw.validate(_PLANT, t, u, y).nrmse, rel=1e-9)


@pytest.mark.parametrize(
    ("units", "words"), [({"u": "N"}, ("'N'", "'mm'")), ({"y": "volt"}, ("'volt'", "'N'"))]
)
def test_unrelated_units_are_refused_naming_the_record_and_both_units(
    units: dict[str, str], words: tuple[str, str]
) -> None:
    t, u, y = _record(5)
    with pytest.raises(UnitMismatchError, match="rec_7.csv") as err:
        bw.validate(_PLANT, t, u, y, data_units=units, name="rec_7.csv")
    assert all(w in str(err.value) for w in words)


def test_the_y_unit_given_as_units_is_checked_too() -> None:
    t, u, y = _record(6)
    with pytest.warns(UnitWarning):
        rep = bw.validate(_PLANT, t, u, y * 1000.0, units="mN")
    assert rep.nrmse == pytest.approx(bw.validate(_PLANT, t, u, y).nrmse, rel=1e-9)
    with pytest.raises(UnitMismatchError):
        bw.validate(_PLANT, t, u, y, units="mm")


def test_units_survive_save_and_load_and_an_old_file_still_loads(tmp_path: Path) -> None:
    path = tmp_path / "model.json"
    bw.save_model(_PLANT, path)
    back = bw.load_model(path)
    assert back.to_dict() == _PLANT.to_dict() and back.units == {"u": "mm", "y": "N"}
    assert bw.WienerPlant.from_dict(_PLANT.to_dict()).units == _PLANT.units
    # A document written before models carried units: it loads, without units, and validating notes it.
    doc = json.loads(path.read_text())
    del doc["units"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(doc))
    plain = bw.load_model(old)
    assert plain.to_dict() == {k: v for k, v in _PLANT.to_dict().items() if k != "units"}
    assert plain.units == {}
    t, u, y = _record(7)
    rep = bw.validate(plain, t, u, y, data_units={"u": "mm", "y": "N"})
    assert any("states no units" in n and "cannot be checked" in n for n in rep.notes)
    bad = tmp_path / "bad.json"
    doc["units"] = {"u": 3}
    bad.write_text(json.dumps(doc))
    with pytest.raises(bw.FileFormatError, match="units"):
        bw.load_model(bad)


def test_the_fits_record_the_units_of_their_records() -> None:
    plant = bw.WienerPlant(bw.TransferFunction([36.0], [1.0, 3.0, 36.0]), bw.BoucWen(0.7, 0.3, 1.8))
    plan = bw.SinePlan(
        [2.0, 5.0, 9.0], 1.0, settle_periods=3, periods=5, samples_per_period=64, noise_sd=0.005, seed=2
    )
    recs = bw.simulate(plant, plan)
    ms = [
        bw.Measurement(r.t, r.u, r.y, units={"u": "mm", "y": "kN"}, nominal_frequency=r.frequency)
        for r in recs
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = bw.identify(ms)
    assert res.units == {"u": "mm", "y": "kN"} and res.to_dict()["units"] == res.units
    tagged = [
        bw.Recording(
            r.t, r.u, r.y, r.amplitude, r.frequency, r.settle_periods, metadata={"units": '{"u": "mm"}'}
        )
        for r in recs
    ]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = bw.fit_time_domain(tagged, start=plant, multistart=False, max_iter=3)
    assert fit.plant.units == {"u": "mm"}
    assert bw.model_from_json(bw.model_to_json(fit)).units == {"u": "mm"}  # a fit saves with its units


def _write(path: Path, t: np.ndarray, u: np.ndarray, y: np.ndarray, names: str) -> None:
    np.savetxt(path, np.column_stack([t, u, y]), delimiter=",", header=names, comments="", fmt="%.17g")


def test_cli_validate_converts_refuses_and_notes(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    t, u, y = _record(8)
    model = tmp_path / "model.json"
    bw.save_model(_PLANT, model)
    same = tmp_path / "in_mm.csv"
    _write(same, t, u, y, "t,Displacement (mm),Force (N)")
    other = tmp_path / "in_m.csv"
    _write(other, t, u / 1000.0, y / 1000.0, "t,Displacement (m),Force (kN)")
    assert main(["validate", "--model", str(model), str(same)]) == 0
    first = capsys.readouterr().out
    with warnings.catch_warnings():
        warnings.simplefilter("always", UnitWarning)  # the command line prints it (not an error here)
        assert main(["validate", "--model", str(model), str(other)]) == 0
    second, warned = capsys.readouterr()
    assert "UnitWarning: converted the output y of in_m.csv from kN to the model's N" in warned
    nrmse = [line.split()[2] for line in (first.splitlines()[1], second.splitlines()[1])]
    assert nrmse[0] == nrmse[1]
    assert "note: converted the input u of in_m.csv from m to the model's mm" in second
    wrong = tmp_path / "wrong.csv"
    _write(wrong, t, u, y, "t,Displacement (mm),Force (mm)")
    assert main(["validate", "--model", str(model), str(wrong)]) == 2
    err = capsys.readouterr().err
    assert "UnitMismatchError" in err and "wrong.csv" in err and "'mm'" in err and "'N'" in err
    old = tmp_path / "old.json"
    doc = json.loads(model.read_text())
    del doc["units"]
    old.write_text(json.dumps(doc))
    assert main(["validate", "--model", str(old), str(same)]) == 0
    assert "note: the model states no units" in capsys.readouterr().out


def test_the_exported_c_names_the_units_and_cannot_be_broken_by_them() -> None:
    code = bw.to_c(_PLANT)
    assert "Units: u in mm, y in N" in code
    odd = _PLANT.with_units({"u": "mm */ int x; /*", "y": "N"})
    code = bw.to_c(odd)
    assert "Units: y in N" in code and "int x;" not in code
