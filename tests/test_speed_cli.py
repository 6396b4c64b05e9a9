"""The command line's batch options (issue #8): ``--no-figures`` and ``--scheduler ADDRESS``."""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import bouc_wen_id as bw
import pytest
from bouc_wen_id import cli


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("recs")
    plan = bw.demo_plan(samples_per_period=128, periods=6, settle_periods=10, seed=5)
    bw.save(path / "recs.npz", bw.simulate(bw.demo_plant(), plan)[:3])
    return path


def test_no_figures_writes_the_numbers_only(
    folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rep"
    assert cli.main(["identify", str(folder), "--out", str(out), "--no-figures"]) == 0
    printed = capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == ["result.json"]
    assert "beta" in printed and "png" not in printed
    assert json.loads((out / "result.json").read_text())["method"] == "refined"


def test_figures_come_after_the_numbers(
    folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rep"
    assert cli.main(["identify", str(folder), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert {p.name for p in out.iterdir()} == {"result.json", "loops.png", "bode.png", "residuals.png"}
    assert printed.index("result.json") < printed.index("loops.png")


def test_scheduler_runs_on_dask_with_the_local_results(folder: Path, tmp_path: Path) -> None:
    import distributed  # the test extra installs it

    assert cli.main(["identify", str(folder), "--out", str(tmp_path / "local"), "--no-figures"]) == 0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # distributed's start-up notices
        with distributed.LocalCluster(  # type: ignore[no-untyped-call]
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster:
            argv = ["identify", str(folder), "--out", str(tmp_path / "dask"), "--no-figures", "--separately"]
            assert cli.main([*argv, "--scheduler", cluster.scheduler_address]) == 0
            assert (
                cli.main(
                    [
                        "identify",
                        str(folder),
                        "--out",
                        str(tmp_path / "joint"),
                        "--no-figures",
                        "--scheduler",
                        cluster.scheduler_address,
                    ]
                )
                == 0
            )
    local = (tmp_path / "local" / "result.json").read_text()
    assert (tmp_path / "joint" / "result.json").read_text() == local
    assert len(list((tmp_path / "dask").glob("experiment_*/result.json"))) == 3


def test_scheduler_without_dask_is_a_clear_error(
    folder: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setitem(sys.modules, "distributed", None)  # as if the extra were not installed
    argv = ["identify", str(folder), "--out", str(tmp_path / "x"), "--scheduler", "tcp://127.0.0.1:1"]
    assert cli.main(argv) == 2
    assert "pip install" in capsys.readouterr().err
