"""A diagnosis saved and read back (diagnosis/saved.py; review 35: no load, readers that refused the file
without naming one, no ``--json`` on the CLI's diagnose).

Round trip on a diagnosis that names a term (viscous damping on u, resonant G, its own noise) and carries a
reading: headline, status and printed status, readings, named terms with value and standard error, the
models' statistics; the file the CLI writes with ``--json`` (and to stdout with ``--json -``) reads back the
same; ``load``, ``load_model`` and ``export`` name the reader.
"""

from __future__ import annotations

import json
import math
import warnings
from dataclasses import replace
from pathlib import Path

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import cli
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis import readings
from bouc_wen_id.errors import FileFormatError


def _recs() -> list[bw.Recording]:
    lin = bw.TransferFunction([6.0], [1.0, 1.5, 6.0])
    om = np.array([0.8, 1.6, 3.2])
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        np.repeat(om, 2), np.tile([0.7, 1.8], 3) / np.repeat(g, 2), settle_periods=10, periods=10,
        samples_per_period=64, substeps=8, noise_sd=0.005, seed=35,
    )  # fmt: skip
    return bw.simulate(bw.WienerPlant(lin, bw.BoucWen(0.6, 0.4, 1.5), terms=(T.Viscous(0.02),)), plan)


@pytest.fixture(scope="module")
def named() -> bw.Diagnosis:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(_recs(), candidates=[T.Viscous.kind, T.Stiffness.kind])


def _same(a: object, b: object) -> bool:
    return a == b or (isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b))


def _check(d: bw.Diagnosis, s: bw.SavedDiagnosis) -> None:
    assert s.status == d.status and s.status_text == d.status_text
    assert s.verdict == d.verdict and s.headline == d.headline and s.details == d.details
    assert s.readings == d.readings and s.named_terms == d.named_terms
    for a, b in zip((*d.named, *d.partial), (*s.named, *s.partial), strict=True):
        assert (a.term, a.symbol, a.unit, a.label) == (b.term, b.symbol, b.unit, b.label)
        assert a.value == b.value and _same(a.standard_error, b.standard_error)
        assert str(a) == str(b)
    for m, n in ((d.plain, s.plain), (d.final, s.final)):
        assert (m.cost, m.dof, m.p_value, m.mu) == (n.cost, n.dof, n.p_value, n.mu)
    assert s.explained_fraction == d.explained_fraction
    assert s.to_dict() == json.loads(d.to_json())
    assert s["steps"] == json.loads(d.to_json())["steps"]


def test_a_diagnosis_round_trips_through_its_json(named: bw.Diagnosis, tmp_path: Path) -> None:
    assert named.named_terms == (T.Viscous.kind,), named.verdict  # a named term, with its se
    assert math.isfinite(named.named[0].standard_error)
    path = tmp_path / "d.json"
    path.write_text(named.to_json(), encoding="utf-8")
    s = bw.load_diagnosis(path)
    _check(named, s)
    _check(named, bw.SavedDiagnosis.from_json(s.to_json()))  # and again from its own JSON
    assert s.summary().startswith(f"Diagnosis: {named.headline}")
    # with readings (a rival and a limit of the evidence): the printed status follows them, and so do they
    rs = (
        readings.Reading("rate", "or a rate-independent loop"),
        readings.Reading("law_untested", "x", False),
    )
    q = replace(named, readings=rs)
    assert q.status_text == f"explained ({readings.NOT_ONLY})"
    _check(q, bw.SavedDiagnosis.from_json(q.to_json()))


def test_the_other_readers_name_load_diagnosis(named: bw.Diagnosis, tmp_path: Path) -> None:
    path = tmp_path / "diagnosis.json"
    path.write_text(named.to_json(), encoding="utf-8")
    with pytest.raises(FileFormatError, match="load_diagnosis"):
        bw.load(path)
    with pytest.raises(FileFormatError, match="load_diagnosis"):
        bw.load(tmp_path)  # the report folder
    with pytest.raises(FileFormatError, match="load_diagnosis"):
        bw.export.load_model(path)
    assert cli.main(["export", str(path), "--to", "json"]) == 2
    model = tmp_path / "m.json"
    bw.export.save_model(bw.demo_plant(), model)
    with pytest.raises(FileFormatError, match="a model document: read it with bouc_wen_id.export.load_model"):
        bw.load_diagnosis(model)
    with pytest.raises(FileFormatError, match="not a diagnosis JSON"):
        bw.SavedDiagnosis.from_json('{"status": "adequate"}')


def test_the_cli_writes_the_json_to_a_file_or_stdout(
    named: bw.Diagnosis, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    data = tmp_path / "data"
    bw.save_recordings(data, _recs())
    argv = ["diagnose", str(data), "--candidates", f"{T.Viscous.kind},{T.Stiffness.kind}"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert cli.main([*argv, "--json", "d.json"]) == 0
        out = capsys.readouterr().out
        assert out.startswith("Diagnosis: ") and not (tmp_path / "bouc_wen_id_diagnosis").exists()
        s = bw.load_diagnosis(tmp_path / "d.json")
        assert s.named_terms == named.named_terms and s.status == named.status
        assert abs(s.named[0].value - named.named[0].value) <= 1e-6 * abs(named.named[0].value)
        assert cli.main([*argv, "--json", "d.json"]) == 2  # exists: refused before any work
        assert cli.main([*argv, "--json", "-"]) == 0
        got = capsys.readouterr()
        assert json.loads(got.out)["headline"] == s.headline and "Diagnosis: " in got.err
        assert cli.main([*argv, "--json", str(data / "x.json")]) == 2  # inside the inputs: refused
        assert cli.main([*argv, "--json", "e.json", "--out", "rep", "--no-figures"]) == 0
    assert bw.load_diagnosis(tmp_path / "rep").headline == bw.load_diagnosis(tmp_path / "e.json").headline


@pytest.mark.parametrize("bad", [3, None, 2.5, ["d.json"]])
def test_a_non_path_is_refused_by_name(bad: object) -> None:
    with pytest.raises(TypeError, match=r"load_diagnosis takes the path .* not " + type(bad).__name__):
        bw.load_diagnosis(bad)  # type: ignore[arg-type]
