"""The diagnosis bench's unabsorbed column (benches/diagnosis.py, ``unabsorbed``): what of an effect the plain
model cannot absorb, in averaged-noise sd, on records of ``benches/generator.py`` (its own G and RK4)."""

from __future__ import annotations

import importlib
import math
import sys
import warnings
from pathlib import Path
from typing import Any

import bouc_wen_id as bw

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benches"))
gen: Any = importlib.import_module("generator")
bench: Any = importlib.import_module("diagnosis")


def _diagnose(recordings: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recordings)


def test_the_plain_model_absorbs_a_plain_plant() -> None:
    """No effect: the plain model refitted to the noise-free record leaves (almost) nothing."""
    p = gen.make_plant(401)
    y = gen.run(p, gen.Effect())[0]
    d = _diagnose(gen.recordings(p, y, 401))
    got, lim, glob = bench.unabsorbed(d, gen.recordings(p, y, 401, noise_sd=0.0))
    assert 0.0 <= got < 0.1 * lim
    assert 0.0 < lim < glob  # one parameter taking it all is seen before the global test sees it


def test_an_outside_effect_is_partly_absorbed_and_a_misaligned_record_is_refused() -> None:
    """A Prandtl-Ishlinskii loop on u at 10 noise sd: the plain model takes up part of it (unabsorbed below
    the raw size) and not all of it (above the one-term limit: the bench's pi_u rows are detectable)."""
    case = gen.make_case("outside", "pi_u", "", 10.0, 402)
    d = _diagnose(case.recordings)
    clean = bench._clean_recordings("outside", "pi_u", "", 10.0, 402)
    got, lim, _glob = bench.unabsorbed(d, clean)
    assert lim < got < case.achieved
    # A record whose experiments do not line up with the diagnosis's is not measured.
    assert all(math.isnan(v) for v in bench.unabsorbed(d, clean[:-1]))
