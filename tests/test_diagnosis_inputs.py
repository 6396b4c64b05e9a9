"""diagnose and diagnose_across check the stated input as identify does (review 31a items 4 and 10)."""

from __future__ import annotations

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.errors import FrequencyMismatchError, InsufficientDataError, InvalidParameterError


def _recs(seed: int = 0) -> list[bw.Recording]:
    plant = bw.WienerPlant(
        bw.TransferFunction([2.0], [0.1, 1.0]), bw.BoucWen(beta=1.0, gamma=0.3, mu=1.5, alpha=1.0)
    )
    plan = bw.SinePlan(
        frequencies=[2.0, 5.0], amplitudes=0.8, settle_periods=3, periods=5, samples_per_period=64,
        noise_sd=0.01, seed=seed,
    )  # fmt: skip
    return list(bw.simulate(plant, plan))


def _restated(recs: list[bw.Recording], amplitude: float = 1.0, frequency: float = 1.0) -> list[bw.Recording]:
    """The recordings with their amplitude and frequency stated ``amplitude`` and ``frequency`` times too
    large (the settling periods scaled with the frequency, so the grid stays whole)."""
    return [
        bw.Recording(
            r.t, r.u, r.y, amplitude=amplitude * r.amplitude, frequency=frequency * r.frequency,
            settle_periods=int(round(frequency * r.settle_periods)),
        )
        for r in recs
    ]  # fmt: skip


def _same_refusal(bad: list[bw.Recording], kind: type[Exception]) -> str:
    with pytest.raises(kind) as by_identify:
        bw.identify(bad)
    with pytest.raises(kind) as by_diagnose:
        bw.diagnose(bad)
    assert str(by_identify.value) in str(by_diagnose.value)
    return str(by_diagnose.value)


def test_a_wrong_stated_amplitude_is_refused_as_identify_refuses_it() -> None:
    assert "stated amplitude" in _same_refusal(_restated(_recs(), amplitude=2.0), InvalidParameterError)


def test_a_wrong_stated_frequency_is_a_frequency_mismatch() -> None:
    bad = _restated(_recs(), frequency=2.0)
    with pytest.raises(FrequencyMismatchError):
        bw.identify(bad)
    with pytest.raises(FrequencyMismatchError, match="does not repeat at omega"):
        bw.diagnose(bad)


def test_an_input_with_harmonics_passes_and_its_fundamental_is_still_checked() -> None:
    # The diagnosis takes a distorted input (its measured-waveform term); identify asks for a pure sine.
    distorted = []
    for r in _recs():
        th = r.frequency * r.t
        u = r.u + 0.2 * r.amplitude * np.cos(3 * th - 1.0)  # a 20 % third harmonic
        distorted.append(
            bw.Recording(
                r.t, u, r.y, amplitude=r.amplitude, frequency=r.frequency, settle_periods=r.settle_periods
            )
        )
    from bouc_wen_id.diagnosis.inputs import check_items

    check_items(distorted)  # no error
    with pytest.raises(FrequencyMismatchError):
        bw.identify(distorted)
    with pytest.raises(InvalidParameterError, match="stated amplitude"):
        check_items(_restated(distorted, amplitude=2.0))


def test_an_input_that_is_not_a_cosine_at_t0_is_refused() -> None:
    shifted = []
    for r in _recs():
        quarter = r.samples_per_period // 4  # u(t) = U cos(omega (t + T/4)) = -U sin(omega t) on t
        shifted.append(
            bw.Recording(
                r.t[: r.t.size - quarter], r.u[quarter:], r.y[quarter:], amplitude=r.amplitude,
                frequency=r.frequency, settle_periods=r.settle_periods,
            )
        )  # fmt: skip
    assert "shift the time column" in _same_refusal(shifted, InvalidParameterError)


def test_the_same_recording_twice_is_refused_by_name() -> None:
    recs = _recs()
    with pytest.raises(InvalidParameterError, match="same recording as item 0"):
        bw.diagnose([recs[0], recs[0], recs[1]])
    copy = bw.Recording(
        np.array(recs[1].t), np.array(recs[1].u), np.array(recs[1].y), amplitude=recs[1].amplitude,
        frequency=recs[1].frequency, settle_periods=recs[1].settle_periods,
    )  # fmt: skip
    with pytest.raises(InvalidParameterError, match="item 2 is the same recording as item 1"):
        bw.diagnose([recs[0], recs[1], copy])


def test_diagnose_across_checks_each_group_and_names_an_empty_one() -> None:
    recs = _recs()
    with pytest.raises(InsufficientDataError, match="condition 0"):
        bw.diagnose_across([[], recs], condition=[0.0, 1.0])
    with pytest.raises(InvalidParameterError, match="condition 1: item 0: the stated amplitude"):
        bw.diagnose_across([recs, _restated(_recs(1), amplitude=2.0)], condition=[0.0, 1.0])
