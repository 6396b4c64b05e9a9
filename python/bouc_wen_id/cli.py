"""Command line: ``bouc-wen-id demo | simulate | identify``."""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NoReturn, Optional, Union

import numpy as np
from numpy.typing import NDArray

from ._threads import limit_blas_threads, one_blas_thread
from .demo import DEMO_FREQUENCIES, demo_plan, demo_plant, design_amplitudes
from .errors import BoucWenIdError, FileFormatError, InsufficientDataError, InvalidParameterError
from .identification import identify
from .io import load, save_recordings
from .measurement import Measurement
from .model import SinePlan, WienerPlant
from .result import IdentificationResult
from .simulation import simulate
from .terms import DIAGNOSIS_CANDIDATES

#: diagnose's candidates: the steady-loop terms and degradation (diagnosis.run.ALL_CANDIDATES, kept here
#: so that the CLI does not import the diagnosis to build its parser).
_DIAG_CANDIDATES = DIAGNOSIS_CANDIDATES

__all__ = ["main"]


# --------------------------------------------------------------------------------------------------
# Output folders: checked before any work, built beside the target and moved into place whole
# --------------------------------------------------------------------------------------------------


def _check_out(out: Path, overwrite: bool, what: str) -> None:
    """Refuse, before any work, an output that would mix runs or cannot be written."""
    if out.exists() or out.is_symlink():
        holds = not out.is_dir() or any(out.iterdir())
        if holds and not overwrite:
            kind = "folder holding files" if out.is_dir() else "file"
            raise InvalidParameterError(
                f"--out {out}: a {kind} of another run is there; pass --overwrite to replace it whole, or "
                f"choose another {what}"
            )
    parent = out.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise InvalidParameterError(f"--out {out}: {parent} is not a writable folder")


@contextmanager
def _staged(out: Path) -> Iterator[Path]:
    """A path beside ``out`` to write the whole output to; on success it replaces ``out`` in one rename.

    On any failure (an error, Ctrl-C) the staged files are removed and ``out`` is left as it was; a kill
    leaves at most a ``.<name>.partial-*`` folder beside it, never a half-written ``out``.
    """
    parent = out.absolute().parent
    parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=parent))
    try:
        yield stage / out.name
        trash = stage / ".replaced"
        replacing = out.exists() or out.is_symlink()
        if replacing:
            os.replace(out, trash)
        try:
            os.replace(stage / out.name, out)
        except BaseException:
            if replacing:
                os.replace(trash, out)  # put the previous output back rather than lose it
            raise
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _shown(path: Path, staged: Path, out: Path) -> Path:
    """Where a staged file ends up."""
    try:
        return out / path.relative_to(staged)
    except ValueError:
        return path


def _write_report(result: IdentificationResult, out: Path, figures: bool = True) -> list[Path]:
    """The report folder: result.json, then (unless ``figures`` is False) the loops per experiment, the Bode
    points, the residuals."""
    out.mkdir(parents=True, exist_ok=True)
    files = [out / "result.json"]
    files[0].write_text(result.to_json() + "\n", encoding="utf-8")
    if figures:
        files += _write_figures(result, out)
    return files


#: The report's figures: file name -> how it is drawn (``_render_figure``).
_FIGURES = ("loops.png", "bode.png", "residuals.png")


def _write_figures(result: IdentificationResult, out: Path) -> list[Path]:
    """The report's figures (matplotlib is imported here, only when figures are asked for)."""
    files = [out / name for name in _FIGURES]
    for f in files:
        _render_figure(result, f)
    return files


def _render_figure(result: IdentificationResult, path: Path) -> None:
    """One figure of the report into ``path`` (here or in a worker process)."""
    from .plotting import plot_loops, plot_residuals

    fig = {"loops.png": plot_loops, "residuals.png": plot_residuals}.get(path.name)
    figure = fig(result) if fig is not None else result.plot_bode()
    # zlib level 1: a third of the PNG encoding time of the default level 6, files ~20 % larger.
    figure.savefig(path, dpi=120, pil_kwargs={"compress_level": 1})


def _progress(done: int, total: int, label: str) -> None:
    """A one-line progress bar on stderr (plain lines when stderr is not a terminal)."""
    width = 30
    filled = width * done // max(total, 1)
    bar = f"[{'#' * filled}{'.' * (width - filled)}] {done}/{total} {label}"
    if sys.stderr.isatty():
        sys.stderr.write("\r" + bar[:120].ljust(120) + ("\n" if done == total else ""))
    else:
        sys.stderr.write(bar + "\n")
    sys.stderr.flush()


def _add_identify_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--method",
        choices=("refined", "profile", "paper"),
        default="refined",
        help="estimator: refined (default: joint output-error fit with uncertainty), profile, or paper",
    )
    p.add_argument(
        "--reference",
        type=_integer(-(1 << 31)),
        default=0,
        help="experiment used for beta, gamma, mu (default 0)",
    )
    p.add_argument("--settle-periods", type=_integer(0), default=None, help="periods dropped as transient")
    p.add_argument(
        "--periods", type=_integer(1), default=None, help="periods averaged (default: all remaining)"
    )
    p.add_argument(
        "--harmonics",
        type=_harmonics,
        default="auto",
        help="harmonics of the spectral derivative: auto (above the noise floor), all, or a number",
    )
    p.add_argument("--mu-bracket", type=_real(), nargs=2, default=(1.0, 10.0), metavar=("LO", "HI"))
    p.add_argument("--tol", type=_real(positive=True), default=1e-8, help="golden-section tolerance on mu")
    p.add_argument("--backend", choices=("rust", "numpy"), default="rust")
    p.add_argument("--out", type=Path, default=Path("bouc_wen_id_report"), help="report folder")
    _add_overwrite(p)
    p.add_argument(
        "--no-figures",
        dest="figures",
        action="store_false",
        help="write result.json and print the table only (batch use: no matplotlib)",
    )


def _identify_options(args: argparse.Namespace) -> dict[str, Any]:
    """``identify`` keyword arguments from the command line."""
    harmonics = args.harmonics if args.harmonics in ("auto", "all") else int(args.harmonics)
    return {
        "method": args.method,
        "reference": args.reference,
        "settle_periods": args.settle_periods,
        "periods": args.periods,
        "harmonics": harmonics,
        "mu_bracket": tuple(args.mu_bracket),
        "tol": args.tol,
        "backend": args.backend,
    }


def _identify_from_args(args: argparse.Namespace, recordings: Sequence[Any]) -> IdentificationResult:
    return identify(recordings, **_identify_options(args))


def _identify_groups(args: argparse.Namespace, groups: list[list[Any]]) -> list[Any]:
    """Identify every group: an ``IdentificationResult`` or the ``BoucWenIdError`` it raised, in order.

    On the Dask scheduler at ``--scheduler`` (one task per group; identical results), else here, one group
    after the other (each identification uses the cores itself, for its restarts).
    """
    options = _identify_options(args)
    if args.scheduler is None:
        out: list[Any] = []
        for group in groups:
            try:
                out.append(identify(group, **options))
            except BoucWenIdError as exc:
                out.append(exc)
        return out
    from .batch import identify_many

    try:
        from distributed import Client
    except ImportError as exc:
        raise InvalidParameterError(
            "--scheduler needs Dask: pip install 'bouc_wen_id[dask]' (or dask[distributed])"
        ) from exc
    with Client(args.scheduler) as client:  # type: ignore[no-untyped-call]
        return identify_many(groups, client=client, errors="return", **options)


def _cmd_demo(args: argparse.Namespace) -> int:
    plant = demo_plant()
    plan = demo_plan(
        samples_per_period=args.samples_per_period,
        periods=args.periods_sim,
        noise_sd=args.noise,
        seed=args.seed,
    )
    print(f"plant: {plant.linear!r}, {plant.hysteresis!r}")
    print(f"plan:  {plan!r}")
    _check_out(args.out, args.overwrite, "report folder")
    t0 = time.perf_counter()
    recs = simulate(plant, plan, backend=args.backend)
    t1 = time.perf_counter()
    result = _identify_from_args(args, recs)
    t2 = time.perf_counter()
    print(f"simulated {len(recs)} experiments in {t1 - t0:.3f} s, identified in {t2 - t1:.3f} s\n")
    print(result.summary())
    if args.compare:
        print(_compare_methods(recs, args))
    with _staged(args.out) as staged:
        written = _write_report(result, staged, figures=args.figures)
    for f in written:
        print(f"wrote {_shown(f, staged, args.out)}")
    return 0


def _compare_methods(recs: list, args: argparse.Namespace) -> str:  # type: ignore[type-arg]
    """Errors of every method on the same recordings (the truth is known in the demo)."""
    lines = ["", "  the same recordings, every method (estimate - truth; worst over the frequencies):"]
    lines.append(f"  {'method':<9}{'beta':>11}{'gamma':>11}{'mu':>11}{'|G| rel':>11}{'phi':>11}")
    for method in ("paper", "profile", "refined"):
        try:
            err = _identify_from_args(argparse.Namespace(**{**vars(args), "method": method}), recs).errors()
        except BoucWenIdError as exc:
            lines.append(f"  {method:<9}failed: {type(exc).__name__}: {exc}")
            continue
        truth_gain = np.abs(err["gain"]) / np.maximum(np.abs(_truth_gains(recs)), 1e-300)
        lines.append(
            f"  {method:<9}{err['beta']:>11.2e}{err['gamma']:>11.2e}{err['mu']:>11.2e}"
            f"{np.max(truth_gain):>11.2e}{np.max(np.abs(err['phase'])):>11.2e}"
        )
    return "\n".join(lines)


def _truth_gains(recs: list) -> NDArray[np.float64]:  # type: ignore[type-arg]
    plant = recs[0].plant.normalized()
    gains: NDArray[np.float64] = plant.linear.gain_phase([r.frequency for r in recs])[0]
    return gains


def _load_plant(path: Path) -> WienerPlant:
    """A plant JSON file (``WienerPlant.to_dict``), every failure a :class:`FileFormatError`."""
    if not path.is_file():
        raise FileFormatError(f"--plant {path}: no such regular file")
    if path.stat().st_size > 1 << 20:
        raise FileFormatError(f"--plant {path}: {path.stat().st_size} bytes is no plant JSON file")
    try:
        spec = json.loads(path.read_text(encoding="utf-8"))
        if not isinstance(spec, dict):
            raise TypeError(f"a JSON {type(spec).__name__}, not an object")
        return WienerPlant.from_dict(spec)
    except BoucWenIdError:
        raise
    except (OSError, ValueError, TypeError, KeyError, AttributeError) as exc:
        raise FileFormatError(
            f"--plant {path}: not a plant JSON file ({type(exc).__name__}: {exc}); expected "
            '{"linear": {"num": [...], "den": [...], "delay": 0}, "hysteresis": {"beta": ..., "gamma": ..., '
            '"mu": ...}}'
        ) from None


def _cmd_simulate(args: argparse.Namespace) -> int:
    _check_out(args.out, args.overwrite, "--out")
    plant = _load_plant(args.plant) if args.plant else demo_plant()
    if args.amplitude is not None and len(args.amplitude) not in (1, len(args.frequencies)):
        raise InvalidParameterError(
            f"--amplitude: {len(args.amplitude)} values for {len(args.frequencies)} frequencies; give one "
            "per frequency, or one for all"
        )
    plan = SinePlan(
        frequencies=args.frequencies,
        amplitudes=design_amplitudes(plant, args.frequencies) if args.amplitude is None else args.amplitude,
        settle_periods=args.settle_periods,
        periods=args.periods,
        samples_per_period=args.samples_per_period,
        substeps=args.substeps,
        noise_sd=args.noise,
        seed=args.seed,
    )
    recs = simulate(plant, plan, backend=args.backend)
    with _staged(args.out) as staged:
        written = save_recordings(staged, recs)
    for f in written:
        print(f"wrote {_shown(f, staged, args.out)}")
    return 0


def _columns(specs: Optional[Sequence[str]]) -> Optional[dict[str, Union[str, int]]]:
    """``["u=disp", "y=3"]`` -> ``{"u": "disp", "y": 3}`` (an integer is a 0-based column index)."""
    if not specs:
        return None
    out: dict[str, Union[str, int]] = {}
    for spec in specs:
        role, sep, column = spec.partition("=")
        if not sep or not role or not column:
            raise InvalidParameterError(f"--columns {spec!r}: expected ROLE=COLUMN, e.g. u=disp_mm or y=2")
        out[role.strip()] = int(column) if column.strip().lstrip("-").isdigit() else column.strip()
    return out


def _experiments(args: argparse.Namespace) -> tuple[list[Any], list[dict[str, Any]]]:
    """Load the files and turn every measurement into its steady, averaged periods (with a progress bar).

    Returns what ``identify`` takes (recordings and averaged periods) and, per measurement, what was kept
    and dropped, for the report.
    """
    from .signal import average_segments

    items = load(args.paths, columns=_columns(args.columns), sample_rate=args.sample_rate)
    out: list[Any] = []
    segments: list[dict[str, Any]] = []
    measurements = [m for m in items if isinstance(m, Measurement)]
    names = [m.name or f"measurement {i}" for i, m in enumerate(measurements)]
    jobs = [(m, args.min_periods, name) for m, name in zip(measurements, names)]
    pool = getattr(args, "pool", None)
    found_all = _both_ends(pool, _segment_job, jobs) if pool is not None else None
    done = 0
    for item in items:
        if not isinstance(item, Measurement):
            out.append(item)
            continue
        name = names[done]
        _progress(done, len(measurements), f"steady segments of {name}")
        found = (
            next(found_all)
            if found_all is not None
            else average_segments(item, min_periods=args.min_periods, name=name)
        )
        done += 1
        _progress(done, len(measurements), f"steady segments of {name}")
        print(f"{name}: {found.report.summary()}")
        segments.append(found.to_dict())
        out.extend(found.periods)
    if not out:
        raise InsufficientDataError(
            "no steady segment of at least --min-periods periods was found in any file; see the dropped "
            "stretches above"
        )
    return out, segments


def _cmd_identify(args: argparse.Namespace) -> int:
    _check_out(args.out, args.overwrite, "report folder")
    with _folder_pool(args) as args.pool:
        experiments, segments = _experiments(args)
        with _staged(args.out) as staged:
            code, written, notes = _identify_into(args, experiments, segments, staged)
    for f in written:
        print(f"wrote {_shown(f, staged, args.out)}")
    for note in notes:
        print(note)
    return code


def _identify_into(
    args: argparse.Namespace, experiments: list[Any], segments: list[dict[str, Any]], root: Path
) -> tuple[int, list[Path], list[str]]:
    """Every result of the run under ``root`` (the staged report folder): the numbers of every group
    first (the table and result.json), the figures last."""
    groups = [[e] for e in experiments] if args.separately else [experiments]
    label_of = [_label(g[0]) if args.separately else f"{len(g)} experiment(s), jointly" for g in groups]
    _progress(0, len(groups), "identifying")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        results = _identify_groups(args, groups)
    _progress(len(groups), len(groups), "identified")
    failures = 0
    written: list[Path] = []
    notes: list[str] = []
    reported = []
    for i, (label, result) in enumerate(zip(label_of, results)):
        out = root / f"experiment_{i:02d}" if args.separately else root
        if isinstance(result, BoucWenIdError):
            if not args.separately:
                raise result
            failures += 1
            print(f"\n{label}: refused: {type(result).__name__}: {result}")
            out.mkdir(parents=True, exist_ok=True)
            refusal = {"source": label, "error": type(result).__name__, "message": str(result)}
            (out / "refused.json").write_text(json.dumps(refusal, indent=2) + "\n", encoding="utf-8")
            written.append(out / "refused.json")
            continue
        print(f"\n{label}:" if args.separately else "")
        print(result.summary())
        written.extend(_write_report(result, out, figures=False))
        reported.append((result, out))
    for w in caught:
        print(f"warning: {w.category.__name__}: {w.message}")
    root.mkdir(parents=True, exist_ok=True)
    if segments:
        seg_file = root / "segments.json"
        seg_file.write_text(json.dumps(segments, indent=2) + "\n", encoding="utf-8")
        written.append(seg_file)
    if failures:
        notes.append(f"{failures} of {len(groups)} experiment(s) refused (see refused.json in their folders)")
    if args.figures:
        sys.stdout.flush()
        pool = getattr(args, "pool", None)
        if pool is None:
            for result, out in reported:
                written.extend(_write_figures(result, out))
        else:  # every figure a task, on every core
            tasks = [(result, out / name) for result, out in reported for name in _FIGURES]
            for _ in _both_ends(pool, _render_figure, tasks, here=False):
                pass
            written.extend(path for _, path in tasks)
    return (0 if failures < len(groups) else 2), written, notes


# --------------------------------------------------------------------------------------------------
# Both cores for a folder (issue #8): the files' preprocessing and the figures in worker processes
# --------------------------------------------------------------------------------------------------

#: Below this many bytes of input files the folder is prepared here: starting the workers (a fork server
#: that imports the package and matplotlib, ~0.5 s of one core) would cost more than it saves.  A lab
#: file of 20,000 samples is about 1.2 MB of CSV.
_PARALLEL_MIN_BYTES = 2_000_000


def _usable_cores() -> int:
    """The cores this process may run on (its affinity mask where the OS has one, e.g. under taskset)."""
    if hasattr(os, "sched_getaffinity"):
        return len(os.sched_getaffinity(0))
    return os.cpu_count() or 1


def _input_bytes(paths: Sequence[Path]) -> int:
    """Total size of the files named or inside the folders named (one level, as ``load`` reads them)."""
    total = 0
    for p in paths:
        try:
            if p.is_dir():
                total += sum(f.stat().st_size for f in p.iterdir() if f.is_file())
            elif p.is_file():
                total += p.stat().st_size
        except OSError:
            pass  # load reports unreadable paths, by name
    return total


def _init_worker() -> None:
    """A worker of the command line: one rayon thread and one BLAS thread (the parallelism is across
    the files and figures; nested threads would only compete for the same cores)."""
    os.environ["RAYON_NUM_THREADS"] = "1"
    limit_blas_threads()


def _warm(pool: Any, workers: int) -> None:
    # A task per worker, so that every worker process is started (ProcessPoolExecutor starts them on
    # submit, and a start waits for the fork server's imports: off the main thread, that overlaps
    # with the loading of the files).
    try:
        for f in [pool.submit(os.getpid) for _ in range(workers)]:
            f.result()
    except Exception:  # noqa: BLE001 - a pool that cannot start fails the main thread's first task, by name
        pass


@contextmanager
def _folder_pool(args: argparse.Namespace) -> Iterator[Optional[Any]]:
    """Worker processes for a large folder on a machine with several cores (else ``None``: all here).

    ``--workers 1`` (or one usable core, or under 2 MB of input) keeps everything in this process.  The
    workers come from a fork server that imports the package (and matplotlib, with figures) once, started
    on a helper thread while this one loads the files.  Results are identical: each file's preprocessing
    and each figure is deterministic and independent of where it runs.
    """
    workers = args.workers if args.workers is not None else _usable_cores()
    if workers < 2 or _input_bytes(args.paths) < _PARALLEL_MIN_BYTES:
        yield None
        return
    import multiprocessing
    import threading
    from concurrent.futures import ProcessPoolExecutor

    ctx: Any
    if "forkserver" in multiprocessing.get_all_start_methods():
        ctx = multiprocessing.get_context("forkserver")
        preload = ["bouc_wen_id.cli", "bouc_wen_id.signal"]
        if args.figures:
            preload += ["bouc_wen_id.plotting", "matplotlib.figure", "matplotlib.backends.backend_agg"]
        ctx.set_forkserver_preload(preload)
    else:  # pragma: no cover - Windows, macOS default: spawned workers import on their own
        ctx = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_init_worker)
    warm = threading.Thread(target=_warm, args=(pool, workers), daemon=True)
    warm.start()
    try:
        yield pool
    finally:
        warm.join()
        pool.shutdown(wait=True, cancel_futures=True)


def _segment_job(measurement: Measurement, min_periods: float, name: str) -> Any:
    """One measurement's steady segments, averaged (a task of the folder's workers)."""
    from .signal import average_segments

    return average_segments(measurement, min_periods=min_periods, name=name)


def _both_ends(
    pool: Any, fn: Callable[..., Any], jobs: Sequence[tuple[Any, ...]], here: bool = True
) -> Iterator[Any]:
    """``fn(*job)`` for every job, yielded in the jobs' order.

    The pool's workers take the jobs from the front; with ``here``, this process takes them from the back
    (each job it can still withdraw from the pool) until the two meet, so that no core waits while the
    workers start.  An error is raised when its job's turn comes, as a loop over the jobs would.
    """
    futures = [pool.submit(fn, *job) for job in jobs]
    local: dict[int, tuple[bool, Any]] = {}
    if here:
        for i in reversed(range(len(jobs))):
            if not futures[i].cancel():
                break
            try:
                local[i] = (True, fn(*jobs[i]))
            except BoucWenIdError as exc:
                local[i] = (False, exc)
    try:
        for i, f in enumerate(futures):
            if i in local:
                ok, value = local.pop(i)
                if not ok:
                    raise value
                yield value
            else:
                yield f.result()
    finally:
        for f in futures:
            f.cancel()


def _label(item: Any) -> str:
    source = getattr(item, "source", None) or getattr(item, "metadata", {}).get("name")
    return str(source) if source else type(item).__name__


class _Parser(argparse.ArgumentParser):
    """An argument error is one line and exit status 2 (argparse's usage block is on ``--help``)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (usage: {self.prog} --help)\n")


def _integer(low: int) -> Callable[[str], int]:
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"{value} must be >= {low}")
        return value

    return parse


def _real(positive: bool = False, nonnegative: bool = False) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text!r} is not finite")
        if positive and not value > 0:
            raise argparse.ArgumentTypeError(f"{value:g} must be > 0")
        if nonnegative and not value >= 0:
            raise argparse.ArgumentTypeError(f"{value:g} must be >= 0")
        return value

    return parse


def _harmonics(text: str) -> Union[str, int]:
    if text in ("auto", "all"):
        return text
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not auto, all or an integer") from None
    if not 1 <= value <= 1 << 20:
        raise argparse.ArgumentTypeError(f"{value} must be in [1, 2**20]")
    return value


def _add_overwrite(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an --out that holds another run's files (it is replaced whole, never mixed)",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="bouc-wen-id",
        description="Identify Wiener systems with Bouc-Wen hysteresis from sine experiments.",
    )
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("demo", help="simulate the built-in plant and identify it")
    p.add_argument("--samples-per-period", type=_integer(8), default=1024)
    p.add_argument("--periods-sim", type=_integer(1), default=40, help="periods simulated after settling")
    p.add_argument(
        "--noise", type=_real(nonnegative=True), default=0.005, help="output noise standard deviation"
    )
    p.add_argument("--seed", type=_integer(0), default=2024)
    p.add_argument(
        "--compare",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="also run every method on the same recordings and print their errors",
    )
    _add_identify_options(p)
    p.set_defaults(func=_cmd_demo)

    p = sub.add_parser("simulate", help="simulate sine experiments and write recordings")
    p.add_argument("--out", type=Path, required=True, help="folder of CSV files, or a .npz bundle")
    _add_overwrite(p)
    p.add_argument("--plant", type=Path, default=None, help="plant JSON (default: the demo plant)")
    p.add_argument(
        "--frequencies", type=_real(positive=True), nargs="+", default=list(DEMO_FREQUENCIES), help="rad/s"
    )
    p.add_argument(
        "--amplitude",
        type=_real(),
        nargs="+",
        default=None,
        help="U per frequency, or one for all (default: designed so that |alpha G| U = 1.2 w_0)",
    )
    p.add_argument("--settle-periods", type=_integer(0), default=30)
    p.add_argument("--periods", type=_integer(1), default=40)
    p.add_argument("--samples-per-period", type=_integer(8), default=1024)
    p.add_argument("--substeps", type=_integer(1), default=2)
    p.add_argument("--noise", type=_real(nonnegative=True), default=0.005)
    p.add_argument("--seed", type=_integer(0), default=2024)
    p.add_argument("--backend", choices=("rust", "numpy"), default="rust")
    p.set_defaults(func=_cmd_simulate)

    p = sub.add_parser(
        "identify",
        help="identify from files (.csv, .npz, .mat, .tdms, .h5) or folders: simulated recordings or lab "
        "measurements",
        description="Identify from recordings (U and omega known) or lab measurements (any sampling rate: "
        "the input's frequency and amplitude are estimated, the steady stretches found and averaged).",
    )
    p.add_argument("paths", nargs="+", type=Path, help="files or folders of files")
    p.add_argument(
        "--columns",
        nargs="+",
        default=None,
        metavar="ROLE=COLUMN",
        help="which column is t, u, y (names or 0-based indices; TDMS/HDF5: channel names or "
        "group/channel paths), e.g. --columns u=disp_mm y=force_N",
    )
    p.add_argument(
        "--sample-rate", type=_real(positive=True), default=None, help="Hz, for files without a time column"
    )
    p.add_argument(
        "--min-periods",
        type=_real(positive=True),
        default=2.0,
        help="shortest steady stretch kept, in periods (default 2)",
    )
    p.add_argument(
        "--separately",
        action="store_true",
        help="identify each experiment on its own (a report subfolder each) instead of one joint fit",
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDRESS",
        help="run the identification on this Dask scheduler (e.g. tcp://10.0.0.5:8786; needs the dask extra)",
    )
    p.add_argument(
        "--workers",
        type=_integer(1),
        default=None,
        help="processes preparing the files and drawing the figures (default: one per core; 1: all in this "
        "process)",
    )
    _add_identify_options(p)
    p.set_defaults(func=_cmd_identify)

    p = sub.add_parser(
        "diagnose",
        help="diagnose what the model leaves out: where, which physics, and the held-out proof",
        description="Fit the plain model and the library's candidate terms jointly; name a term only when "
        "it passes a nested F-test (Bonferroni over the candidates), explains a material share of the misfit "
        "and improves the fit on held-out experiments. The verdict comes first.",
    )
    p.add_argument("paths", nargs="+", type=Path, help="files or folders of files")
    p.add_argument(
        "--columns",
        nargs="+",
        default=None,
        metavar="ROLE=COLUMN",
        help="which column (TDMS/HDF5: channel, or group/channel) is t, u, y",
    )
    p.add_argument(
        "--sample-rate", type=_real(positive=True), default=None, help="Hz, for files without a time column"
    )
    p.add_argument(
        "--candidates",
        type=_candidates,
        default=None,
        help="comma-separated terms to try (default: all of " + ",".join(_DIAG_CANDIDATES) + ")",
    )
    p.add_argument("--alpha", type=_level, default=0.05, help="false-alarm level per step (default 0.05)")
    p.add_argument("--no-held-out", action="store_true", help="skip the held-out check (faster, weaker)")
    p.add_argument("--no-figures", action="store_true", help="write the JSON and a text-only HTML page")
    p.add_argument("--out", type=Path, default=Path("bouc_wen_id_diagnosis"), help="report folder")
    _add_overwrite(p)
    p.set_defaults(func=_cmd_diagnose)
    _add_plan_parser(sub)
    return parser


def _candidates(text: str) -> list[str]:
    names = [c.strip() for c in text.split(",") if c.strip()]
    bad = [c for c in names if c not in _DIAG_CANDIDATES]
    if not names or bad or len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(
            f"{text!r}: give distinct names among {','.join(_DIAG_CANDIDATES)}, separated by commas"
        )
    return names


def _level(text: str) -> float:
    value = _real(positive=True)(text)
    if not value < 1:
        raise argparse.ArgumentTypeError(f"{value:g} must lie in (0, 1)")
    return value


def _cmd_diagnose(args: argparse.Namespace) -> int:
    """Diagnose the files jointly; the verdict first, then diagnosis.json, the figures and report.html."""
    from .diagnosis import diagnose
    from .diagnosis.report import write_report

    _check_out(args.out, args.overwrite, "report folder")
    items = list(load(args.paths, columns=_columns(args.columns), sample_rate=args.sample_rate))
    units = next((m.units for m in items if isinstance(m, Measurement)), {})
    d = diagnose(
        items,
        candidates=args.candidates,
        alpha=args.alpha,
        held_out_test=not args.no_held_out,
        y_unit=str(units.get("y", "")),
        u_unit=str(units.get("u", "")),
    )
    print(d.summary())
    with _staged(args.out) as staged:
        written = write_report(d, staged, figures=not args.no_figures)
    for f in written:
        print(f"wrote {_shown(f, staged, args.out)}")
    return 0


def _one_line(text: str) -> str:
    return " ".join(text.split())


# --------------------------------------------------------------------------------------------------
# bouc-wen-id plan: the experiment planner (bouc_wen_id.planning)
# --------------------------------------------------------------------------------------------------


def _add_plan_parser(sub: Any) -> None:
    p = sub.add_parser(
        "plan",
        help="plan sine experiments (frequencies, amplitudes, periods) for the best precision in a budget",
        description="From a prior plant, choose the experiments that minimise the Cramer-Rao bound of the "
        "target within the test-time budget and the actuator and sampling limits; print the design, its "
        "expected standard errors and the gain over a naive design of the same budget.",
    )
    p.add_argument(
        "--plant",
        type=Path,
        default=None,
        help="prior: a plant JSON, or a previous result JSON (then give G with --num/--den); default: the "
        "demo plant, or the plant given by --num/--den/--beta/--gamma/--mu",
    )
    p.add_argument(
        "--num", type=_real(), nargs="+", default=None, help="prior G numerator (descending powers)"
    )
    p.add_argument("--den", type=_real(), nargs="+", default=None, help="prior G denominator")
    p.add_argument("--delay", type=_real(nonnegative=True), default=0.0, help="prior G pure delay, s")
    p.add_argument("--beta", type=_real(), default=None)
    p.add_argument("--gamma", type=_real(), default=None)
    p.add_argument("--mu", type=_real(), default=None)
    p.add_argument("--alpha", type=_real(positive=True), default=1.0)
    p.add_argument("--budget", type=_real(positive=True), required=True, help="total test time, s")
    p.add_argument(
        "--band", type=_real(positive=True), nargs=2, required=True, metavar=("LOW", "HIGH"), help="rad/s"
    )
    p.add_argument("--max-amplitude", type=_real(positive=True), required=True, help="largest input U")
    p.add_argument(
        "--max-rate", type=_real(positive=True), default=None, help="largest U omega (velocity limit)"
    )
    p.add_argument(
        "--noise", type=_real(positive=True), required=True, help="prior output noise sd per sample"
    )
    p.add_argument(
        "--sample-rate", type=_real(positive=True), required=True, help="highest sampling rate, Hz"
    )
    p.add_argument("--target", choices=("bouc_wen", "beta", "gamma", "mu", "G"), default="bouc_wen")
    p.add_argument(
        "--frequencies", type=_integer(2), default=12, help="candidate frequencies (G: tested grid)"
    )
    p.add_argument("--amplitudes", type=_integer(1), default=4, help="candidate amplitudes per frequency")
    p.add_argument("--settle-periods", type=_integer(0), default=20)
    p.add_argument(
        "--overhead", type=_real(nonnegative=True), default=0.0, help="set-up time per experiment, s"
    )
    p.add_argument("--max-samples-per-period", type=_integer(16), default=512)
    p.add_argument("--min-periods", type=_integer(2), default=5)
    p.add_argument("--max-experiments", type=_integer(2), default=None)
    p.add_argument("--out", type=Path, default=None, help="write the plan as JSON to this file")
    _add_overwrite(p)
    p.set_defaults(func=_cmd_plan)


def _prior_from_args(args: argparse.Namespace) -> WienerPlant:
    """The prior plant of ``bouc-wen-id plan``: a plant JSON, a result JSON + --num/--den, or arguments."""
    from .model import BoucWen, TransferFunction

    bw_args = (args.beta, args.gamma, args.mu)
    linear = None if args.num is None and args.den is None else (args.num, args.den)
    if linear is not None and (args.num is None or args.den is None):
        raise InvalidParameterError("--num and --den go together")
    if args.plant is None:
        if linear is None and all(v is None for v in bw_args):
            return demo_plant()
        if linear is None or any(v is None for v in bw_args):
            raise InvalidParameterError(
                "without --plant, give the prior as --num, --den, --beta, --gamma and --mu "
                "(or none of them: the demo plant)"
            )
        return WienerPlant(
            TransferFunction(args.num, args.den, args.delay),
            BoucWen(args.beta, args.gamma, args.mu, args.alpha),
        )
    try:
        spec = json.loads(args.plant.read_text(encoding="utf-8")) if args.plant.is_file() else None
    except (OSError, ValueError):
        spec = None
    if isinstance(spec, dict) and spec.get("format") == "bouc_wen_id.result":
        if linear is None:
            raise InvalidParameterError(
                f"--plant {args.plant}: a result JSON holds G only at its tested frequencies; give the prior "
                "G(s) with --num/--den (and --delay), e.g. from bouc_wen_id.fit_transfer_function"
            )
        try:
            values = [float(spec[k]) for k in ("beta", "gamma", "mu")]
        except (KeyError, TypeError, ValueError):
            raise FileFormatError(f"--plant {args.plant}: a result JSON without beta, gamma, mu") from None
        # The result is alpha-normalised: its G is alpha G, so alpha = 1 with the G the user gives.
        return WienerPlant(TransferFunction(args.num, args.den, args.delay), BoucWen(*values))
    if linear is not None or any(v is not None for v in bw_args):
        raise InvalidParameterError("--plant with a plant JSON takes no --num/--den/--beta/--gamma/--mu")
    return _load_plant(args.plant)


def _cmd_plan(args: argparse.Namespace) -> int:
    from .planning import plan_experiment

    if args.out is not None:
        _check_out(args.out, args.overwrite, "--out")
    prior = _prior_from_args(args)
    plan = plan_experiment(
        prior,
        args.budget,
        band=(args.band[0], args.band[1]),
        max_amplitude=args.max_amplitude,
        noise_sd=args.noise,
        sample_rate=args.sample_rate,
        target=args.target,
        max_rate=args.max_rate,
        n_frequencies=args.frequencies,
        n_amplitudes=args.amplitudes,
        settle_periods=args.settle_periods,
        overhead=args.overhead,
        max_samples_per_period=args.max_samples_per_period,
        min_periods=args.min_periods,
        max_experiments=args.max_experiments,
    )
    print(plan.summary())
    if args.out is not None:
        with _staged(args.out) as staged:
            staged.write_text(plan.to_json() + "\n", encoding="utf-8")
        print(f"wrote {args.out}")
    return 0


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command line; every failure is one line on stderr, never a traceback.

    Exit status: 0 done, 2 refused (a bad argument, file or value: the line names it), 130 interrupted
    (nothing was written), 1 an internal error (a bug: please report the line).
    """
    args = build_parser().parse_args(argv)
    try:
        with one_blas_thread():  # small matrices only: see bouc_wen_id._threads
            return int(args.func(args))
    except BoucWenIdError as exc:
        print(f"error: {type(exc).__name__}: {_one_line(str(exc))}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted: nothing was written", file=sys.stderr)
        return 130
    except ImportError as exc:  # an optional extra (pandas, npTDMS, h5py) is missing: the line says which
        print(f"error: {type(exc).__name__}: {_one_line(str(exc))}", file=sys.stderr)
        return 2
    except OSError as exc:
        print(f"error: {type(exc).__name__}: {_one_line(str(exc))}", file=sys.stderr)
        return 2
    except MemoryError:
        print(
            "error: MemoryError: out of memory; use a smaller problem or lower bouc_wen_id.budget limits",
            file=sys.stderr,
        )
        return 2
    except Exception as exc:  # noqa: BLE001 - no traceback reaches a terminal user
        print(
            f"internal error: {type(exc).__name__}: {_one_line(str(exc))} (please report it)", file=sys.stderr
        )
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
