"""An "adequate" headline whose DC was taken out says that an output offset was not tested (review 45).

Review 45's ``offset-10-C-1`` (an output offset of 2.4 noise sd under a drifting zero) read "adequate: the
plain Wiener-Bouc-Wen model fits at the noise floor"; only a detail said that the zero drifts and an offset
cannot be told from it. The headline now carries that caveat (diagnosis/dc_untested.py), and a record whose
DC was used keeps its headline.

Data: tests/wiener_sim.py (RK4 on a resonant G's two states and w together, a pure delay on the drive), not
the library's simulator: an output offset of 3 noise sd, and a straight line of 3 noise sd from the first
sample to the last added to each recording, its sign per recording.
"""

from __future__ import annotations

import warnings
from dataclasses import replace
from typing import Any

import bouc_wen_id as bw
import numpy as np
from bouc_wen_id.diagnosis import dc_untested, gate, zero_drift
from wiener_sim import recordings

#: The caveat's opening words in the headline.
CAVEAT = "an output offset cannot be tested"


def _drifting(seed: int, offset_sd: float, drift_sd: float) -> list[Any]:
    """wiener_sim's recordings (white noise 1 % of the output's RMS) with an output offset of ``offset_sd``
    noise sd and a line of ``drift_sd`` noise sd over each record (its sign per recording)."""
    plain = recordings(seed, [0.0] * 4)
    sd = 0.01 * float(np.sqrt(np.mean(np.asarray(plain[0].y) ** 2)))
    recs = recordings(seed, [offset_sd * sd] * 4)
    rng = np.random.default_rng([seed, 46])
    out = []
    for r in recs:
        y = np.asarray(r.y, dtype=np.float64)
        line = float(rng.choice([-1.0, 1.0])) * drift_sd * sd * np.linspace(0.0, 1.0, y.size)
        out.append(
            bw.Recording(r.t, r.u, y + line, r.amplitude, r.frequency, settle_periods=r.settle_periods)
        )
    return out


def _diagnose(recs: list[Any]) -> Any:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bw.diagnose(recs, candidates=["offset", "viscous", "asymmetry"])


def test_an_offset_under_a_drifting_zero_is_said_untested_and_a_white_null_is_not() -> None:
    recs = _drifting(3, 3.0, 3.0)
    drift = zero_drift.detect(recs, 0.05 / 3)
    assert drift is not None and not drift.kept  # the zero-drift path takes the DC out
    d = _diagnose(recs)
    assert d.status == "adequate", d.summary()
    assert d.headline.startswith("adequate: the plain Wiener-Bouc-Wen model"), d.headline
    assert CAVEAT in d.headline and "zero drifts" in d.headline, d.headline
    assert not any(t.term == "offset" for t in d.named)
    # the same plant with white noise alone (no drift, no offset) keeps the headline word for word
    white = _diagnose(recordings(3, [0.0] * 4))
    assert white.status == "adequate", white.summary()
    assert CAVEAT not in white.verdict and white.headline == gate.ADEQUATE, white.headline


def test_the_caveat_only_where_the_dc_was_not_used() -> None:
    drift = zero_drift.detect(_drifting(3, 3.0, 3.0), 0.05 / 3)
    assert drift is not None
    assert dc_untested.why(drift) == "the output's zero drifts over the record"
    assert dc_untested.why(replace(drift, kept=True)) == ""  # a common centre kept: an offset is tested
    assert dc_untested.why(replace(drift, too_short=True)) == "the period means trend over the record"
    assert dc_untested.why(None) == ""
