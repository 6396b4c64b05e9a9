"""Progress of ``diagnose``: quiet by default, stages on stderr with ``progress=True``, or a callback."""

from __future__ import annotations

import io
import math
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import terms as T
from bouc_wen_id.diagnosis.progress import StderrProgress

TWO_PI = 2.0 * math.pi


def _recs(seed: int = 5) -> list[bw.Recording]:
    """A first-order G, a hidden dashpot beside the loop, 1 % noise: the selection has a term to name."""
    lin = bw.TransferFunction([1.0], [0.1, 1.0])
    plant = bw.WienerPlant(lin, bw.BoucWen(0.6, 0.4, 2.0), terms=(T.Viscous(0.01),))
    om = np.repeat(TWO_PI * np.array([0.4, 1.2, 3.0]), 2)
    g, _ = lin.gain_phase(om)
    plan = bw.SinePlan(
        om,
        np.tile([0.7, 1.8], 3) / g,
        settle_periods=8,
        periods=10,
        samples_per_period=64,
        substeps=8,
        noise_sd=0.01,
        seed=seed,
    )
    return bw.simulate(plant, plan)


@pytest.fixture(scope="module")
def recs() -> list[bw.Recording]:
    return _recs()


def test_quiet_by_default_and_stages_in_order_through_a_callback(
    recs: list[bw.Recording], capsys: pytest.CaptureFixture[str]
) -> None:
    quiet = bw.diagnose(recs, candidates=["offset", "viscous"])
    out, err = capsys.readouterr()
    assert out == "" and err == "", "the library prints nothing unless asked"
    seen: list[tuple[str, int, int]] = []
    d = bw.diagnose(recs, candidates=["offset", "viscous"], progress=lambda *a: seen.append(a))
    assert d.verdict == quiet.verdict, "reporting progress changes nothing in the diagnosis"
    stages = [s for s, _, _ in seen]
    assert stages[0].startswith("preparing") and stages[-1] == "done"
    assert stages.index("fitting the plain model") < stages.index("step 1: fitting candidate offset")
    # Step 1 fits both candidates, counted 0 of 2 then 1 of 2; later steps only the remaining one.
    step1 = [(s, k, n) for s, k, n in seen if s.startswith("step 1:")]
    assert step1 == [("step 1: fitting candidate offset", 0, 2), ("step 1: fitting candidate viscous", 1, 2)]
    assert len(d.steps) >= 1
    assert sum(1 for s in stages if s.startswith("step ")) == sum(len(st.trials) for st in d.steps)
    assert all(0 <= k < n or s == "done" for s, k, n in seen)
    assert seen[-1] == ("done", 1, 1)


def test_progress_true_writes_lines_on_stderr_and_a_bar_on_a_terminal(
    recs: list[bw.Recording], capsys: pytest.CaptureFixture[str]
) -> None:
    bw.diagnose(recs[:4], candidates=["offset"], progress=True)
    out, err = capsys.readouterr()
    assert out == ""
    lines = err.splitlines()
    assert lines[0].startswith("diagnose:") and "preparing" in lines[0]
    assert lines[-1].startswith("diagnose:") and lines[-1].endswith("done")
    assert "\r" not in err, "no bar redrawn in a log (stderr is not a terminal here)"
    term = io.StringIO()
    bar = StderrProgress(term, tty=True)
    bar("step 1: fitting candidate offset", 1, 4)
    bar("done", 1, 1)
    text = term.getvalue()
    assert text.startswith("\rdiagnose [#####---------------]") and "(1/4)" in text
    assert "[####################]" in text and text.endswith("\n")


@pytest.mark.parametrize("bad", ["yes", 3])
def test_bad_progress_is_a_named_error(recs: list[bw.Recording], bad: Any) -> None:
    with pytest.raises(bw.InvalidParameterError, match="progress"):
        bw.diagnose(recs[:2], candidates=["offset"], progress=bad)
