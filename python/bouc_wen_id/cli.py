"""Command line: ``bouc-wen-id demo | simulate | identify | diagnose | plan``.

Every command calls the functions a user calls (:func:`~bouc_wen_id.identify`,
:func:`~bouc_wen_id.batch.identify_many`, :func:`~bouc_wen_id.batch.average_many`,
:func:`~bouc_wen_id.diagnose`, :func:`~bouc_wen_id.plan_experiment`); what is the command line's own is the
parsing, the printing, and the report folder (:mod:`bouc_wen_id._output`: only ever our own).
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import time
import warnings
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Optional, Union

import numpy as np
from numpy.typing import NDArray

from . import _output, _pool
from ._cli_across import cmd_across
from ._cli_export import run_export
from ._cli_parser import build_parser, flags_named
from ._cli_validate import cmd_validate
from ._threads import one_blas_thread
from .batch import average_many, identify_many
from .demo import DEMO_HIDDEN, demo_hidden_plant, demo_plan, demo_plant, design_amplitudes
from .errors import BoucWenIdError, FileFormatError, InvalidParameterError
from .identification import identify
from .io import load, save_recordings
from .measurement import Measurement
from .model import SinePlan, WienerPlant
from .result import IdentificationResult
from .simulation import simulate

__all__ = ["main", "build_parser"]


# --------------------------------------------------------------------------------------------------
# The report: checked before any work, built in a partial folder and moved into place whole
# --------------------------------------------------------------------------------------------------


def _check_out(args: argparse.Namespace, inputs: Sequence[Path] = (), what: str = "report folder") -> None:
    """Refuse, before any work, an ``--out`` that is not ours to write (see :mod:`bouc_wen_id._output`)."""
    args.out_resolved = _output.check_out(args.out, overwrite=args.overwrite, inputs=inputs, what=what)
    # The report --overwrite replaces: the one there now, not one another run puts there meanwhile.
    args.out_replaces = _output.identity(args.out_resolved) if args.overwrite else None


@contextmanager
def _staged(args: argparse.Namespace) -> Iterator[Path]:
    with _output.staged(args.out_resolved, command=args.command, replaces=args.out_replaces) as staged:
        yield staged
    args.out_staged = staged


def _print_written(args: argparse.Namespace, written: Sequence[Path]) -> None:
    for f in written:
        print(f"wrote {_output.shown(f, args.out_staged, args.out)}")


def _write_report(
    result: IdentificationResult, out: Path, figures: bool = True, style: Optional[dict[str, str]] = None
) -> list[Path]:
    """The report folder: result.json, then (unless ``figures`` is False) the loops per experiment, the Bode
    points, the residuals (``style``: the data's units and the Bode units, see ``_figure_style``)."""
    out.mkdir(parents=True, exist_ok=True)
    files = [out / "result.json"]
    files[0].write_text(result.to_json() + "\n", encoding="utf-8")
    if figures:
        files += _write_figures(result, out, style)
    return files


#: The report's figures, one file each (drawn by ``_render_figure``).
_FIGURES = ("loops.png", "bode.png", "residuals.png")


def _figure_style(args: argparse.Namespace, items: Sequence[Any] = ()) -> dict[str, str]:
    """The figures' labels: the units of the first lab measurement that names them, and ``--bode-units``."""
    units = next((m.units for m in items if isinstance(m, Measurement)), {})
    return {
        "u_unit": str(units.get("u", "")),
        "y_unit": str(units.get("y", "")),
        "bode_units": str(getattr(args, "bode_units", "linear")),
    }


def _write_figures(
    result: IdentificationResult, out: Path, style: Optional[dict[str, str]] = None
) -> list[Path]:
    """The report's figures (matplotlib is imported here, only when figures are asked for)."""
    files = [out / name for name in _FIGURES]
    for f in files:
        _render_figure(result, f, style)
    return files


def _render_figure(result: IdentificationResult, path: Path, style: Optional[dict[str, str]] = None) -> None:
    """One figure of the report into ``path`` (here or in a worker process), labelled with ``style``."""
    from .plotting import plot_bode, plot_loops, plot_residuals

    st = style or {}
    u_unit, y_unit = st.get("u_unit", ""), st.get("y_unit", "")
    if path.name == "loops.png":
        figure = plot_loops(result, u_unit=u_unit, y_unit=y_unit)
    elif path.name == "residuals.png":
        figure = plot_residuals(result, y_unit=y_unit)
    else:
        figure = plot_bode(result, units=st.get("bode_units", "linear"), u_unit=u_unit, y_unit=y_unit)
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


# --------------------------------------------------------------------------------------------------
# demo and simulate
# --------------------------------------------------------------------------------------------------


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
    _check_out(args)
    t0 = time.perf_counter()
    recs = simulate(plant, plan, backend=args.backend)
    t1 = time.perf_counter()
    result = identify(recs, **_identify_options(args))
    t2 = time.perf_counter()
    print(f"simulated {len(recs)} experiments in {t1 - t0:.3f} s, identified in {t2 - t1:.3f} s\n")
    print(result.summary())
    if args.compare:
        print(_compare_methods(recs, args))
    diagnosis = _demo_diagnosis(plan, args) if args.diagnosis else None
    with _staged(args) as staged:
        written = _write_report(result, staged, figures=args.figures, style=_figure_style(args))
        if diagnosis is not None:
            from .diagnosis.report import write_report

            d, plain, notes = diagnosis
            written += write_report(
                d, staged / "diagnosis", figures=args.figures, identified=plain, identify_warnings=notes
            )
    _print_written(args, written)
    return 0


def _demo_diagnosis(plan: SinePlan, args: argparse.Namespace) -> Any:
    """The demo's second half: the same plant with a dashpot hidden beside it, identified (the plain
    model fails its test) and diagnosed (the dashpot named, its value, the held-out gain)."""
    from .diagnosis import diagnose

    hidden = DEMO_HIDDEN
    print(
        f"\n--- diagnosis: the same plant with a hidden {hidden.description} "
        f"({hidden.symbol} = {hidden.value:g}) ---"
    )
    from .diagnosis.report import identify_plain

    recs = simulate(demo_hidden_plant(), plan, backend=args.backend)
    plain, notes = identify_plain(recs, **_identify_options(args))
    adequacy = None if isinstance(plain, Exception) else plain.adequacy
    if adequacy is not None:
        fails = "fails" if adequacy.rejects() else "passes"
        print(f"identify: the plain model {fails} its adequacy test (p = {adequacy.p_value:.2g})")
    d = diagnose(recs)
    print(d.summary())
    return d, plain, notes


def _compare_methods(recs: list, args: argparse.Namespace) -> str:  # type: ignore[type-arg]
    """Errors of every method on the same recordings (the truth is known in the demo)."""
    lines = ["", "  the same recordings, every method (estimate - truth; worst over the frequencies):"]
    lines.append(f"  {'method':<9}{'beta':>11}{'gamma':>11}{'mu':>11}{'|G| rel':>11}{'phi':>11}")
    for method in ("paper", "profile", "refined"):
        try:
            err = identify(recs, **{**_identify_options(args), "method": method}).errors()
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
    _check_out(args, what="--out")
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
    with _staged(args) as staged:
        written = save_recordings(staged, recs)
    _print_written(args, written)
    return 0


# --------------------------------------------------------------------------------------------------
# identify: files and folders, lab measurements prepared on every core (bouc_wen_id.batch.average_many)
# --------------------------------------------------------------------------------------------------


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


#: Below this many bytes of input files the folder is prepared here: starting the workers (a fork server
#: that imports the package and matplotlib, ~0.5 s of one core) would cost more than it saves.  A lab
#: file of 20,000 samples is about 1.2 MB of CSV.
_PARALLEL_MIN_BYTES = 2_000_000


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


@contextmanager
def _workers(args: argparse.Namespace) -> Iterator[int]:
    """How many processes prepare the files and draw the figures: ``--workers`` (default one per usable
    core), but 1 under 2 MB of input.  With several, their pool is started on a helper thread while this
    one loads the files (the fork server imports the package, and matplotlib with figures, once)."""
    workers = args.workers if args.workers is not None else _pool.usable_cores()
    if workers < 2 or _input_bytes(args.paths) < _PARALLEL_MIN_BYTES:
        yield 1
        return
    preload = [*_pool.DEFAULT_PRELOAD, "bouc_wen_id.cli"]
    if args.figures:
        preload += ["bouc_wen_id.plotting", "matplotlib.figure", "matplotlib.backends.backend_agg"]
    starting = _pool.warm(_pool.get_pool(workers, preload), workers)
    try:
        yield workers
    finally:
        starting.join()


def _prepare(args: argparse.Namespace, workers: int) -> tuple[list[Any], list[dict[str, Any]]]:
    """Load the files; every lab measurement cut into its steady, averaged periods (a progress bar on
    stderr, each file's kept and dropped stretches on stdout)."""
    items = load(
        args.paths, columns=_columns(args.columns), sample_rate=args.sample_rate, skiprows=args.skiprows
    )
    args.figure_style = _figure_style(args, items)
    total = sum(isinstance(m, Measurement) for m in items)

    def report(i: int, found: Any) -> None:
        _progress(i + 1, total, f"steady segments of {found.name}")
        print(f"{found.name}: {found.report.summary()}")

    if total:
        _progress(0, total, "steady segments")
    experiments, segmented = average_many(
        items, min_periods=args.min_periods, workers=workers, on_each=report
    )
    return experiments, [s.to_dict() for s in segmented]


def _cmd_identify(args: argparse.Namespace) -> int:
    _check_out(args, inputs=args.paths)
    with _workers(args) as workers:
        experiments, segments = _prepare(args, workers)
        with _staged(args) as staged:
            code, written, notes = _identify_into(args, experiments, segments, staged, workers)
    _print_written(args, written)
    for note in notes:
        print(note)
    return code


def _identify_groups(args: argparse.Namespace, groups: list[list[Any]]) -> list[Any]:
    """Identify every group: an ``IdentificationResult`` or the ``BoucWenIdError`` it raised, in order.

    On the Dask scheduler at ``--scheduler`` (one task per group; identical results), else here, one group
    after the other (each identification uses the cores itself, for its restarts).
    """
    options = _identify_options(args)
    if args.scheduler is None:
        return identify_many(groups, workers=1, errors="return", **options)
    try:
        from distributed import Client
    except ImportError as exc:
        raise InvalidParameterError(
            "--scheduler needs Dask: pip install 'bouc_wen_id[dask]' (or dask[distributed])"
        ) from exc
    try:
        client = Client(args.scheduler)  # type: ignore[no-untyped-call]
    except (ValueError, TypeError, OSError) as exc:
        raise InvalidParameterError(
            f"--scheduler {args.scheduler!r}: no Dask scheduler there ({type(exc).__name__}: {exc}); give "
            "its address, e.g. tcp://10.0.0.5:8786"
        ) from None
    with client:
        return identify_many(groups, client=client, errors="return", **options)


def _identify_into(
    args: argparse.Namespace, experiments: list[Any], segments: list[dict[str, Any]], root: Path, workers: int
) -> tuple[int, list[Path], list[str]]:
    """Every result of the run under ``root`` (the staged report folder): the numbers of every group
    first (the table and result.json), the figures last."""
    groups = [[e] for e in experiments] if args.separately else [experiments]
    _progress(0, len(groups), "identifying")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        results = _identify_groups(args, groups)
    _progress(len(groups), len(groups), "identified")
    written: list[Path] = []
    reported = []
    for i, (group, result) in enumerate(zip(groups, results)):
        out = root / f"experiment_{i:02d}" if args.separately else root
        label = _label(group[0]) if args.separately else f"{len(group)} experiment(s), jointly"
        if isinstance(result, BoucWenIdError):
            if not args.separately:
                raise result
            written.append(_write_refusal(label, result, out))
            continue
        print(f"\n{label}:" if args.separately else "")
        print(result.summary())
        written.extend(_write_report(result, out, figures=False))
        reported.append((result, out))
    for w in caught:
        print(f"warning: {w.category.__name__}: {w.message}")
    root.mkdir(parents=True, exist_ok=True)
    if segments:
        (root / "segments.json").write_text(json.dumps(segments, indent=2) + "\n", encoding="utf-8")
        written.append(root / "segments.json")
    if args.figures:
        written.extend(_figures_of(reported, workers, getattr(args, "figure_style", _figure_style(args))))
    failures = len(groups) - len(reported)
    notes = [f"{failures} of {len(groups)} experiment(s) refused (see refused.json in their folders)"]
    return (0 if reported else 2), written, notes if failures else []


def _write_refusal(label: str, error: BoucWenIdError, out: Path) -> Path:
    print(f"\n{label}: refused: {type(error).__name__}: {error}")
    out.mkdir(parents=True, exist_ok=True)
    refusal = {"source": label, "error": type(error).__name__, "message": str(error)}
    (out / "refused.json").write_text(json.dumps(refusal, indent=2) + "\n", encoding="utf-8")
    return out / "refused.json"


def _figures_of(
    reported: Sequence[tuple[IdentificationResult, Path]], workers: int, style: dict[str, str]
) -> list[Path]:
    """Every figure of every result: here, or one task each on the pool of ``workers``."""
    sys.stdout.flush()
    if workers < 2:
        return [f for result, out in reported for f in _write_figures(result, out, style)]
    tasks = [(result, out / name, style) for result, out in reported for name in _FIGURES]
    for _ in _pool.ordered(_pool.get_pool(workers), _render_figure, tasks, here=False):
        pass
    return [task[1] for task in tasks]


def _label(item: Any) -> str:
    source = getattr(item, "source", None) or getattr(item, "metadata", {}).get("name")
    return str(source) if source else type(item).__name__


# --------------------------------------------------------------------------------------------------
# diagnose and plan
# --------------------------------------------------------------------------------------------------


def _cmd_diagnose(args: argparse.Namespace) -> int:
    """Diagnose the files jointly; the verdict first, then diagnosis.json, the figures and report.html."""
    from .diagnosis import diagnose
    from .diagnosis.report import identify_plain, write_report

    folder = _json_target(args)
    items = list(
        load(args.paths, columns=_columns(args.columns), sample_rate=args.sample_rate, skiprows=args.skiprows)
    )
    style = _figure_style(args, items)
    # The plain model as identify fits the same files, and its warnings, for the page (after the verdict).
    print("identify: fitting the plain model for the report", file=sys.stderr, flush=True)
    identified, notes = identify_plain(items)
    d = diagnose(
        items,
        candidates=args.candidates,
        alpha=args.alpha,
        held_out_test=not args.no_held_out,
        y_unit=style["y_unit"],
        u_unit=style["u_unit"],
        progress=True,
        value_stability=not args.no_stability,
    )
    to_stdout = args.json is not None and str(args.json) == "-"
    print(d.summary(), file=sys.stderr if to_stdout else sys.stdout)
    if args.json is not None:
        if to_stdout:
            sys.stdout.write(d.to_json() + "\n")
        else:
            _output.write_file(args.json, d.to_json() + "\n", overwrite=args.overwrite, flag="--json")
            print(f"wrote {args.json}", file=sys.stderr)
    if not folder:
        return 0
    with _staged(args) as staged:
        written = write_report(
            d,
            staged,
            figures=not args.no_figures,
            identified=identified,
            identify_warnings=notes,
            u_unit=style["u_unit"],
            y_unit=style["y_unit"],
        )
        failed = ""
        if args.model:
            try:
                written = [*written, _diagnosed_model(d, items, staged, identified)]
            except BoucWenIdError as exc:  # the report stands without it (review 36b: lost with it)
                failed = f"{type(exc).__name__}: {exc}"
    _print_written(args, written)
    if failed:
        print(f"error: model.json not written ({failed}); the report above was written", file=sys.stderr)
        return 1
    return 0


def _json_target(args: argparse.Namespace) -> bool:
    """Check ``diagnose``'s outputs before any work; whether a report folder is written (``--out``, or no
    ``--json``, or ``--model``, whose model.json goes in it). ``--json`` is refused when it names an input or
    an existing file without --overwrite."""
    folder = args.out is not None or args.json is None or args.model
    if args.out is None and folder:
        args.out = Path("bouc_wen_id_diagnosis")
    if folder:
        _check_out(args, inputs=args.paths)
    if args.json is not None and str(args.json) != "-":
        _output.check_spelling(args.json, "--json")  # a NUL byte, too long or too deep: refused by name
        try:
            target = args.json.resolve()
            inputs = [Path(p).resolve() for p in args.paths]
        except (OSError, RuntimeError) as exc:
            raise InvalidParameterError(f"--json {args.json}: cannot be resolved ({exc})") from None
        if any(target == q or q in target.parents for q in inputs):
            raise InvalidParameterError(f"--json {args.json} is one of the inputs (or inside one)")
        _output.check_file(args.json, overwrite=args.overwrite, flag="--json")
    return folder


def _diagnosed_model(d: Any, items: Sequence[Any], out: Path, identified: Any = None) -> Path:
    """OUT/model.json: the model the diagnosis describes (``Diagnosis.to_model``), saved by save_model.
    Lab files (no sine Recording among them) start from the plain model identify fitted for the report."""
    from .export import save_model
    from .model import Recording
    from .result import IdentificationResult

    print("to_model: fitting G with the named terms to the same files", file=sys.stderr, flush=True)
    sines = any(isinstance(r, Recording) for r in items)
    if sines or not isinstance(identified, IdentificationResult):
        fit = d.to_model(items)
    else:
        fit = d.to_model(items, start=identified)
    print(fit.summary(), file=sys.stderr)
    path = out / "model.json"
    save_model(fit, path)
    return path


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


def _detect_arg(text: str) -> dict[str, float]:
    """``--detect TERM=SIZE`` as ``{term: size}`` (the term and the size are checked by the planner)."""
    term, sep, size = text.partition("=")
    try:
        value = float(size)
    except ValueError:
        value = math.nan
    if not sep or not term.strip() or not math.isfinite(value):
        raise InvalidParameterError(
            f"--detect {text!r} must be TERM=SIZE with a finite size, e.g. sensor_lag=1e-3"
        )
    return {term.strip(): value}


def _cmd_plan(args: argparse.Namespace) -> int:
    from .planning import plan_experiment

    if args.out is not None:
        _check_out(args, inputs=[args.plant] if args.plant else [], what="--out file")
    prior = _prior_from_args(args)
    lab: dict[str, Any] = dict(
        band=(args.band[0], args.band[1]),
        max_amplitude=args.max_amplitude,
        noise_sd=args.noise,
        sample_rate=args.sample_rate,
        max_rate=args.max_rate,
        n_frequencies=args.frequencies,
        n_amplitudes=args.amplitudes,
        settle_periods=args.settle_periods,
        overhead=args.overhead,
        max_samples_per_period=args.max_samples_per_period,
        min_periods=args.min_periods,
        max_experiments=args.max_experiments,
    )
    plan: Any
    if args.detect is not None:
        from .planning import plan_detection

        more: dict[str, Any] = {"min_experiments": args.min_experiments, "seed": args.seed}
        if args.candidates is not None:
            more["candidates"] = args.candidates
        plan = plan_detection(
            prior, args.budget, _detect_arg(args.detect), alpha=args.diagnosis_alpha, **more, **lab
        )
    else:
        plan = plan_experiment(prior, args.budget, target=args.target, **lab)
    print(plan.summary())
    if args.out is not None:
        with _staged(args) as staged:
            staged.write_text(plan.to_json() + "\n", encoding="utf-8")
        print(f"wrote {args.out}")
    return 0


#: What each command runs.
_COMMANDS: dict[str, Callable[[argparse.Namespace], int]] = {
    "demo": _cmd_demo,
    "simulate": _cmd_simulate,
    "identify": _cmd_identify,
    "diagnose": _cmd_diagnose,
    "plan": _cmd_plan,
    "validate": cmd_validate,  # issue #20: bouc_wen_id._cli_validate
    "export": run_export,  # issue #21: model export (_cli_export)
    "diagnose-across": cmd_across,  # issue 18: the diagnosis across conditions (_cli_across)
}


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _fail(kind: str, exc: BaseException, command: str = "") -> int:
    print(f"error: {kind}: {flags_named(_one_line(str(exc)), command)}", file=sys.stderr)
    return 2


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Run the command line; every failure is one line on stderr, never a traceback.

    Exit status: 0 done, 2 refused (a bad argument, file or value: the line names it), 130 interrupted by
    Ctrl-C and 143 by SIGTERM (nothing was written), 1 an internal error (a bug: please report the line).
    """
    args = build_parser().parse_args(argv)
    previous = signal.getsignal(signal.SIGTERM)
    try:
        _output.terminate_on_sigterm()
    except ValueError:  # not the main thread: SIGTERM keeps its handler
        previous = None
    try:
        return _run(args)
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


def _show_warning(message: Any, category: type[Warning], *args: Any, **kwargs: Any) -> None:
    """A warning as one line on stderr (Python's own format adds its file, line and source line)."""
    print(f"warning: {category.__name__}: {_one_line(str(message))}", file=sys.stderr)


def _run(args: argparse.Namespace) -> int:
    try:
        # NumPy's floating-point warnings (an overflow on a value of 1e308) are not for a terminal: the
        # checks that follow name the value in one line.
        with one_blas_thread(), np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.showwarning = _show_warning
            # (errstate is per thread: the simulation's worker threads warn through the filter instead.)
            warnings.filterwarnings(
                "ignore", r"(overflow|invalid value|divide by zero) encountered", RuntimeWarning
            )
            return int(_COMMANDS[args.command](args))  # one_blas_thread: see bouc_wen_id._threads
    except BoucWenIdError as exc:
        return _fail(type(exc).__name__, exc, args.command)
    except KeyboardInterrupt:
        _pool.stop_all()
        print("interrupted: nothing was written", file=sys.stderr)
        return 130
    except _output.Terminated:
        _pool.stop_all()
        print("terminated (SIGTERM): nothing was written", file=sys.stderr)
        return _output.EXIT_TERMINATED
    except (ImportError, OSError) as exc:  # a missing extra (the line says which), an unreadable path
        return _fail(type(exc).__name__, exc)
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
