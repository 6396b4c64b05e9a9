"""A property-based sweep of the command line's surface (issue 19): every flag of every command given a
hostile value (negative, zero, NaN, infinities, huge, empty, blank, unicode, long paths, a NUL byte) ends
in a result (exit 0) or one named line (exit 2), never a raw traceback, an "internal error" or a hang.

``python tests/test_cli_hostile.py`` runs the whole sweep (every flag x every value, once each) and prints
the counts; the tests below draw from it with hypothesis (seeded by hypothesis' database-free default) and
run the flags that are cheap exhaustively.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import signal
import sys
import tempfile
import warnings
from collections import Counter
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import pytest
from bouc_wen_id import cli
from bouc_wen_id._cli_parser import build_parser
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

#: Values a hostile or careless user types.
VALUES = (
    "-1",
    "0",
    "-0",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "1e-308",
    "1e400",
    "9" * 400,
    "",
    "   ",
    "0x10",
    "1_000",
    "\u0661\u0662",  # Arabic-Indic digits: int() reads them
    "données/ü",
    "a" * 300,  # longer than a file name may be
    "d/" * 1500,  # longer than a path may be
    "x\x00y",
    "--",
)
#: The longest a call may take before it counts as a hang (a loaded machine gets a margin).
HANG_SECONDS = 120.0
#: Flags left out: --overwrite replaces a report, and a hostile --out with it is not for a sweep to try;
#: --scheduler dials the network.
SKIP = {"--overwrite", "--scheduler", "--help"}


def _base(command: str, data: Path) -> list[str]:
    """A valid, cheap call of ``command`` (the sweep replaces one value of it)."""
    return {
        "plan": ["plan", "--budget", "300", "--band", "1", "10", "--max-amplitude", "1", "--noise", "0.05"]
        + ["--sample-rate", "100", "--frequencies", "4", "--amplitudes", "2", "--out", "plan.json"],
        "simulate": ["simulate", "--out", "recs", "--frequencies", "1", "2", "--samples-per-period", "64"]
        + ["--periods", "4", "--settle-periods", "2"],
        "identify": ["identify", str(data), "--out", "rep", "--no-figures", "--workers", "1"],
        "diagnose": ["diagnose", str(data), "--out", "diag", "--no-figures", "--no-held-out"]
        + ["--candidates", "offset"],
        "demo": ["demo", "--no-compare", "--no-diagnosis", "--no-figures", "--samples-per-period", "64"]
        + ["--periods-sim", "4", "--settle-periods", "2", "--out", "demo"],
    }[command]


def _flags(command: str) -> list[tuple[str, int]]:
    """Every option of ``command`` that takes values, with how many; ``PATHS`` for the positional files."""
    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            sub = action.choices[command]
    out = []
    for a in sub._actions:
        if not a.option_strings:
            if a.dest == "paths":
                out.append(("PATHS", 1))
            continue
        flag = a.option_strings[-1]
        if flag in SKIP or a.nargs == 0:
            continue
        n = 2 if a.nargs == 2 else 1
        out.append((flag, n))
    return out


def argv_with(command: str, flag: str, value: str, data: Path) -> list[str]:
    """The cheap call with ``flag``'s (first) value replaced by ``value`` (the flag added when absent)."""
    argv = _base(command, data)
    if flag == "PATHS":
        argv[1] = value
        return argv
    if flag in argv:
        argv[argv.index(flag) + 1] = value
        return argv
    n = dict(_flags(command))[flag]
    return [*argv, flag, value, *(["1"] * (n - 1))]


class _Hang(BaseException):
    """The alarm: a call that runs past HANG_SECONDS (not an Exception, so main cannot swallow it)."""


@contextlib.contextmanager
def _alarm(seconds: float) -> Iterator[None]:
    def ring(signum: int, frame: Any) -> None:
        raise _Hang

    previous = signal.signal(signal.SIGALRM, ring)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def outcome(argv: list[str]) -> tuple[str, str]:
    """``(kind, detail)``: ``done`` (exit 0), ``named`` (exit 2, one ``error:`` line), ``raw`` (anything
    else: a traceback, an internal error, another status, several lines) or ``hang``."""
    err, out = io.StringIO(), io.StringIO()
    with warnings.catch_warnings():
        return _classify(argv, err, out)


def _classify(argv: list[str], err: io.StringIO, out: io.StringIO) -> tuple[str, str]:
    try:
        with _alarm(HANG_SECONDS), contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            # As a terminal shows warnings (printed, not raised as pytest's filter would): a stray one
            # before an error line makes the outcome "raw".
            warnings.simplefilter("default")
            try:
                code = cli.main(argv)
            except SystemExit as exc:  # the parser's refusal
                code = exc.code if isinstance(exc.code, int) else 1
    except _Hang:
        return "hang", " ".join(argv)[:200]
    except BaseException as exc:  # noqa: BLE001 - what escaped main is the finding
        return "raw", f"{type(exc).__name__}: {exc}"[:300]
    text = err.getvalue().strip()
    # Progress lines and one-line warnings (cli prints each as "warning: Category: message") aside.
    lines = [
        ln for ln in text.splitlines() if not ln.startswith(("diagnose:", "[", "identify:", "warning: "))
    ]
    if code == 0:
        return "done", ""
    if code == 2 and len(lines) == 1 and ("error:" in lines[0]) and "Traceback" not in text:
        return "named", lines[0][:200]
    return "raw", f"exit {code}: {text[-300:]}"


@pytest.fixture(scope="module")
def data(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three short recordings of the demo plant, written as the CLI writes them."""
    folder = tmp_path_factory.mktemp("hostile") / "data"
    plan = bw.SinePlan(
        [2.0, 4.0, 6.0], 1.0, settle_periods=6, periods=6, samples_per_period=64, noise_sd=0.01
    )
    bw.save_recordings(folder, bw.simulate(bw.demo_plant(), plan))
    return folder


CHEAP = ("plan", "simulate", "identify")
SURFACE = [(c, f) for c in ("plan", "simulate", "identify", "diagnose", "demo") for f, _ in _flags(c)]


@pytest.mark.parametrize("command", CHEAP)
def test_every_flag_of_the_cheap_commands_with_every_hostile_value(
    command: str, data: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    found: Counter[str] = Counter()
    bad = []
    for flag, _ in _flags(command):
        for value in VALUES:
            run = tmp_path / f"{len(found) + sum(found.values())}"
            run.mkdir()
            monkeypatch.chdir(run)
            kind, detail = outcome(argv_with(command, flag, value, data))
            found[kind] += 1
            if kind in ("raw", "hang"):
                bad.append((flag, value[:20], detail))
    assert not bad, bad
    assert found["named"] > 0 and found["done"] > 0, found


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(which=st.sampled_from([s for s in SURFACE if s[0] not in CHEAP]), value=st.sampled_from(VALUES))
def test_the_costly_commands_with_hostile_values(
    which: tuple[str, str], value: str, data: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    command, flag = which
    with tempfile.TemporaryDirectory(dir=tmp_path) as run:
        monkeypatch.chdir(run)
        kind, detail = outcome(argv_with(command, flag, value, data))
    assert kind in ("done", "named"), (command, flag, value[:20], detail)


def main() -> int:
    """The whole sweep, once each, with the counts per command (see the module docstring)."""
    with tempfile.TemporaryDirectory() as root:
        base = Path(root)
        plan = bw.SinePlan(
            [2.0, 4.0, 6.0], 1.0, settle_periods=6, periods=6, samples_per_period=64, noise_sd=0.01
        )
        bw.save_recordings(base / "data", bw.simulate(bw.demo_plant(), plan))
        total: Counter[str] = Counter()
        findings = []
        for command in ("plan", "simulate", "identify", "diagnose", "demo"):
            counts: Counter[str] = Counter()
            for flag, _ in _flags(command):
                for value in VALUES:
                    run = Path(tempfile.mkdtemp(dir=root))
                    os.chdir(run)
                    kind, detail = outcome(argv_with(command, flag, value, base / "data"))
                    counts[kind] += 1
                    if kind in ("raw", "hang"):
                        findings.append(f"{command} {flag} {value[:20]!r}: {kind}: {detail}")
            os.chdir(root)
            total += counts
            print(f"{command:<9} " + "  ".join(f"{k} {counts[k]}" for k in ("done", "named", "raw", "hang")))
        print(f"{'all':<9} " + "  ".join(f"{k} {total[k]}" for k in ("done", "named", "raw", "hang")))
        for f in findings:
            print(f)
        return 1 if findings else 0


if __name__ == "__main__":
    sys.exit(main())
