"""The ``bouc-wen-id`` argument parser: a sub-parser per command, and the checks of each option's text.

Kept apart from :mod:`bouc_wen_id.cli` (which runs the commands) so that each reads on its own; a library
error's message is put in the command line's words here too (:func:`flags_named`).
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any, NoReturn, Optional, Union

from . import _pool
from ._cli_across import add_across_parser
from ._cli_export import add_export_parser
from ._cli_validate import add_validate_parser
from .demo import DEMO_FREQUENCIES
from .errors import InvalidParameterError
from .terms import DIAGNOSIS_CANDIDATES
from .validation import real_number

__all__ = ["build_parser", "flags_named"]

#: The highest sampling rate ``plan --sample-rate`` takes (1 THz, beyond any DAQ): 1e308 overflowed the
#: planner's sample counts.
MAX_RATE = 1e12

#: diagnose's candidates: the steady-loop terms and degradation (diagnosis.run.ALL_CANDIDATES, kept here
#: so that the CLI does not import the diagnosis to build its parser).
DIAG_CANDIDATES = DIAGNOSIS_CANDIDATES


# --------------------------------------------------------------------------------------------------
# The parser: one function per command
# --------------------------------------------------------------------------------------------------


class _Parser(argparse.ArgumentParser):
    """An argument error is one line and exit status 2 (argparse's usage block is on ``--help``)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (usage: {self.prog} --help)\n")


#: The largest integer any count flag takes (a 400-digit --settle-periods overflowed the planner's floats).
MAX_COUNT = (1 << 31) - 1


def _integer(low: int, high: Optional[int] = MAX_COUNT) -> Callable[[str], int]:
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"{value} must be >= {low}")
        if high is not None and value > high:
            raise argparse.ArgumentTypeError(f"{value} must be <= {high}")
        return value

    return parse


def _real(
    positive: bool = False, nonnegative: bool = False, high: float = math.inf
) -> Callable[[str], float]:
    def parse(text: str) -> float:
        try:
            value = real_number(repr(text), float(text))
        except (ValueError, OverflowError):  # float() itself, or real_number's named errors
            raise argparse.ArgumentTypeError(f"{text!r} is not a finite number") from None
        if positive and not value > 0:
            raise argparse.ArgumentTypeError(f"{value:g} must be > 0")
        if nonnegative and not value >= 0:
            raise argparse.ArgumentTypeError(f"{value:g} must be >= 0")
        if not value <= high:
            raise argparse.ArgumentTypeError(f"{value:g} must be <= {high:g}")
        return value

    return parse


def _workers_flag(text: str) -> int:
    """``--workers``: an integer in [1, the CPU count] (a million workers would fork a million processes)."""
    try:
        return _pool.check_workers(_integer(1)(text), "")
    except InvalidParameterError as exc:
        raise argparse.ArgumentTypeError(str(exc).strip(" =")) from None


def _harmonics(text: str) -> Union[str, int]:
    if text in ("auto", "all"):
        return text
    if not text.strip().isdigit():
        raise argparse.ArgumentTypeError(f"{text!r} is not auto, all or an integer")
    return _integer(1, 1 << 20)(text)


def _candidates(text: str) -> list[str]:
    names = [c.strip() for c in text.split(",") if c.strip()]
    bad = [c for c in names if c not in DIAG_CANDIDATES]
    if not names or bad or len(set(names)) != len(names):
        raise argparse.ArgumentTypeError(
            f"{text!r}: give distinct names among {','.join(DIAG_CANDIDATES)}, separated by commas"
        )
    return names


def _level(text: str) -> float:
    value = _real(positive=True)(text)
    if not value < 1:
        raise argparse.ArgumentTypeError(f"{value:g} must lie in (0, 1)")
    return value


def _add_overwrite(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--overwrite",
        action="store_true",
        help="replace an --out that holds a previous report of bouc-wen-id (whole, never mixed; never a "
        "file or a folder of other files)",
    )


def _add_inputs(p: argparse.ArgumentParser) -> None:
    """The files of ``identify`` and ``diagnose``, and how to read them."""
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
        "--skiprows",
        type=_integer(0),
        default=None,
        metavar="N",
        help="text files: lines before the column names (found by themselves when left out)",
    )


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
    p.add_argument(
        "--bode-units",
        choices=("linear", "dB"),
        default="linear",
        help="bode.png: linear (default: |G| on a log axis against omega in rad/s, the units of every "
        "printed number) or dB (20 log10 |G| against f in Hz); the phase in degrees, unwrapped, in both",
    )


def _add_demo_parser(sub: Any) -> None:
    p = sub.add_parser("demo", help="simulate the built-in plant and identify it")
    p.add_argument("--samples-per-period", type=_integer(8), default=1024)
    p.add_argument("--periods-sim", type=_integer(1), default=40, help="periods simulated after settling")
    p.add_argument(
        "--noise", type=_real(nonnegative=True), default=0.005, help="output noise standard deviation"
    )
    p.add_argument("--seed", type=_integer(0, (1 << 63) - 1), default=2024)
    p.add_argument(
        "--compare",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="also run every method on the same recordings and print their errors",
    )
    p.add_argument(
        "--diagnosis",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="also diagnose the same plant with a hidden dashpot (report in OUT/diagnosis)",
    )
    _add_identify_options(p)


def _add_simulate_parser(sub: Any) -> None:
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
    p.add_argument("--seed", type=_integer(0, (1 << 63) - 1), default=2024)
    p.add_argument("--backend", choices=("rust", "numpy"), default="rust")


def _add_identify_parser(sub: Any) -> None:
    p = sub.add_parser(
        "identify",
        help="identify from files (.csv, .npz, .mat, .tdms, .h5) or folders: simulated recordings or lab "
        "measurements",
        description="Identify from recordings (U and omega known) or lab measurements (any sampling rate: "
        "the input's frequency and amplitude are estimated, the steady stretches found and averaged).",
    )
    _add_inputs(p)
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
        type=_workers_flag,
        default=None,
        help="processes preparing the files and drawing the figures, at most the CPU count (default: one "
        "per usable core; 1: all in this process)",
    )
    _add_identify_options(p)


def _add_diagnose_parser(sub: Any) -> None:
    p = sub.add_parser(
        "diagnose",
        help="diagnose what the model leaves out: where, which physics, and the held-out proof",
        description="Fit the plain model and the library's candidate terms jointly; name a term only when "
        "it passes a nested F-test (Bonferroni over the candidates), explains a material share of the misfit "
        "and improves the fit on held-out experiments. The verdict comes first.",
    )
    _add_inputs(p)
    p.add_argument(
        "--candidates",
        type=_candidates,
        default=None,
        help="comma-separated terms to try (default: all of " + ", ".join(DIAG_CANDIDATES) + ")",
    )
    p.add_argument("--alpha", type=_level, default=0.05, help="false-alarm level per step (default 0.05)")
    p.add_argument("--no-held-out", action="store_true", help="skip the held-out check (faster, weaker)")
    p.add_argument(
        "--no-stability",
        action="store_true",
        help="skip refitting the final model on preprocessing variants (early/late stretch) to check that "
        "named values do not move (two final-model refits, about 0.2 s or 1-3 %% of a diagnosis; a moved "
        "value is then not said)",
    )
    p.add_argument("--no-figures", action="store_true", help="write the JSON and a text-only HTML page")
    p.add_argument(
        "--out",
        type=Path,
        default=None,
        help="report folder (default bouc_wen_id_diagnosis; none with --json alone)",
    )
    p.add_argument(
        "--json",
        type=Path,
        default=None,
        metavar="PATH",
        help="write the diagnosis JSON (bouc_wen_id.load_diagnosis reads it) to this new file, or '-' for "
        "stdout (the summary then goes to stderr); without --out no report folder is written",
    )
    p.add_argument(
        "--model",
        action="store_true",
        help="also fit the model the diagnosis describes (G with the named terms: Diagnosis.to_model) and "
        "write OUT/model.json, which export, validate and compensate take (compensate refuses by name the "
        "terms its inverse does not handle: Dahl friction, inertia on x, the series dashpot, play, ...)",
    )
    _add_overwrite(p)


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
        "--sample-rate",
        type=_real(positive=True, high=MAX_RATE),
        required=True,
        help="highest sampling rate, Hz",
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
    p.add_argument(
        "--detect",
        default=None,
        metavar="TERM=SIZE",
        help="plan to detect one term of this size instead (e.g. sensor_lag=1e-3, in the alpha-normalised "
        "model's units: the design with the best predicted chance that the diagnosis names it, reported with "
        "the power of its test; Dahl friction is not plannable: plan its coulomb or stiffness limit; "
        "--target is then not used)",
    )
    p.add_argument(
        "--diagnosis-alpha", type=_level, default=0.05, help="with --detect: the diagnosis's alpha (0.05)"
    )
    p.add_argument(
        "--min-experiments",
        type=_integer(1),
        default=3,
        help="with --detect: fewest experiments of the plan (3: the diagnosis names a term only if it also "
        "passes the held-out test across experiments, which 2 pass rarely and 1 cannot run)",
    )
    p.add_argument(
        "--candidates",
        type=_integer(1),
        default=None,
        help="with --detect: candidate terms sharing the diagnosis's targeted step (default: the diagnosis's "
        "own count on pure sines; one more where the inputs carry harmonics, the distortion term)",
    )
    p.add_argument(
        "--seed",
        type=_integer(0, (1 << 63) - 1),
        default=0,
        help="with --detect: seed of the predicted chance to name's draws (0; the same seed, the same plan)",
    )
    p.add_argument("--out", type=Path, default=None, help="write the plan as JSON to this file")
    _add_overwrite(p)


def build_parser() -> argparse.ArgumentParser:
    """The ``bouc-wen-id`` parser: a sub-parser per command (its name in ``command``)."""
    parser = _Parser(
        prog="bouc-wen-id",
        description="Identify Wiener systems with Bouc-Wen hysteresis from sine experiments.",
    )
    sub = parser.add_subparsers(dest="command", required=True)
    for add in (_add_demo_parser, _add_simulate_parser, _add_identify_parser, _add_diagnose_parser):
        add(sub)
    _add_plan_parser(sub)
    add_validate_parser(sub)  # issue #20: bouc_wen_id._cli_validate
    add_export_parser(sub)  # issue #21: model export (_cli_export)
    add_across_parser(sub)  # issue 18: the diagnosis across conditions (_cli_across)
    return parser


#: Python argument names that differ from the flag's (``plan_experiment(n_frequencies=...)`` is
#: ``--frequencies``; ``SinePlan(noise_sd=...)`` is ``--noise``).
_PYTHON_NAMES = {
    "plan": {"n_frequencies": "--frequencies", "n_amplitudes": "--amplitudes", "noise_sd": "--noise"},
    "simulate": {"noise_sd": "--noise", "amplitudes": "--amplitude"},
    "demo": {"noise_sd": "--noise", "periods": "--periods-sim"},
}


def flags_named(message: str, command: str) -> str:
    """The message of a library error in the words of the command line: ``min_periods`` -> ``--min-periods``,
    ``budget = 300 s`` -> ``--budget 300 s``.

    A Python name with an underscore is replaced wherever it stands; one without (``budget``, ``alpha``,
    ``periods``: also plain words) only where the message states its value (``name = value``).
    """
    sub = _subparser(command)
    names = dict(_PYTHON_NAMES.get(command, {}))
    for action in sub._actions if sub is not None else ():
        flags = [f for f in action.option_strings if f.startswith("--")]
        if flags:
            names.setdefault(action.dest, flags[0])
    for name, flag in names.items():
        if "_" in name:
            message = re.sub(rf"(?<![\w-]){re.escape(name)}\b", flag, message)
        else:
            message = re.sub(rf"(?<![\w-]){re.escape(name)} = ", f"{flag} ", message)
    return message


def _subparser(command: str) -> Optional[argparse.ArgumentParser]:
    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            found: Optional[argparse.ArgumentParser] = action.choices.get(command)
            return found
    return None  # pragma: no cover - every parser has its sub-parsers
