"""The law test on a set whose some inputs are not sines (select.law_rows; blind design ``clipped``).

The model's latent ``x`` is a sine; where the measured input clips, the true ``x`` carries the input's
harmonics through G and a term's value fitted on that experiment takes them up, so "one value for all" failed
on the true term: blind ``coulomb:10:0:clipped`` and ``coulomb:30:0:clipped`` (seed 2026) were
"unexplained" with dry friction's law at p = 5e-6 and 2.8e-7 (share 0.90 and 0.87), ``play:10:0:clipped``
likewise. The law now compares the experiments whose input is a sine, when two or more have one.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from bouc_wen_id.augmented import AugExperiment
from bouc_wen_id.diagnosis import select

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
blind: Any = importlib.import_module("blind")


def _exp(waveform: Any) -> AugExperiment:
    return AugExperiment(
        ybar=np.zeros(16), amplitude=1.0, frequency=1.0, grid_phase=0.0, weight=1.0, source="r",
        waveform=np.asarray(waveform, dtype=np.float64),
    )  # fmt: skip


def test_law_rows_leave_out_the_inputs_that_are_not_sines() -> None:
    clean, clipped = _exp([]), _exp([0.0, 0.0, 0.01, 0.0])
    assert list(select.law_rows([clean, clipped, clean, clipped, clean], "coulomb")) == [0, 2, 4]
    # every experiment when all inputs are sines, when fewer than three are (review 32: two clean ones
    # passed a false series dashpot and a play on outside physics), and for the input's own term
    assert list(select.law_rows([clean, clipped, clean, clipped], "coulomb")) == [0, 1, 2, 3]
    assert list(select.law_rows([clean, clean], "coulomb")) == [0, 1]
    assert list(select.law_rows([clean, clipped, clipped], "coulomb")) == [0, 1, 2]
    assert list(select.law_rows([clean, clipped, clean], "distortion")) == [0, 1, 2]


@pytest.mark.parametrize("key", ["coulomb:10:0:clipped", "play:10:0:clipped"])
def test_a_blind_clipped_library_term_is_named(key: str) -> None:
    eff, size, k, dz = key.split(":")
    tag = (blind.LIBRARY + blind.OUTSIDE + ("null",)).index(eff)
    sd = int(np.random.SeedSequence([2026, tag, int(size), int(k)]).generate_state(1)[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rec = blind.run_case(blind.Case(eff, float(size), int(k), sd, None, blind.DRIFT, dz))
    assert rec["category"] == "right", rec["verdict"]
