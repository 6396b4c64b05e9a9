"""python-control interop (bouc_wen_id.interop, issue #11 part 2): FRD of the points, tf both ways, Pade."""

from __future__ import annotations

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id.demo import design_amplitudes
from bouc_wen_id.errors import InvalidParameterError, UnstableSystemError

control = pytest.importorskip("control")  # in the test extra; skipped only in a bare install


@pytest.fixture(scope="module")
def result() -> bw.IdentificationResult:
    plant = bw.WienerPlant(bw.TransferFunction([6.0], [1.0, 1.2, 4.0], delay=0.05), bw.BoucWen(0.8, 0.2, 1.6))
    freqs = [float(f) for f in np.geomspace(0.5, 5.0, 8)]
    plan = bw.SinePlan(
        frequencies=tuple(freqs),
        amplitudes=design_amplitudes(plant, freqs),
        settle_periods=10,
        periods=10,
        samples_per_period=128,
        substeps=2,
        noise_sd=0.02,
        seed=8,
    )
    return bw.identify(bw.simulate(plant, plan), method="profile")


def test_frd_holds_the_points_with_the_library_sign(result: bw.IdentificationResult) -> None:
    frd = result.to_frd()
    assert isinstance(frd, control.FRD)
    np.testing.assert_array_equal(frd.omega, np.sort(result.frequencies))
    order = np.argsort(result.frequencies)
    g = result.frequency_response[order]
    np.testing.assert_allclose(frd.eval(frd.omega), g, rtol=1e-15)
    # python-control's phase is -phi: G = |G| exp(-j phi).
    np.testing.assert_allclose(np.angle(frd.eval(frd.omega)), np.angle(np.exp(-1j * result.phases[order])))
    # Round trip: the FRD evaluated at its own frequencies gives the points back.
    np.testing.assert_allclose(frd.eval(frd.omega[2]), g[2], rtol=1e-12)


def test_to_control_and_back() -> None:
    tf = bw.TransferFunction([3.0, 1.0, 20.0], [1.0, 1.2, 30.0, 10.0, 50.0])
    sys = tf.to_control()
    assert isinstance(sys, control.TransferFunction)
    w = np.geomspace(0.1, 30.0, 9)
    np.testing.assert_allclose(sys(1j * w), tf.freqresp(w), rtol=1e-12)
    back = bw.TransferFunction.from_control(sys, delay=0.2)
    np.testing.assert_allclose(back.num, tf.num)
    np.testing.assert_allclose(back.den, tf.den)
    assert back.delay == 0.2
    # State space converts too (through control.tfdata): same response.
    ss_back = bw.TransferFunction.from_control(control.ss(sys))
    np.testing.assert_allclose(ss_back.freqresp(w), tf.freqresp(w), rtol=1e-8)


def test_delay_needs_a_pade_order() -> None:
    tf = bw.TransferFunction([25.0], [1.0, 2.0, 25.0], delay=0.05)
    with pytest.raises(InvalidParameterError, match="pade_order"):
        tf.to_control()
    for bad in (0, 11, 2.5, True):
        with pytest.raises(InvalidParameterError):
            tf.to_control(pade_order=bad)  # type: ignore[arg-type]
    sys = tf.to_control(pade_order=4)
    num, den = control.pade(0.05, 4)
    np.testing.assert_allclose(sys.den[0][0], np.polymul([1.0, 2.0, 25.0], den), rtol=1e-12)
    # A 4th-order Pade of a 0.05 s delay is exact to ~1e-9 well below 1/delay = 20 rad/s.
    w = np.array([0.5, 2.0, 5.0])
    np.testing.assert_allclose(sys(1j * w), tf.freqresp(w), rtol=1e-6)


def test_from_control_refuses_what_it_cannot_hold() -> None:
    with pytest.raises(InvalidParameterError, match="continuous"):
        bw.TransferFunction.from_control(control.tf([1.0], [1.0, 0.5], 0.1))
    with pytest.raises(InvalidParameterError, match="SISO"):
        bw.TransferFunction.from_control(control.ss(-np.eye(2), np.eye(2), np.eye(2), np.zeros((2, 2))))
    with pytest.raises(InvalidParameterError):
        bw.TransferFunction.from_control(np.array([1.0]))
    with pytest.raises(UnstableSystemError):
        bw.TransferFunction.from_control(control.tf([1.0], [1.0, -1.0]))


def test_fit_from_the_frd_points_matches_the_fit_from_the_result(result: bw.IdentificationResult) -> None:
    frd = result.to_frd()
    a = bw.fit_transfer_function(result, order=(0, 2), delay=True)
    b = bw.fit_transfer_function(omega=frd.omega, response=frd.eval(frd.omega), order=(0, 2), delay=True)
    np.testing.assert_allclose(a.parameters, b.parameters, rtol=1e-8)
    # profile method: no uncertainty on the points, so relative weights and scatter-based intervals
    assert not a.weighted and a.p_value is None
