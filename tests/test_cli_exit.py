"""Every exit status the README documents, each from a real ``bouc-wen-id`` process: 0 done, 2 refused (a
bad argument or a named error, one line naming the flag), 130 Ctrl-C, 143 SIGTERM (nothing written in
either case), 1 an internal error (one line, "please report it")."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
ENV = dict(os.environ, MPLBACKEND="Agg")
#: About a minute of work inside the core (one experiment of 700 000 samples x 1000 RK4 substeps), which
#: polls for signals.
LONG = ["simulate", "--frequencies", "1", "--samples-per-period", "10000", "--substeps", "1000"]
PLAN = ["plan", "--budget", "300", "--band", "1", "10", "--max-amplitude", "1", "--noise", "0.05"]
PLAN += ["--sample-rate", "100"]


def _cli(args: list[str]) -> subprocess.Popen[str]:
    cmd = [sys.executable, "-m", "bouc_wen_id", *args]
    return subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=ENV)


def _catching_sigterm(pid: int) -> bool:
    """Whether the process has its own SIGTERM handler (installed by ``cli.main``): it is in the command."""
    status = Path(f"/proc/{pid}/status").read_text()
    caught = int(re.search(r"^SigCgt:\s*([0-9a-f]+)", status, re.M).group(1), 16)  # type: ignore[union-attr]
    return bool(caught >> (signal.SIGTERM - 1) & 1)


def _started(proc: subprocess.Popen[str], timeout: float = 120.0) -> None:
    """Wait until the command runs (its handlers are set) and is at work, not still importing: a signal
    sent before then would meet Python's defaults, not the command line's (a loaded machine takes seconds to
    import)."""
    if not Path(f"/proc/{proc.pid}/status").exists():  # pragma: no cover - not Linux
        time.sleep(5.0)
        return
    end = time.monotonic() + timeout
    while not _catching_sigterm(proc.pid):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < end, "the command never started"
        time.sleep(0.05)
    time.sleep(0.5)  # inside the simulation by now


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_the_readme_documents_these_codes() -> None:
    text = " ".join(README.read_text(encoding="utf-8").split())
    stated = text[text.index("Exit status:") :][:400]
    for code, what in (("0", "success"), ("2", "named error"), ("130", "Ctrl-C"), ("143", "SIGTERM")):
        assert f"{code} on {what}" in stated or f"{code} on a {what}" in stated, stated
    assert "1 on an internal error" in stated


def test_exit_0_when_done(tmp_path: Path) -> None:
    proc = _cli([*PLAN, "--out", str(tmp_path / "plan.json")])
    out, err = proc.communicate(timeout=300)
    assert proc.returncode == 0, err
    assert (tmp_path / "plan.json").is_file() and "wrote" in out


@pytest.mark.parametrize(
    ("args", "named"),
    [
        (["plan", "--budget", "-3"], "--budget"),  # the parser's refusal
        (["identify", "no/such/folder", "--out", "r"], "FileFormatError"),  # a named library error
        ([*PLAN[:-2], "--sample-rate", "nan"], "--sample-rate"),
    ],
)
def test_exit_2_when_refused_with_one_line_naming_it(tmp_path: Path, args: list[str], named: str) -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "bouc_wen_id", *args],
        capture_output=True,
        text=True,
        env=ENV,
        cwd=tmp_path,
        timeout=300,
    )
    assert proc.returncode == 2, proc.stderr
    assert named in _one_line(proc.stderr)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("sig", "code", "said"), [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")]
)
def test_a_signal_exits_with_its_code_and_writes_nothing(
    tmp_path: Path, sig: signal.Signals, code: int, said: str
) -> None:
    proc = _cli([*LONG, "--out", str(tmp_path / "R")])
    _started(proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == code, err
    assert _one_line(err).startswith(said)
    assert list(tmp_path.iterdir()) == []


def test_exit_1_on_an_internal_error_with_one_line(tmp_path: Path) -> None:
    """A bug (here: planted) reaches the user as one line and status 1, never a traceback."""
    code = textwrap.dedent(
        f"""
        import sys
        from bouc_wen_id import cli
        def broken(*args, **kwargs):
            raise KeyError("a planted bug")
        cli.simulate = broken
        sys.exit(cli.main([*{LONG[:3]!r}, "--samples-per-period", "64", "--out", {str(tmp_path / "R")!r}]))
        """
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=ENV, timeout=300)
    assert proc.returncode == 1, proc.stderr
    line = _one_line(proc.stderr)
    assert line.startswith("internal error: KeyError:") and "please report" in line
    assert list(tmp_path.iterdir()) == []
