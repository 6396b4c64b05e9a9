"""The README's examples run as written, with their own numbers (issue 19: the planning example failed).

Every ```python block runs, in the README's order, in one namespace (a reader pastes them one after the
other); every ``bouc-wen-id`` line of a shell block runs in a fresh folder. What a user brings is made here,
by NumPy alone, not by the library's simulator: the lab arrays ``t, disp_mm, force_N`` (a Bouc-Wen
specimen integrated below, off its nominal frequency, with ramps and noise), the files ``test_rig.tdms`` and
``runs.h5``, the CSV folders ``lab/`` and ``data/``, ``plant.json`` and ``result.json``. The shell lines that
install or build (pip, maturin, cargo, scripts/*.sh) are listed in ``NOT_RUN`` with the reason; any other
line makes this test fail until it runs or is listed.
"""

from __future__ import annotations

import importlib
import json
import os
import re
import subprocess
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"

#: Shell lines not run here (by their start), and why.
NOT_RUN = {
    "bash scripts/demo.sh": "builds .venv and the Rust core, then runs `bouc-wen-id demo` (run below)",
    "bash scripts/test.sh": "the test runner that runs this test",
    "pip install": "installs the package (CI installs it that way before the tests)",
    "maturin build": "builds the wheel (CI's packaging step)",
    "cargo bench": "criterion benchmarks, not a test",
    ".venv/bin/python benches/bench_core.py": "a benchmark (needs numba)",
}


def _blocks() -> list[tuple[str, str, int]]:
    """``(language, code, line)`` of every fenced block."""
    text = README.read_text(encoding="utf-8")
    out = []
    for m in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.S | re.M):
        out.append((m.group(1), m.group(2), text[: m.start()].count("\n") + 1))
    return out


def _shell_commands(code: str) -> list[str]:
    """A block's command lines, continuations joined, comments dropped."""
    joined = re.sub(r"\\\n\s*", " ", code)
    return [ln.split("  #")[0].strip() for ln in joined.splitlines() if ln.strip()]


def _not_run(command: str) -> bool:
    return any(command.startswith(prefix) for prefix in NOT_RUN)


# --------------------------------------------------------------------------------------------------
# What a user brings, made with NumPy alone
# --------------------------------------------------------------------------------------------------


def _specimen(f_hz: float, seed: int, fs: float = 1000.0, steady: int = 12) -> tuple[Any, Any, Any]:
    """``t`` (s), displacement (mm), force (N) of a Bouc-Wen specimen (G = 1: a Wiener plant), driven at
    ``f_hz`` after 1 s idle and a 2-period ramp (explicit Euler, 20 substeps per sample)."""
    rng = np.random.default_rng(seed)
    n = int((1.0 + (steady + 4) / f_hz) * fs)
    t = np.arange(n) / fs
    env = np.clip((t - 1.0) * f_hz / 2.0, 0.0, 1.0) * np.clip((t[-1] - t) * f_hz / 2.0, 0.0, 1.0)
    x = 5.0 * env * np.sin(2 * np.pi * f_hz * t)
    a, beta, gamma, n_exp, sub = 30.0, 0.6, 0.3, 1.5, 20
    z = np.zeros(n)
    zk = 0.0
    for k in range(1, n):
        dx = (x[k] - x[k - 1]) / sub
        for _ in range(sub):
            zk += dx * (a - abs(zk) ** n_exp * (beta * np.sign(dx * zk) + gamma))
        z[k] = zk
    force = z + 0.05 * rng.standard_normal(n) + 1.5
    return t, x + 0.3, force


def _write_lab_csv(folder: Path) -> None:
    folder.mkdir()
    for i, f in enumerate((1.0, 2.0, 3.02)):
        _, x, force = _specimen(f, seed=i)
        data = np.column_stack([x, force])
        np.savetxt(folder / f"run_{i}.csv", data, delimiter=",", header="disp_mm,force_N", comments="")


def _write_tdms(path: Path) -> None:
    tdms: Any = importlib.import_module("nptdms")  # the [test] extra (as for the lab's own software)
    ChannelObject, GroupObject = tdms.ChannelObject, tdms.GroupObject
    with tdms.TdmsWriter(str(path)) as w:
        for group, f in (("Run 1", 2.0), ("Run 3", 3.02)):
            _, x, force = _specimen(f, seed=7)
            props = {"wf_increment": 0.001}
            w.write_segment(
                [
                    GroupObject(group),
                    ChannelObject(group, "Displacement", x, properties={**props, "unit_string": "mm"}),
                    ChannelObject(group, "Force", force, properties={**props, "unit_string": "N"}),
                ]
            )


def _write_h5(path: Path) -> None:
    h5py: Any = importlib.import_module("h5py")
    with h5py.File(path, "w") as h:
        g = h.create_group("run_a")
        g.attrs["sample_rate"] = 1000.0
        _, x, force = _specimen(1.5, seed=9)
        g["Displacement"] = x
        g["Force"] = force


def _bring(code: str, where: Path, scope: dict[str, Any]) -> None:
    """Put in place what the block reads and the user brings."""
    if "bw.Measurement(t, disp_mm, force_N" in code:
        scope["t"], scope["disp_mm"], scope["force_N"] = _specimen(3.02, seed=3)
    if "test_rig.tdms" in code:
        _write_tdms(where / "test_rig.tdms")
    if "runs.h5" in code:
        _write_h5(where / "runs.h5")
    if "lab/" in code:
        _write_lab_csv(where / "lab")
    if "data/*.csv" in code:
        plan = bw.SinePlan([1.5, 3.0, 6.0], 1.0, settle_periods=10, periods=8, samples_per_period=128,
                           noise_sd=0.004, seed=2)  # fmt: skip
        plant = bw.WienerPlant(bw.TransferFunction([6.0], [1.0, 6.0]), bw.BoucWen(1.0, 0.3, 1.5),
                               terms=(bw.terms.Viscous(0.03),))  # fmt: skip
        bw.save_recordings(where / "data", bw.simulate(plant, plan))
    if "--plant plant.json" in code:
        (where / "plant.json").write_text(json.dumps(bw.demo_plant().to_dict()))
    if "--plant result.json" in code:
        plan = bw.SinePlan(
            [2.0, 5.0], 1.0, settle_periods=10, periods=8, samples_per_period=128, noise_sd=0.004
        )
        (where / "result.json").write_text(bw.identify(bw.simulate(bw.demo_plant(), plan)).to_json())


# --------------------------------------------------------------------------------------------------
# The tests
# --------------------------------------------------------------------------------------------------


def test_every_block_is_python_shell_or_the_csv_format() -> None:
    blocks = _blocks()
    assert len(blocks) >= 10
    for lang, code, line in blocks:
        if lang in ("python", "bash"):
            continue
        assert lang == "", (line, lang)
        # The one unlabelled block that is not a command is the CSV header's description.
        assert code.startswith("bouc-wen-id ") or code.startswith("# format:"), (line, code[:40])


def test_the_python_examples_run_in_order_as_written(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    scope: dict[str, Any] = {"__name__": "readme"}
    ran = []
    for lang, code, line in _blocks():
        if lang != "python":
            continue
        _bring(code, tmp_path, scope)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # the examples print their warnings; they are not failures
            exec(compile(code, f"README.md:{line}", "exec"), scope)  # noqa: S102 - the README's own code
        ran.append(line)
        if "bw.plan_experiment(" in code:
            planned = scope["plan"]  # (a later block names its own plan)
    assert len(ran) >= 8
    # What the examples promise: the quick start's fit near its truth (alpha-normalised: 1.6 / 2, 0.4 / 2).
    quick = scope["result"]
    assert isinstance(quick, bw.IdentificationResult)
    assert (tmp_path / "loops.png").is_file() and (tmp_path / "bode.png").is_file()
    d = scope["d"]
    assert d.verdict and (tmp_path / "diag" / "report.html").is_file()
    assert "Identified model" in (tmp_path / "diag" / "report.html").read_text()
    assert scope["found"].periods, "the lab record's steady stretch was found"
    assert planned.total_time <= planned.budget
    for e in planned.experiments:  # the lab's 100 Hz kept (or an integer fraction of it)
        assert 100.0 / e.sample_rate == pytest.approx(round(100.0 / e.sample_rate), rel=1e-12)
    assert len(scope["runs"]) == 2 and len(scope["one"]) == 1


def _shell_blocks() -> list[tuple[int, list[str]]]:
    out = []
    for lang, code, line in _blocks():
        if lang == "bash" or (lang == "" and code.startswith("bouc-wen-id ")):
            out.append((line, _shell_commands(code)))
    return out


def test_every_shell_line_is_run_or_listed() -> None:
    for line, commands in _shell_blocks():
        for c in commands:
            assert c.startswith("bouc-wen-id ") or _not_run(c), (
                f"README.md:{line}: {c!r} is neither run nor listed"
            )


@pytest.mark.parametrize(
    "block", [line for line, cmds in _shell_blocks() if any(not _not_run(c) for c in cmds)]
)
def test_the_shell_examples_run_as_written(block: int, tmp_path: Path) -> None:
    commands = dict(_shell_blocks())[block]
    code = "\n".join(c for c in commands if not _not_run(c))
    _bring(code, tmp_path, {})
    env = dict(os.environ, MPLBACKEND="Agg")
    for command in code.splitlines():
        script = f'bouc-wen-id() {{ "{sys.executable}" -m bouc_wen_id "$@"; }}\n{command}\n'
        proc = subprocess.run(["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True, text=True,
                              timeout=900)  # fmt: skip
        assert proc.returncode == 0, (
            f"README.md:{block}: {command}\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}"
        )
        out = re.search(r"--out (\S+)", command)
        if out is not None and "--help" not in command:
            assert (tmp_path / out.group(1)).exists(), command
