"""Messages about one experiment of a folder name its file (review 34: "item 3", "recording 4" left the
user to count files), and naming a loaded recording changes nothing else of it."""

from __future__ import annotations

from pathlib import Path

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.io import write_csv


def _folder(tmp_path: Path, recs: list[bw.Recording]) -> Path:
    for k, r in enumerate(recs):
        write_csv(tmp_path / f"exp{k}.csv", r)
    return tmp_path


def _recordings(periods: int) -> list[bw.Recording]:
    plan = bw.SinePlan([2.0, 3.0, 5.0], [0.5, 0.5, 0.5], settle_periods=1, periods=periods, seed=3)
    return bw.simulate(bw.demo_plant(), plan)


def test_load_names_each_recording_after_its_file_and_keeps_everything_else(tmp_path: Path) -> None:
    recs = _recordings(periods=4)
    items = bw.load(_folder(tmp_path, recs))
    assert [it.metadata["name"] for it in items] == ["exp0.csv", "exp1.csv", "exp2.csv"]
    for a, b in zip(recs, items):
        assert isinstance(b, bw.Recording)
        assert np.array_equal(a.y, b.y) and np.array_equal(a.u, b.u) and a.frequency == b.frequency
        assert {k: v for k, v in b.metadata.items() if k != "name"} == dict(a.metadata)


def test_a_header_name_is_kept(tmp_path: Path) -> None:
    rec = _recordings(periods=4)[0]
    named = bw.Recording(
        rec.t, rec.u, rec.y, rec.amplitude, rec.frequency, rec.settle_periods, metadata={"name": "run 7"}
    )
    write_csv(tmp_path / "a.csv", named)
    assert bw.load(tmp_path / "a.csv")[0].metadata["name"] == "run 7"


def test_a_wrong_frequency_names_the_file(tmp_path: Path) -> None:
    recs = _recordings(periods=4)
    r = recs[1]
    recs[1] = bw.Recording(r.t, r.u, r.y, r.amplitude, 1.3 * r.frequency, r.settle_periods)
    with pytest.raises(bw.errors.BoucWenIdError, match=r"exp1\.csv"):
        bw.diagnose(bw.load(_folder(tmp_path, recs)))


def test_too_few_periods_names_the_file(tmp_path: Path) -> None:
    recs = _recordings(periods=4)
    recs[2] = _recordings(periods=1)[2]
    with pytest.raises(bw.errors.InsufficientDataError, match=r"exp2\.csv"):
        bw.diagnose(bw.load(_folder(tmp_path, recs)))
