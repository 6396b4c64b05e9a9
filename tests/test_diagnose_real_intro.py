"""The real-data page says how loaded the machine was from the load measured before the run started."""

from __future__ import annotations

import importlib.util
import math
import sys
from pathlib import Path
from types import ModuleType

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _study() -> ModuleType:
    spec = importlib.util.spec_from_file_location("diagnose_real", ROOT / "studies" / "diagnose_real.py")
    assert spec is not None and spec.loader is not None, "cannot load studies/diagnose_real.py"
    mod = importlib.util.module_from_spec(spec)
    sys.modules["diagnose_real"] = mod
    spec.loader.exec_module(mod)
    return mod


@pytest.mark.parametrize(
    ("load", "says", "never"),
    [(0.6, "quiet machine", "loaded"), (4.8, "loaded machine", "quiet"), (math.nan, "unknown", "quiet")],
)
def test_page_intro_says_quiet_only_when_the_machine_was(load: float, says: str, never: str) -> None:
    """A run started quiet must not be called loaded (the page said so at load 0.6), nor the reverse."""
    study = _study()
    timing = {"wall": 57.0, "diagnoses": 51.0, "figures": 2.0, "stability": 0.0, "load_start": load}
    intro = study.markdown([], timing, command="x", commit="abc").split("| data set |")[0]
    assert says in intro
    assert never not in intro
