"""identify's figures in the units a user reads (issue 19): loops against the applied input, the phase
unwrapped and in degrees, Bode in dB and Hz on request (``units="dB"``, ``--bode-units dB``)."""

from __future__ import annotations

from pathlib import Path

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import cli
from bouc_wen_id.errors import InvalidParameterError
from bouc_wen_id.plotting import (
    input_grid,
    plot_bode,
    plot_loop,
    plot_loops,
    plot_residuals,
    unwrapped_degrees,
)

#: A first-order G with a 0.3 s delay: its lag passes 180 degrees inside the band, so a wrapped phase jumps.
PLANT = bw.WienerPlant(
    bw.TransferFunction([3.0], [1.0, 3.0], delay=0.3),
    bw.BoucWen(beta=0.9, gamma=0.3, mu=1.5, alpha=1.0),
)


@pytest.fixture(scope="module")
def result() -> bw.IdentificationResult:
    plan = bw.SinePlan(
        frequencies=[0.5, 2.0, 6.0, 12.0],
        amplitudes=[1.0, 1.5, 2.5, 4.0],
        settle_periods=10,
        periods=8,
        samples_per_period=256,
        noise_sd=0.002,
        seed=4,
    )
    return bw.identify(bw.simulate(PLANT, plan))


def test_unwrapped_degrees_follow_a_delay_past_a_full_turn() -> None:
    # The true lag of e^{-0.8 s}/(1 + s/2): atan(w/2) + 0.8 w, computed here, not by the library.
    w = np.array([9.0, 0.3, 3.0, 6.0, 1.0])  # out of order on purpose
    true = np.degrees(np.arctan(w / 2.0) + 0.8 * w)
    assert true.max() > 360.0
    wrapped = np.mod(np.radians(true), 2 * np.pi)
    assert np.allclose(unwrapped_degrees(w, wrapped), true)
    # The lowest frequency's phase is put in (-180, 180], whatever branch it came on.
    assert np.allclose(unwrapped_degrees(w, wrapped + 6 * np.pi), true)
    assert unwrapped_degrees(np.array([1.0]), np.array([np.pi]))[0] == pytest.approx(180.0)


def test_bode_by_default_in_rad_per_s_with_the_phase_in_degrees(result: bw.IdentificationResult) -> None:
    fig = plot_bode(result)
    ax_g, ax_p = fig.axes[:2]
    points_g = [ln for ln in ax_g.get_lines() if ln.get_marker() == "o"][0]
    points_p = [ln for ln in ax_p.get_lines() if ln.get_marker() == "o"][0]
    assert np.allclose(points_g.get_xdata(), result.frequencies)
    assert np.allclose(points_g.get_ydata(), result.gains)
    lag = np.degrees(np.arctan(result.frequencies / 3.0) + 0.3 * result.frequencies)
    assert lag.max() > 180.0  # the wrapped phase would have jumped here
    assert np.allclose(points_p.get_ydata(), lag, atol=2.0)
    assert "rad/s" in ax_p.get_xlabel() and "(deg)" in ax_p.get_ylabel()
    assert ax_g.get_yscale() == "log"


def test_bode_in_db_and_hz_on_request(result: bw.IdentificationResult) -> None:
    fig = plot_bode(result, units="dB", u_unit="mm", y_unit="N")
    ax_g, ax_p = fig.axes[:2]
    points_g = [ln for ln in ax_g.get_lines() if ln.get_marker() == "o"][0]
    assert np.allclose(points_g.get_xdata(), result.frequencies / (2 * np.pi))
    assert np.allclose(points_g.get_ydata(), 20 * np.log10(result.gains))
    assert "Hz" in ax_p.get_xlabel() and "dB" in ax_g.get_ylabel() and "N/mm" in ax_g.get_ylabel()
    assert ax_g.get_yscale() == "linear"
    with pytest.raises(InvalidParameterError, match="units"):
        plot_bode(result, units="decibel")


def test_loops_are_drawn_against_the_applied_input_in_its_units(result: bw.IdentificationResult) -> None:
    fig = plot_loops(result, u_unit="mm", y_unit="N")
    for ax, e in zip(fig.axes, result.experiments):
        x = np.asarray(ax.get_lines()[0].get_xdata(), dtype=np.float64)
        # The applied input U cos(omega t), not the alpha-normalised x = U|G| cos(omega t - phi).
        assert np.max(np.abs(x)) == pytest.approx(e.amplitude, rel=1e-3)
        assert np.max(np.abs(x[:-1] - e.model_input())) > 0.1 * e.amplitude
    labels = [t.get_text() for t in fig.texts]
    assert any("(mm)" in t for t in labels) and any("(N)" in t for t in labels)
    ax = plot_loop(result, u_unit="mm", y_unit="N").axes[0]
    assert ax.get_xlabel().endswith("(mm)") and ax.get_ylabel().endswith("(N)")
    assert any("(N)" in t.get_text() for t in plot_residuals(result, y_unit="N").texts)


def test_the_input_grid_is_the_recorded_input(result: bw.IdentificationResult) -> None:
    """On a recording's own grid the reconstructed input is the recorded one, sample for sample."""
    plan = bw.SinePlan(frequencies=[2.0], amplitudes=1.5, settle_periods=3, periods=4, samples_per_period=64)
    rec = bw.simulate(PLANT, plan)[0]
    e = bw.identify([rec], method="profile").experiments[0]
    p = rec.samples_per_period
    u = rec.u[rec.settle_periods * p : (rec.settle_periods + 1) * p]
    assert np.allclose(input_grid(e), u - u.mean(), atol=1e-9)


def test_the_cli_draws_bode_in_db_on_request(tmp_path: Path) -> None:
    recs = tmp_path / "recs"
    argv = ["simulate", "--out", str(recs), "--frequencies", "1", "3", "--samples-per-period", "128"]
    assert cli.main([*argv, "--periods", "6", "--settle-periods", "10"]) == 0
    outs = {}
    for units in ("linear", "dB"):
        out = tmp_path / units
        assert cli.main(["identify", str(recs), "--out", str(out), "--bode-units", units]) == 0
        outs[units] = (out / "bode.png").read_bytes()
    assert outs["linear"][:4] == b"\x89PNG" and outs["linear"] != outs["dB"]
    with pytest.raises(SystemExit) as exc:
        cli.main(["identify", str(recs), "--out", str(tmp_path / "x"), "--bode-units", "decibel"])
    assert exc.value.code == 2
