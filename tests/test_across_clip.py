"""Clipped outputs at one condition are left out of the joint fit across conditions (review 36b, 4).

Viscous damping on u at three conditions, the slowest experiment's output clipped at the middle one: the
clipped experiment stayed in the joint fit, its flat tops failed the term's law and the verdict said
"nothing named" at every condition, the two clean ones too. Now a condition's clipped experiments are left
out before it is prepared when enough remain (law.MIN_CLEAN), its own diagnosis (fitted with them) is not
reused, and the verdict says which were left out and where; with too few left all stay.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path
from typing import Any

from bouc_wen_id.diagnosis import across_clip
from bouc_wen_id.diagnosis.law import MIN_CLEAN

sys.path.insert(0, str(Path(__file__).parent))
output_clipped: Any = importlib.import_module("test_clean_value")._output_clipped


def test_the_clipped_experiments_are_left_out_where_enough_remain() -> None:
    clean, bad = output_clipped(0.0), output_clipped(0.92)
    own = ["own 0", "own 1"]
    gs, owns, checks, left = across_clip.unclipped([clean, bad], own, ["check 0", "check 1"], ["0", "0.5"])
    assert left == {"0.5": ["recording 3", "recording 4"]}, left
    assert len(gs[0]) == len(clean) and len(gs[1]) == len(bad) - 2, [len(g) for g in gs]
    assert all(r is not bad[3] and r is not bad[4] for r in gs[1])
    assert (
        owns == ["own 0", None] and checks == ["check 0", None] and own == ["own 0", "own 1"]
    )  # nothing the user gave is modified
    said = across_clip.text(left)
    assert "at 0.5, the measured output of recording 3, recording 4 looks clipped" in said, said
    assert "left out of the joint fit" in said, said


def test_with_too_few_left_every_experiment_stays() -> None:
    bad = output_clipped(0.92)
    few = [bad[i] for i in range(len(bad)) if i in (3, 4) or i < MIN_CLEAN - 1]  # one short of MIN_CLEAN
    gs, owns, checks, left = across_clip.unclipped([few, output_clipped(0.0)], ["a", "b"], [1, 2], ["0", "1"])
    assert left == {} and len(gs[0]) == len(few) and owns == ["a", "b"] and checks == [1, 2]
    assert across_clip.text(left) == ""
