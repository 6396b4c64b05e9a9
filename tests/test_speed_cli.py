"""The command line's batch options (issue #8): ``--no-figures`` and ``--scheduler ADDRESS``."""

from __future__ import annotations

import json
import os
import sys
import warnings
from pathlib import Path

import bouc_wen_id as bw
import pytest
from bouc_wen_id import _pool, cli


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
    assert sorted(p.name for p in out.iterdir()) == [".bouc_wen_id-report", "result.json"]
    assert "beta" in printed and "png" not in printed
    assert json.loads((out / "result.json").read_text())["method"] == "refined"


def test_figures_come_after_the_numbers(
    folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "rep"
    assert cli.main(["identify", str(folder), "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert {p.name for p in out.glob("[!.]*")} == {"result.json", "loops.png", "bode.png", "residuals.png"}
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


# --------------------------------------------------------------------------------------------------
# A folder on both cores (--workers): the files' preprocessing and the figures in worker processes
# --------------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def lab(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Four lab-like measurements (no U or omega in the files: the CLI finds and averages the steady
    stretches), named so that the loader's order is known."""
    path = tmp_path_factory.mktemp("lab")
    plan = bw.demo_plan(samples_per_period=96, periods=12, settle_periods=4, seed=11)
    for i, rec in enumerate(bw.simulate(bw.demo_plant(), plan)[:4]):
        m = bw.Measurement(rec.t, rec.u, rec.y, nominal_frequency=rec.frequency, name=f"lab_{i}")
        bw.io.write_csv(path / f"lab_{i}.csv", m)
    return path


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="--workers is capped at the CPU count")
def test_workers_give_the_serial_report(
    lab: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    # The folder is far below the size where the workers pay; lower the bar so that they run.
    monkeypatch.setattr(cli, "_PARALLEL_MIN_BYTES", 0)
    printed = {}
    for workers in ("1", "2"):
        out = tmp_path / f"w{workers}"
        assert cli.main(["identify", str(lab), "--out", str(out), "--workers", workers]) == 0
        printed[workers] = capsys.readouterr().out.replace(str(out), "OUT")
    w1, w2 = tmp_path / "w1", tmp_path / "w2"
    assert {p.name for p in w2.iterdir()} == {p.name for p in w1.iterdir()} >= {"loops.png", "segments.json"}
    for name in ("result.json", "segments.json"):
        assert (w2 / name).read_text() == (w1 / name).read_text(), name
    assert printed["2"] == printed["1"]  # the same table and per-file lines, in the same order
    assert all((w2 / n).stat().st_size > 10_000 for n in ("loops.png", "bode.png", "residuals.png"))


def test_both_ends_keeps_the_order_and_the_first_error() -> None:
    from concurrent.futures import ThreadPoolExecutor

    from bouc_wen_id.errors import InvalidParameterError

    def job(i: int) -> int:
        if i in (3, 6):
            raise InvalidParameterError(f"job {i}")
        return i * i

    with ThreadPoolExecutor(1) as pool:
        assert list(_pool.ordered(pool, job, [(i,) for i in range(3)])) == [0, 1, 4]
        got = _pool.ordered(pool, job, [(i,) for i in range(8)])
        assert [next(got) for _ in range(3)] == [0, 1, 4]
        with pytest.raises(InvalidParameterError, match="job 3"):  # job 6's error (maybe met first) waits
            next(got)


def test_one_blas_thread_limits_the_loaded_and_later_blas_and_restores(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import numpy as np
    from bouc_wen_id._threads import BLAS_THREAD_VARIABLES, one_blas_thread
    from threadpoolctl import threadpool_info  # type: ignore[import-untyped]

    for v in BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(v, raising=False)
    np.linalg.cholesky(np.eye(2))  # NumPy's BLAS is loaded

    def counts() -> list[int]:
        return [int(i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"]

    before = counts()
    with one_blas_thread():
        assert set(counts()) == {1}
        assert os.environ["OPENBLAS_NUM_THREADS"] == "1"  # for a BLAS loaded later, and worker processes
    assert counts() == before
    assert "OPENBLAS_NUM_THREADS" not in os.environ
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")  # the user's choice stands
    with one_blas_thread():
        assert os.environ["OPENBLAS_NUM_THREADS"] == "2" and counts() == before


def test_workers_beyond_the_cpu_count_is_a_usage_error_naming_the_flag(
    lab: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for workers in ("1000000", str((os.cpu_count() or 1) + 1), "0"):
        with pytest.raises(SystemExit) as info:
            cli.main(["identify", str(lab), "--out", str(tmp_path / "x"), "--workers", workers])
        assert info.value.code == 2
        err = capsys.readouterr().err
        assert "argument --workers" in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x").exists()


def test_a_malformed_scheduler_address_is_a_named_error(
    folder: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    argv = ["identify", str(folder), "--out", str(tmp_path / "x"), "--scheduler", "::::"]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if not line.startswith("[")]
    assert len(lines) == 1 and lines[0].startswith("error: InvalidParameterError: --scheduler '::::'"), err
    assert not (tmp_path / "x").exists()
