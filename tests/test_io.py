"""Files: recordings and lab measurements in the CSV, NPZ and MAT formats (round trips, layouts, malformed
files), and the clipping check of measurements."""

from __future__ import annotations

import io as _stdio
import json
import math
import os
import struct
import zlib
from pathlib import Path
from typing import Any, Callable

import bouc_wen_id as bw
import numpy as np
import pytest
import scipy.io  # type: ignore[import-untyped]
import scipy.sparse  # type: ignore[import-untyped]
from bouc_wen_id import io
from bouc_wen_id.errors import (
    ClippingError,
    FileFormatError,
    InsufficientDataError,
    InvalidParameterError,
    NonFiniteError,
    TimeAxisError,
    UnitMismatchError,
    UnitWarning,
)
from bouc_wen_id.io import read_csv, write_csv
from bouc_wen_id.measurement import Measurement, clipping_check


def _measurement(n: int = 400, rate: float = 1000.0, **kw: Any) -> Measurement:
    """A lab-like record: 7.3 Hz sine (not a whole number of samples per period) and a lagging response."""
    k = np.arange(n)
    u = 4.2 * np.sin(2 * np.pi * 7.3 * k / rate) - 29.9
    y = 1500.0 * np.sin(2 * np.pi * 7.3 * k / rate + 1.2) + 40.0
    defaults: dict[str, Any] = {
        "nominal_frequency": 2 * np.pi * 7.2,
        "units": {"u": "mm", "y": "N"},
        "channels": {"u": "CHANNEL0", "y": "CHANNEL1"},
        "name": "ME5mm3Hz, 0.5 A",
        "metadata": {"operator": "M. Quiroz", "note": 'quotes " and, commas; µm Выход'},
    }
    defaults.update(kw)
    return Measurement.from_rate(rate, u, y, **defaults)


def _assert_same(a: io.Item, b: io.Item, exact: bool = True) -> None:
    assert type(a) is type(b)
    for name in ("t", "u", "y", "x", "w"):
        va, vb = getattr(a, name, None), getattr(b, name, None)
        assert (va is None) == (vb is None), name
        if va is not None:
            assert vb is not None
            if exact:
                assert np.array_equal(va, vb), name
            else:
                np.testing.assert_allclose(vb, va, rtol=1e-15, atol=0, err_msg=name)
    if isinstance(a, Measurement) and isinstance(b, Measurement):
        assert a.name == b.name
        assert a.nominal_frequency == b.nominal_frequency
        assert dict(a.units) == dict(b.units)
        assert dict(a.channels) == dict(b.channels)
        assert dict(a.metadata) == dict(b.metadata)
    if isinstance(a, bw.Recording) and isinstance(b, bw.Recording):
        assert (a.amplitude, a.frequency, a.settle_periods) == (b.amplitude, b.frequency, b.settle_periods)
        # load() names a recording after its file unless its header names it; nothing else changes.
        ma, mb = dict(a.metadata), dict(b.metadata)
        na, nb = ma.pop("name", None), mb.pop("name", None)
        assert ma == mb and (na == nb or None in (na, nb))
        assert (a.plant is None) == (b.plant is None)
        if a.plant is not None and b.plant is not None:
            assert a.plant.to_dict() == b.plant.to_dict()


@pytest.fixture(scope="module")
def short_recordings() -> list[bw.Recording]:
    """Two noise-free demo recordings of 32 samples per period."""
    plan = bw.SinePlan([2.0, 5.0], [0.5, -0.25], settle_periods=1, periods=2, samples_per_period=32, seed=1)
    return bw.simulate(bw.demo_plant(), plan)


# --------------------------------------------------------------------------------------------------
# Measurement
# --------------------------------------------------------------------------------------------------


def test_measurement_copies_and_freezes_its_arrays() -> None:
    t, u, y = np.arange(10) * 0.01, np.arange(10.0), np.ones(10)
    m = Measurement(t, u, y, units={"u": "V"})
    u[0] = 99.0
    assert m.u[0] == 0.0
    for arr in (m.t, m.u, m.y):
        assert not arr.flags.writeable
        assert arr.dtype == np.float64
    assert dict(m.units) == {"t": "s", "u": "V"}
    assert m.nominal_frequency is None and m.name == "" and dict(m.metadata) == {}
    assert len(m) == 10 and m.dt == pytest.approx(0.01) and m.sample_rate == pytest.approx(100.0)
    assert m.duration == pytest.approx(0.09)


def test_from_rate_builds_t_as_k_over_rate() -> None:
    m = Measurement.from_rate(10240, np.zeros(7), np.ones(7), nominal_frequency=2 * np.pi * 16)
    assert np.array_equal(m.t, np.arange(7) / 10240.0)
    assert m.nominal_frequency == 2 * np.pi * 16


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"t": np.arange(5.0), "u": np.zeros(4)}, InvalidParameterError, "equal lengths"),
        ({"y": [0, 1, np.nan, 3, 4]}, NonFiniteError, "y holds a non-finite value"),
        ({"u": [0, np.inf, 2, 3, 4]}, NonFiniteError, "u holds"),
        ({"t": [0, 1, 2, 2, 3]}, TimeAxisError, "not strictly increasing"),
        ({"t": [0, 1, 3, 2, 4]}, TimeAxisError, "not strictly increasing"),
        ({"t": [0, 1, 2.02, 3, 4]}, TimeAxisError, "not uniformly sampled"),
        ({"t": [0.0], "u": [0.0], "y": [0.0]}, InsufficientDataError, "at least 2"),
        ({"t": np.zeros((5, 1))}, InvalidParameterError, "1-D"),
        ({"u": np.array([1j, 0, 0, 0, 0])}, InvalidParameterError, "real numbers"),
        ({"nominal_frequency": 0.0}, InvalidParameterError, "> 0"),
        ({"nominal_frequency": math.nan}, NonFiniteError, "not finite"),
        ({"units": {"t": "ms"}}, InvalidParameterError, "seconds"),
        ({"units": {"force": "N"}}, InvalidParameterError, "keyed by"),
        ({"channels": {"u": 3}}, InvalidParameterError, "string"),
        ({"metadata": {"units": "mm"}}, InvalidParameterError, "reserved"),
        ({"metadata": {"a: b": "c"}}, InvalidParameterError, "metadata key"),
        ({"metadata": {"line\nbreak": "c"}}, InvalidParameterError, "metadata key"),
    ],
)
def test_measurement_refuses_bad_input(kwargs: dict[str, Any], error: type[Exception], match: str) -> None:
    args: dict[str, Any] = {"t": np.arange(5.0), "u": np.zeros(5), "y": np.zeros(5)}
    args.update(kwargs)
    with pytest.raises(error, match=match):
        Measurement(args.pop("t"), args.pop("u"), args.pop("y"), **args)


def test_small_jitter_is_accepted() -> None:
    t = np.arange(100) * 1e-3
    t[50] += 0.4e-5  # steps of 1.004 ms and 0.996 ms: within 1 % of the median step
    Measurement(t, np.zeros(100), np.zeros(100))


def test_segment_scaled_and_to_recording(short_recordings: list[bw.Recording]) -> None:
    m = _measurement()
    seg = m.segment(0.1, 0.2)
    assert seg.t[0] >= 0.1 and seg.t[-1] < 0.2 and seg.t.size == 100
    assert seg.name == m.name and dict(seg.units) == dict(m.units)
    s = m.scaled(u=10.0, y=980.665, units={"y": "N (scaled)"})
    assert np.array_equal(s.u, m.u * 10.0) and s.units["y"] == "N (scaled)" and s.units["u"] == "mm"
    # A measurement of known U and omega becomes a recording that identifies like the original.
    rec = short_recordings[0]
    meas = Measurement(rec.t, rec.u, rec.y, name="exp 0", units={"u": "mm"}, metadata={"rig": "A"})
    back = meas.to_recording(rec.amplitude, rec.frequency, settle_periods=rec.settle_periods)
    assert isinstance(back, bw.Recording)
    assert np.array_equal(back.y, rec.y) and back.samples_per_period == rec.samples_per_period
    assert back.metadata["name"] == "exp 0" and back.metadata["rig"] == "A"
    assert json.loads(back.metadata["units"]) == {"t": "s", "u": "mm"}
    assert bw.identify([back], method="paper").mu == bw.identify([rec], method="paper").mu


# --------------------------------------------------------------------------------------------------
# Clipping
# --------------------------------------------------------------------------------------------------


def _sine(periods: float = 20, p: float = 400.3, amp: float = 1.0, phase: float = 0.3) -> np.ndarray:
    k = np.arange(int(periods * p))
    out: np.ndarray = amp * np.cos(2 * np.pi * k / p + phase)
    return out


def test_clean_and_quantised_sines_are_not_clipped() -> None:
    clipping_check(_sine(), "clean")
    rng = np.random.default_rng(3)
    for levels in (16, 78, 256, 4096):
        q = 2.0 / levels
        # An 8-bit-like scope trace repeats its top level for tens of samples per period: legitimate.
        clipping_check(np.round(_sine() / q) * q, f"quantised {levels}")
        noisy = _sine() + 0.3 * q * rng.standard_normal(_sine().size)
        clipping_check(np.round(noisy / q) * q, f"noisy quantised {levels}")
    clipping_check(np.full(100, 3.0), "constant")  # no extremes to judge: other checks refuse it
    # Settles onto its plateau (exactly 1.0 in floating point for a stretch of every period), no cut.
    saturating = np.tanh(40 * _sine())
    assert np.count_nonzero(saturating == 1.0) > 0.05 * saturating.size
    clipping_check(saturating, "saturating")


@pytest.mark.parametrize("levels", [None, 256, 4096])
def test_clipped_sines_are_refused(levels: int | None) -> None:
    x = np.clip(_sine(), -2.0, 0.9)  # a rail at 90 % of the amplitude, on one side only
    if levels is not None:
        q = 2.0 / levels
        x = np.round(x / q) * q
    with pytest.raises(ClippingError, match="clipped at its maximum"):
        clipping_check(x, "force")


def test_a_few_flat_runs_are_not_clipping() -> None:
    x = _sine(periods=20)
    x[: int(2.2 * 400.3)] = np.minimum(x[: int(2.2 * 400.3)], 0.8)  # only two clipped peaks
    x[int(2.2 * 400.3) :] *= 0.9
    clipping_check(x, "two runs")


def test_measurement_check_names_the_channel() -> None:
    x = _sine()
    m = Measurement.from_rate(1000, np.clip(x, -0.8, 0.8), x, channels={"u": "LVDT 2"}, name="run 7")
    with pytest.raises(ClippingError, match=r"run 7: u \(LVDT 2\)"):
        m.check()
    Measurement.from_rate(1000, x, x).check()


def test_simulated_recordings_pass_the_clipping_check() -> None:
    plan = bw.SinePlan([1.0, 8.0], 3.0, settle_periods=2, periods=4, samples_per_period=512)
    for rec in bw.simulate(bw.demo_plant(), plan):
        Measurement(rec.t, rec.u, rec.y).check()


@pytest.mark.real_data
def test_real_scope_captures_load_headerless_and_are_not_clipped(real_data: Path) -> None:
    """The microwire B-H captures: 8-bit scope, no header, no time column (the dt of PROVENANCE.md)."""
    folder = real_data / "bh-loop-microwire"
    dt = {"50kHz": 5e-8, "100kHz": 2e-8, "200kHz": 1e-8, "250kHz": 1e-8}
    for stem, step in dt.items():
        (m,) = io.load(folder / f"{stem}.csv", columns={"u": 1, "y": 0}, sample_rate=1 / step)
        assert isinstance(m, Measurement) and m.t.size == 1200 and m.name == stem
        assert dict(m.channels) == {"u": "column 1", "y": "column 0"}
        assert m.sample_rate == pytest.approx(1 / step)
        m.check()  # the reference channel repeats its top level for ~30 samples: not a clip


@pytest.mark.real_data
def test_real_lab_channels_are_not_clipped(real_data: Path) -> None:
    rope = np.loadtxt(real_data / "wire-rope-isolator" / "18Hz_A4.txt")
    Measurement.from_rate(10240, rope[:, 1], rope[:, 0]).check()
    data = json.loads((real_data / "friction-damper-brfd" / "1Hz30lbtension1amplitude.json").read_text())
    arr = np.array(data["data"])
    Measurement(arr[:, 0], arr[:, 1], arr[:, 2], units={"u": "in", "y": "kip"}).check()
    lines = (real_data / "mr-damper-utfsm" / "ME2mm5Hz.txt").read_text(encoding="latin-1").splitlines()[7:]
    cols = np.array([[float(c) for c in line.split(",")[2:4]] for line in lines])
    m = Measurement.from_rate(200, cols[:, 1] * 10, cols[:, 0] * 980.665, units={"u": "mm", "y": "N"})
    m.check()
    # The same force channel cut at a rail is caught.
    rail = np.percentile(m.y, 97)
    with pytest.raises(ClippingError):
        clipping_check(np.minimum(m.y, rail), "force")


# --------------------------------------------------------------------------------------------------
# Round trips
# --------------------------------------------------------------------------------------------------


def test_csv_round_trip_of_a_measurement(tmp_path: Path) -> None:
    m = _measurement()
    path = tmp_path / "m.csv"
    io.write_csv(path, m)
    text = path.read_text(encoding="utf-8")
    assert text.startswith('# format: "bouc_wen_id.measurement"\n# version: 1\n')
    assert '# units: {"t": "s", "u": "mm", "y": "N"}' in text and "\nt,u,y\n" in text
    back = io.read_csv(path)
    _assert_same(m, back, exact=False)
    _assert_same(m, back)  # %.17g round-trips a double exactly
    # No nominal frequency, no name, no units: still the same after the trip.
    bare = Measurement(m.t, m.u, m.y)
    io.write_csv(path, bare)
    _assert_same(bare, io.read_csv(path))


def test_csv_sample_rate_variant(tmp_path: Path) -> None:
    m = _measurement(rate=10240.0)
    path = tmp_path / "rate.csv"
    io.write_csv(path, m, sample_rate=10240)
    text = path.read_text(encoding="utf-8")
    assert "# sample_rate: 10240.0\n" in text and "\nu,y\n" in text
    _assert_same(m, io.read_csv(path))
    with pytest.raises(InvalidParameterError, match="not t = k"):
        io.write_csv(path, m, sample_rate=1000)
    # The same file without the header line reads with the rate as an argument.
    body = "\n".join(line for line in text.splitlines() if not line.startswith("# sample_rate")) + "\n"
    path.write_text(body, encoding="utf-8")
    _assert_same(m, io.read_csv(path, sample_rate=10240.0))
    with pytest.raises(FileFormatError, match="no time column"):
        io.read_csv(path)


def test_hand_written_csv_with_named_columns_and_units(tmp_path: Path) -> None:
    k = np.arange(64)
    disp, force = np.sin(k / 5.0), np.cos(k / 5.0)
    rows = "\n".join(
        f"{f!r},{i},{d!r},{i * 0.5!r}" for i, d, f in zip(k.tolist(), disp.tolist(), force.tolist())
    )
    path = tmp_path / "lab.csv"
    path.write_text(
        '# units: {"u": "mm", "y": "N"}\n'
        "# nominal_frequency_hz: 2.0\n"
        '# name: "damper A"\n'
        "# operator: J. Smith\n"
        "# temperature_C: 21.5\n"
        "# sample_rate: 500\n"
        "force_N,sample,disp_mm,time_s\n" + rows + "\n",
        encoding="utf-8",
    )
    (m,) = io.load(path, columns={"u": "disp_mm", "y": "force_N"})
    assert isinstance(m, Measurement)
    assert np.array_equal(m.u, disp) and np.array_equal(m.y, force)
    assert np.array_equal(m.t, k / 500.0)
    assert m.nominal_frequency == pytest.approx(4 * np.pi, rel=1e-15)
    assert m.name == "damper A"
    assert dict(m.units) == {"t": "s", "u": "mm", "y": "N"}
    assert dict(m.channels) == {"u": "disp_mm", "y": "force_N"}
    # A header value that is not JSON is kept as its text; a JSON number as its JSON text.
    assert dict(m.metadata) == {"operator": "J. Smith", "temperature_C": "21.5"}
    # The time column can be mapped too; it must then agree with the stated rate (0.5 s is not 500 Hz).
    with pytest.raises(FileFormatError, match="not at the stated sample rate"):
        io.load(path, columns={"u": "disp_mm", "y": "force_N", "t": "time_s"})


def test_mapped_time_column_must_match_the_stated_rate(tmp_path: Path) -> None:
    path = tmp_path / "t.csv"
    path.write_text("# sample_rate: 500\nsec,u,y\n" + "".join(f"{i * 0.5},{i},{-i}\n" for i in range(20)))
    with pytest.raises(FileFormatError, match="not at the stated sample rate"):
        io.load(path, columns={"t": "sec"})
    path.write_text("sec,u,y\n" + "".join(f"{i * 0.5},{i},{-i}\n" for i in range(20)))
    (m,) = io.load(path, columns={"t": "sec"})
    assert isinstance(m, Measurement) and m.sample_rate == 2.0 and m.channels["t"] == "sec"


def test_headerless_and_other_delimiters(tmp_path: Path) -> None:
    data = np.column_stack([np.linspace(-1, 1, 30), np.linspace(2, 3, 30)])
    for delim in (",", ";", "\t", " "):
        path = tmp_path / "raw.csv"
        path.write_text("\n".join(delim.join(f"{float(v)!r}" for v in row) for row in data) + "\n")
        (m,) = io.load(path, columns={"u": 1, "y": 0}, sample_rate=10240)
        assert isinstance(m, Measurement)
        assert np.array_equal(m.u, data[:, 1]) and np.array_equal(m.y, data[:, 0]), delim
    with pytest.raises(FileFormatError, match="no line of column names"):
        io.load(path, sample_rate=10240)


def test_recording_csv_reads_as_recording_and_plain_csv_as_measurement(
    tmp_path: Path, short_recordings: list[bw.Recording]
) -> None:
    io.write_csv(tmp_path / "rec.csv", short_recordings[0])
    (rec,) = io.load(tmp_path / "rec.csv")
    _assert_same(short_recordings[0], rec)
    t = np.arange(40) * 0.01
    text = "t,u,y\n" + "".join(f"{a!r},{math.cos(a)!r},{math.sin(a)!r}\n" for a in t.tolist())
    (tmp_path / "meas.csv").write_text(text)
    (meas,) = io.load(tmp_path / "meas.csv")
    assert isinstance(meas, Measurement) and meas.name == "meas"
    # amplitude and frequency in the header, no format line: the paper's Recording.
    (tmp_path / "meas.csv").write_text(f"# amplitude: 1.0\n# frequency: {2 * np.pi / 0.4!r}\n" + text)
    (rec2,) = io.load(tmp_path / "meas.csv")
    assert isinstance(rec2, bw.Recording) and rec2.samples_per_period == 40


def test_load_recordings_refuses_measurements(tmp_path: Path, short_recordings: list[bw.Recording]) -> None:
    io.save(tmp_path / "mixed.npz", [short_recordings[0], _measurement()])
    assert len(io.load(tmp_path / "mixed.npz")) == 2
    with pytest.raises(FileFormatError, match="holds a measurement"):
        io.load_recordings(tmp_path / "mixed.npz")


def test_npz_bundle_mixes_recordings_and_measurements(
    tmp_path: Path, short_recordings: list[bw.Recording]
) -> None:
    items: list[io.Item] = [
        short_recordings[0],
        _measurement(),
        short_recordings[1],
        _measurement(nominal_frequency=None),
    ]
    path = tmp_path / "bundle.npz"
    assert io.save(path, items) == [path]
    back = io.load(path)
    assert [type(b) for b in back] == [type(a) for a in items]
    for a, b in zip(items, back):
        _assert_same(a, b)
    with np.load(path) as z:
        kinds = [h["format"] for h in json.loads(str(z["meta"]))]
    assert kinds == [io.FORMAT, io.MEASUREMENT_FORMAT, io.FORMAT, io.MEASUREMENT_FORMAT]


def test_plain_npz_archives(tmp_path: Path) -> None:
    u, y = np.linspace(0, 1, 50), np.linspace(1, 2, 50)
    np.savez(tmp_path / "a.npz", disp=u, force=y, fs=np.float64(200.0))
    (m,) = io.load(tmp_path / "a.npz", columns={"u": "disp", "y": "force"})
    assert isinstance(m, Measurement) and np.array_equal(m.t, np.arange(50) / 200.0)
    assert dict(m.channels) == {"u": "disp", "y": "force"} and m.name == "a"
    meta = json.dumps({"name": "plain", "units": {"u": "mm"}, "nominal_frequency_hz": 1.5})
    np.savez(tmp_path / "b.npz", t=np.arange(50) * 0.1, u=u, y=y, meta=np.array(meta))
    (m,) = io.load(tmp_path / "b.npz")
    assert isinstance(m, Measurement) and m.name == "plain" and m.units["u"] == "mm"
    assert m.nominal_frequency == pytest.approx(3 * np.pi)


def test_mat_round_trips(tmp_path: Path, short_recordings: list[bw.Recording]) -> None:
    m = _measurement()
    single = tmp_path / "one.mat"
    io.save(single, [m])
    raw = scipy.io.loadmat(single, simplify_cells=True)
    assert {"t", "u", "y", "meta"} <= set(raw) and "experiments" not in raw
    assert json.loads(raw["meta"])["format"] == io.MEASUREMENT_FORMAT
    (back,) = io.load(single)
    _assert_same(m, back)
    # Several measurements: a struct array; recordings (with x, w) and measurements: a cell array.
    cases: list[tuple[str, list[io.Item]]] = [
        ("same.mat", [m, _measurement(name="other")]),
        ("mixed.mat", [short_recordings[0], m, short_recordings[1]]),
    ]
    for name, items in cases:
        path = tmp_path / name
        io.save(path, items)
        back_items = io.load(path)
        assert len(back_items) == len(items)
        for a, b in zip(items, back_items):
            _assert_same(a, b)
    raw = scipy.io.loadmat(tmp_path / "same.mat")
    assert raw["experiments"].dtype.names is not None  # a struct array
    io.write_mat(tmp_path / "b1.mat", [m], bundle=True)
    (b1,) = io.load(tmp_path / "b1.mat")
    _assert_same(m, b1)


def test_matlab_written_files(tmp_path: Path) -> None:
    """What a MATLAB user saves: own variable names, a sampling frequency, column vectors, integers."""
    u = np.arange(-50, 50, dtype=np.int16).reshape(-1, 1)
    y = np.linspace(0, 1, 100).reshape(1, -1)
    scipy.io.savemat(tmp_path / "lab.mat", {"disp": u, "force": y, "fs": 1000.0})
    (m,) = io.load(tmp_path / "lab.mat", columns={"u": "disp", "y": "force"})
    assert isinstance(m, Measurement)
    assert np.array_equal(m.u, u.ravel().astype(float)) and np.array_equal(m.y, y.ravel())
    assert np.array_equal(m.t, np.arange(100) / 1000.0) and m.name == "lab"
    exps = np.empty((1, 2), dtype=object)
    exps[0, 0] = {"u": u.ravel().astype(float), "y": y.ravel(), "sample_rate": 500.0}
    exps[0, 1] = {"u": y.ravel(), "y": y.ravel(), "t": np.arange(100) * 0.5, "meta": '{"name": "second"}'}
    scipy.io.savemat(tmp_path / "cells.mat", {"experiments": exps})
    first, second = io.load(tmp_path / "cells.mat")
    assert isinstance(first, Measurement) and first.sample_rate == pytest.approx(500.0)
    assert first.name == "cells[0]" and isinstance(second, Measurement) and second.name == "second"


def test_folders_and_save_layouts(tmp_path: Path, short_recordings: list[bw.Recording]) -> None:
    items: list[io.Item] = [short_recordings[0], _measurement(), short_recordings[1]]
    for fmt in ("csv", "npz", "mat"):
        folder = tmp_path / fmt
        files = io.save(folder, items, fmt=fmt)
        assert [f.name for f in files] == [f"exp_{i:03d}.{fmt}" for i in range(3)]
        back = io.load(folder)
        for a, b in zip(items, back):
            _assert_same(a, b)
    # A folder of mixed formats loads in name order; hidden files and other suffixes are skipped.
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    io.save(mixed / "b.mat", [items[1]])
    io.save(mixed / "a.csv", [items[0]])
    io.save(mixed / "c.npz", [items[2], items[1]])
    (mixed / "notes.txt").write_text("not data")
    (mixed / ".hidden.csv").write_text("garbage")
    back = io.load(mixed)
    for a, b in zip([items[0], items[1], items[2], items[1]], back):
        _assert_same(a, b)
    assert len(io.load([mixed / "c.npz", mixed / "a.csv"])) == 3
    with pytest.raises(InvalidParameterError, match="one experiment"):
        io.save(tmp_path / "two.csv", items[:2])
    with pytest.raises(InvalidParameterError, match="nothing to save"):
        io.save(tmp_path / "none.npz", [])
    with pytest.raises(InvalidParameterError, match="fmt"):
        io.save(tmp_path / "f", items, fmt="xls")  # type: ignore[arg-type]
    with pytest.raises(InvalidParameterError, match="columns"):
        io.load(mixed, columns={"force": "y"})
    with pytest.raises(InvalidParameterError, match="sample_rate"):
        io.load(mixed, sample_rate=-1.0)


def test_save_recordings_keeps_todays_layout(tmp_path: Path, short_recordings: list[bw.Recording]) -> None:
    files = io.save_recordings(tmp_path / "recs", short_recordings)
    assert [f.name for f in files] == ["exp_000.csv", "exp_001.csv"]
    for a, b in zip(short_recordings, io.load_recordings(tmp_path / "recs")):
        _assert_same(a, b)
    assert io.save_recordings(tmp_path / "r.mat", short_recordings) == [tmp_path / "r.mat"]
    for a, b in zip(short_recordings, io.load_recordings(tmp_path / "r.mat")):
        _assert_same(a, b)


# --------------------------------------------------------------------------------------------------
# Malformed files
# --------------------------------------------------------------------------------------------------

ROWS = "".join(f"{i * 0.01!r},{math.sin(i)!r},{math.cos(i)!r}\n" for i in range(20))


def _npz(**arrays: Any) -> Callable[[Path], object]:
    def write(path: Path) -> None:
        with open(path, "wb") as fh:
            np.savez(fh, **arrays)

    return write


def _mat(**variables: Any) -> Callable[[Path], object]:
    return lambda path: scipy.io.savemat(path, variables)


def _text(text: str) -> Callable[[Path], object]:
    return lambda path: path.write_text(text, encoding="utf-8")


def _bytes(data: bytes) -> Callable[[Path], object]:
    return lambda path: path.write_bytes(data)


def _patched_mat(
    variables: dict[str, Any], patches: dict[int, int], compressed: bool = False
) -> Callable[[Path], object]:
    """A MAT file with bytes of its (inflated) first variable overwritten: offsets from the variable's tag."""

    def write(path: Path) -> None:
        buf = _stdio.BytesIO()
        scipy.io.savemat(buf, variables, do_compression=compressed)
        data = bytearray(buf.getvalue())
        if not compressed:
            for at, byte in patches.items():
                data[128 + at] = byte
        else:
            (count,) = struct.unpack_from("<I", data, 132)
            raw = bytearray(zlib.decompress(bytes(data[136 : 136 + count])))
            for at, byte in patches.items():
                raw[at] = byte
            body = zlib.compress(bytes(raw))
            data = data[:128] + struct.pack("<II", 15, len(body)) + body + data[136 + count :]
        path.write_bytes(bytes(data))

    return write


U = np.linspace(0, 1, 20)
MALFORMED: list[tuple[str, Callable[[Path], object], str]] = [
    ("empty.csv", _text(""), "empty"),
    ("blank.csv", _text("\n  \n"), "empty"),
    ("header_only.csv", _text('# name: "x"\n'), "no column names and no data"),
    ("names_only.csv", _text("t,u,y\n"), "no data rows"),
    ("missing_column.csv", _text("t,u\n0,1\n1,2\n"), "no 'y' data"),
    ("non_numeric.csv", _text("t,u,y\n" + ROWS + "0.2,abc,1\n"), "line 22, field 2: 'abc' is not a number"),
    ("ragged.csv", _text("t,u,y\n" + ROWS + "0.2,1\n"), "line 22 has 2 fields"),
    ("too_many_fields.csv", _text("t,u,y\n0,1,2,3\n1,2,3,4\n"), "3 column names but 4 columns"),
    ("bad_units_json.csv", _text('# units: {"u": "mm"\nt,u,y\n' + ROWS), "'units' is not valid JSON"),
    ("units_not_object.csv", _text('# units: "mm"\nt,u,y\n' + ROWS), "must be a JSON object"),
    ("nominal_not_number.csv", _text('# nominal_frequency: "fast"\nt,u,y\n' + ROWS), "must be a number"),
    ("duplicate_key.csv", _text("# name: 1\n# name: 2\nt,u,y\n" + ROWS), "appears twice"),
    ("duplicate_column.csv", _text("t,u,u,y\n0,1,2,3\n"), "more than once"),
    ("empty_column_name.csv", _text("t,,y\n0,1,2\n"), "has no name"),
    ("no_separator.csv", _text("# just a comment\nt,u,y\n" + ROWS), "is not '# key: value'"),
    ("amplitude_only.csv", _text("# amplitude: 1.0\nt,u,y\n" + ROWS), "no 'frequency'"),
    ("unknown_format.csv", _text('# format: "other"\nt,u,y\n' + ROWS), "format 'other'"),
    ("newer.csv", _text('# format: "bouc_wen_id.measurement"\n# version: 2\nt,u,y\n' + ROWS), "newer"),
    ("bad_version.csv", _text("# version: 1.5\nt,u,y\n" + ROWS), "integer"),
    ("bad_plant.csv", _text('# amplitude: 1\n# frequency: 2\n# plant: {"a": 1}\nt,u,y\n' + ROWS), "plant"),
    ("no_time.csv", _text("u,y\n1,2\n3,4\n"), "no time column"),
    ("binary.csv", _bytes(b"\xff\xfe\x00\x81garbage\x00"), "not a UTF-8 text file"),
    ("unknown.xls", _text("t,u,y\n" + ROWS), "unknown recording format '.xls'"),
    ("unequal.npz", _npz(t=np.arange(20.0), u=U, y=U[:19]), "unequal lengths"),
    ("no_meta.npz", _npz(t_0=np.arange(20.0), u_0=U, y_0=U), "no 'meta' entry"),
    (
        "meta_json.npz",
        _npz(t_0=np.arange(20.0), u_0=U, y_0=U, meta=np.array("[{")),
        "'meta' is not valid JSON",
    ),
    ("meta_type.npz", _npz(u=U, y=U, meta=np.array("3")), "JSON list"),
    ("meta_empty.npz", _npz(meta=np.array("[]")), "no experiments"),
    ("meta_short.npz", _npz(u_0=U, y_0=U, u_1=U, y_1=U, meta=np.array('[{"sample_rate": 1}]')), "'u_1'"),
    ("strings.npz", _npz(t=np.arange(20.0), u=np.array(["a"] * 20), y=U), "not real numbers"),
    ("matrix.npz", _npz(t=np.arange(20.0), u=np.ones((4, 5)), y=U), "must be a vector"),
    ("garbage.npz", _bytes(b"PK\x03\x04 this is not a zip archive"), "not a readable NPZ archive"),
    ("no_uy.mat", _mat(a=np.ones(3)), "no variables 'u' and 'y'"),
    ("meta_not_json.mat", _mat(t=np.arange(20.0), u=U, y=U, meta="{oops"), "'meta' is not valid JSON"),
    ("meta_not_text.mat", _mat(t=np.arange(20.0), u=U, y=U, meta=np.ones(3)), "JSON string"),
    ("unequal.mat", _mat(t=np.arange(20.0), u=U, y=U[:5]), "unequal lengths"),
    ("bad_fs.mat", _mat(u=U, y=U, fs=np.ones(2)), "one number"),
    ("bad_experiments.mat", _mat(experiments=np.ones(3)), "struct"),
    ("garbage.mat", _bytes(b"MATLAB 5.0 MAT-file" + bytes(range(256)) * 2), "not a readable MAT file"),
    # Files that crash scipy's reader (a segfault, scipy/scipy#25349 and a 0-d char conversion) are refused
    # before it sees them: an unknown data-type code on the numeric data (offset 48: the real part's tag) ...
    ("dtype_code.mat", _patched_mat({"u": U, "y": U}, {48: 10}), "unknown data type code 10"),
    ("dtype_empty.mat", _patched_mat({"u": U, "y": U}, {48: 0, 52: 0}), "unknown data type code 0"),
    ("dtype_zip.mat", _patched_mat({"u": U, "y": U}, {48: 8}, compressed=True), "unknown data type code 8"),
    # ... a char array without dimensions (the dims element's byte count, offset 28, set to 1) ...
    ("char_no_dims.mat", _patched_mat({"meta": "{}", "u": U, "y": U}, {28: 1}), "0 dimensions"),
    # ... and classes this library does not read.
    ("sparse.mat", _mat(u=scipy.sparse.csc_array(np.eye(3)), y=U), "class 5"),
    ("hdf5.mat", _bytes(b"MATLAB 7.3 MAT-file".ljust(124) + b"\x00\x02IM" + b"\x00" * 64), "v7.3"),
]


@pytest.mark.parametrize(("name", "write", "match"), MALFORMED, ids=[m[0] for m in MALFORMED])
def test_malformed_files_raise_file_format_error_naming_the_file(
    tmp_path: Path, name: str, write: Callable[[Path], object], match: str
) -> None:
    path = tmp_path / name
    write(path)
    with pytest.raises(FileFormatError, match=match) as info:
        io.load(path)
    assert str(path) in str(info.value)


def test_data_errors_keep_their_names_and_name_the_file(tmp_path: Path) -> None:
    path = tmp_path / "nan.csv"
    path.write_text("t,u,y\n" + ROWS + "0.2,nan,1\n")
    with pytest.raises(NonFiniteError, match=f"{path}: u holds a non-finite value"):
        io.load(path)
    path.write_text("t,u,y\n" + ROWS + "0.1,1,1\n")
    with pytest.raises(TimeAxisError, match=f"{path}: t is not strictly increasing"):
        io.load(path)
    # A time column declared in ms is converted to seconds (it was refused before: bouc_wen_id.timeunits).
    path.write_text('# units: {"t": "ms"}\nt,u,y\n' + ROWS)
    with pytest.warns(UnitWarning, match=f"{path}: read the time column in ms as seconds"):
        (m,) = io.load(path)
    assert isinstance(m, Measurement) and m.units["t"] == "s"
    path.write_text('# units: {"t": "mm"}\nt,u,y\n' + ROWS)
    with pytest.raises(UnitMismatchError, match=f"{path}: the time column is in 'mm'"):
        io.load(path)
    path.write_text("# sample_rate: 0\nu,y\n1,2\n3,4\n")
    with pytest.raises(InvalidParameterError, match="sample_rate"):
        io.load(path)
    path.write_text("# sample_rate: 1000\nu,y\n1,2\n3,4\n")
    with pytest.raises(FileFormatError, match="disagrees"):
        io.load(path, sample_rate=2000)


def test_column_mapping_errors(tmp_path: Path) -> None:
    path = tmp_path / "c.csv"
    path.write_text("t,a,b\n" + ROWS)
    with pytest.raises(FileFormatError, match="no column 'disp'"):
        io.load(path, columns={"u": "disp", "y": "b"})
    with pytest.raises(FileFormatError, match="has 3 columns"):
        io.load(path, columns={"u": 7, "y": "b"})
    with pytest.raises(InvalidParameterError, match="both read"):
        io.load(path, columns={"u": "b", "y": "b"})
    with pytest.raises(InvalidParameterError, match="0-based"):
        io.load(path, columns={"u": -1, "y": "b"})
    (m,) = io.load(path, columns={"u": "a", "y": 2})
    assert isinstance(m, Measurement) and dict(m.channels) == {"u": "a", "y": "b"}


def test_writers_refuse_keys_a_header_cannot_hold(tmp_path: Path) -> None:
    t = np.arange(64) * (2 * np.pi / 2.0 / 32)
    rec = bw.Recording(t, np.cos(2.0 * t), np.sin(2.0 * t), 1.0, 2.0, metadata={"bad: key": "x"})
    with pytest.raises(InvalidParameterError, match="metadata key"):
        io.write_csv(tmp_path / "r.csv", rec)
    # NPZ and MAT headers are JSON: any key survives there.
    (back,) = io.load(io.save(tmp_path / "r.npz", [rec]))
    assert isinstance(back, bw.Recording) and back.metadata["bad: key"] == "x"


# --------------------------------------------------------------------------------------------------
# Recordings (U and omega known): CSV and NPZ round trips and errors
# --------------------------------------------------------------------------------------------------


def _assert_same_recording(a: bw.Recording, b: bw.Recording) -> None:
    for name in ("t", "u", "y", "x", "w"):
        va, vb = getattr(a, name), getattr(b, name)
        assert (va is None) == (vb is None), name
        if va is not None:
            # %.17g in CSV and binary in NPZ: both round-trip a double exactly.
            assert np.array_equal(va, vb), name
    assert a.amplitude == b.amplitude and a.frequency == b.frequency
    assert a.settle_periods == b.settle_periods
    # load() names a recording after its file unless its header names it; nothing else changes.
    ma, mb = dict(a.metadata), dict(b.metadata)
    na, nb = ma.pop("name", None), mb.pop("name", None)
    assert ma == mb and (na == nb or None in (na, nb))
    assert (a.plant is None) == (b.plant is None)
    if a.plant is not None and b.plant is not None:
        assert a.plant.to_dict() == b.plant.to_dict()


def test_csv_round_trip(tmp_path: Path, recordings: list[bw.Recording]) -> None:
    files = bw.save_recordings(tmp_path / "recs", recordings)
    assert [f.name for f in files] == ["exp_000.csv", "exp_001.csv"]
    loaded = bw.load_recordings(tmp_path / "recs")
    assert len(loaded) == 2
    for a, b in zip(recordings, loaded):
        _assert_same_recording(a, b)
    # Loading files one by one gives the same, in the given order.
    loaded2 = bw.load_recordings([files[1], files[0]])
    _assert_same_recording(loaded2[0], recordings[1])
    # Identification from the files equals identification from memory.
    assert bw.identify(loaded).mu == bw.identify(recordings).mu


def test_npz_round_trip(tmp_path: Path, recordings: list[bw.Recording]) -> None:
    path = tmp_path / "bundle.npz"
    assert bw.save_recordings(path, recordings) == [path]
    loaded = bw.load_recordings(path)
    assert len(loaded) == 2
    for a, b in zip(recordings, loaded):
        _assert_same_recording(a, b)


def test_round_trip_of_a_measured_recording_with_custom_metadata(tmp_path: Path) -> None:
    t = np.arange(256) * (2 * np.pi / 3.0 / 64)
    rec = bw.Recording(
        t,
        1.5 * np.cos(3.0 * t),
        np.sin(3.0 * t - 0.4),
        1.5,
        3.0,
        settle_periods=1,
        metadata={"units": "mm", "channel": "LVDT 2", "note": 'quotes " and, commas'},
    )
    for target in (tmp_path / "one.npz", tmp_path / "dir"):
        bw.save_recordings(target, [rec])
        (back,) = bw.load_recordings(target)
        _assert_same_recording(rec, back)
        assert back.x is None and back.plant is None
        assert back.metadata["note"] == 'quotes " and, commas'


def _write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


GOOD_HEADER = '# format: "bouc_wen_id.recording"\n# version: 1\n# amplitude: 1.0\n# frequency: 2.0\n'


def _rows(n: int = 16, cols: int = 3) -> str:
    t = np.arange(n) * (2 * np.pi / 2.0 / 8)
    data = np.column_stack([t, np.cos(2.0 * t), np.sin(2.0 * t)] + [t] * (cols - 3))
    return "\n".join(",".join(f"{v:.17g}" for v in row) for row in data) + "\n"


@pytest.mark.parametrize(
    ("name", "content"),
    [
        ("missing_column.csv", GOOD_HEADER + "t,u\n" + "\n".join("0.1,0.2" for _ in range(16))),
        ("missing_amplitude.csv", "# frequency: 2.0\nt,u,y\n" + _rows()),
        ("missing_frequency.csv", "# amplitude: 1.0\nt,u,y\n" + _rows()),
        (
            "wrong_format.csv",
            GOOD_HEADER.replace("bouc_wen_id.recording", "something.else") + "t,u,y\n" + _rows(),
        ),
        ("newer_version.csv", GOOD_HEADER.replace("version: 1", "version: 99") + "t,u,y\n" + _rows()),
        ("not_numeric.csv", GOOD_HEADER + "t,u,y\n" + "0,1,abc\n" * 16),
        ("column_count.csv", GOOD_HEADER + "t,u,y\n" + _rows(cols=4)),
        ("bad_header_line.csv", "# no separator here\n" + GOOD_HEADER + "t,u,y\n" + _rows()),
        ("unknown_suffix.xls", GOOD_HEADER + "t,u,y\n" + _rows()),
    ],
)
def test_malformed_files_raise_file_format_error(tmp_path: Path, name: str, content: str) -> None:
    # Sanity: the same rows under a good header do load, so each case fails for its stated reason only.
    good = _write(tmp_path / "good.csv", GOOD_HEADER + "t,u,y\n" + _rows())
    assert len(bw.load_recordings(good)) == 1
    bad = _write(tmp_path / name, content)
    with pytest.raises(bw.FileFormatError):
        bw.load_recordings(bad)


def test_folder_and_path_errors(tmp_path: Path) -> None:
    (tmp_path / "empty").mkdir()
    with pytest.raises(bw.FileFormatError, match="no .csv or .npz"):
        bw.load_recordings(tmp_path / "empty")
    (tmp_path / "other").mkdir()
    _write(tmp_path / "other" / "readme.txt", "not a recording")
    with pytest.raises(bw.FileFormatError):
        bw.load_recordings(tmp_path / "other")
    with pytest.raises(bw.FileFormatError, match="no such file"):
        bw.load_recordings(tmp_path / "missing.csv")


def test_npz_without_meta_is_refused(tmp_path: Path) -> None:
    np.savez(tmp_path / "plain.npz", t_0=np.arange(10.0), u_0=np.ones(10), y_0=np.ones(10))
    with pytest.raises(bw.FileFormatError, match="meta"):
        bw.load_recordings(tmp_path / "plain.npz")


def test_csv_data_errors_are_the_recordings_named_errors(
    tmp_path: Path, recordings: list[bw.Recording]
) -> None:
    """Data problems inside a well-formed file keep their own names (not FileFormatError)."""
    path = tmp_path / "r.csv"
    write_csv(path, recordings[0])
    lines = path.read_text(encoding="utf-8").splitlines()
    first_row = next(i for i, line in enumerate(lines) if line[0].isdigit())
    cells = lines[first_row + 3].split(",")
    cells[2] = "nan"
    lines[first_row + 3] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    with pytest.raises(bw.NonFiniteError):
        read_csv(path)


# --------------------------------------------------------------------------------------------------
# HDF5: only the file named is read (issue 19)
# --------------------------------------------------------------------------------------------------

SECRET = "TOP-SECRET 1234567890 do not read"


def _h5py() -> Any:
    return pytest.importorskip("h5py")


def _h5_lab(path: Path, n: int = 200, **extra: Any) -> Path:
    """A lab HDF5 file: group 'run' with u, y and a sample_rate attribute; ``extra`` adds to the root."""
    h5py = _h5py()
    m = _measurement(n)
    with h5py.File(path, "w") as f:
        g = f.create_group("run")
        g["u"], g["y"] = m.u, m.y
        g.attrs["sample_rate"] = 1000.0
        for name, value in extra.items():
            f[name] = value
    return path


def _assert_refused(path: Path, *words: str) -> str:
    with pytest.raises(FileFormatError) as info:
        bw.load(path)
    msg = str(info.value)
    assert str(path) in msg and "refused" in msg, msg
    for word in words:
        assert word in msg, msg
    assert "SECRET" not in msg
    return msg


def test_hdf5_external_raw_storage_is_refused_and_its_file_not_read(tmp_path: Path) -> None:
    h5py = _h5py()
    secret = tmp_path / "secret.txt"
    secret.write_text(SECRET * 8, encoding="ascii")
    path = _h5_lab(tmp_path / "ext.h5")
    with h5py.File(path, "a") as f:
        del f["run/u"]
        f["run"].create_dataset("u", shape=(200,), dtype="<f8", external=[(str(secret), 0, 1600)])
    _assert_refused(path, "'run/u'", "external files", "secret.txt")
    # The same through the CLI's folder reading.
    with pytest.raises(FileFormatError, match="refused"):
        bw.load(tmp_path)


def test_hdf5_external_storage_on_a_fifo_is_refused_without_opening_it(tmp_path: Path) -> None:
    """Before: a FIFO behind a dataset's external storage hung the reader (in a child, with a timeout)."""
    import subprocess
    import sys

    h5py = _h5py()
    fifo = tmp_path / "pipe"
    path = _h5_lab(tmp_path / "fifo.h5")
    with h5py.File(path, "a") as f:
        del f["run/y"]
        f["run"].create_dataset("y", shape=(200,), dtype="<f8", external=[(str(fifo), 0, 1600)])
    os.mkfifo(fifo)
    code = (
        "import sys, bouc_wen_id as bw\n"
        "try:\n    bw.load(sys.argv[1])\nexcept bw.FileFormatError as e:\n    print(e)\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, timeout=60, check=True
    )
    assert "refused" in out.stdout and "'run/y'" in out.stdout, out.stdout + out.stderr


def test_hdf5_virtual_dataset_is_refused(tmp_path: Path) -> None:
    h5py = _h5py()
    source = tmp_path / "source.h5"
    with h5py.File(source, "w") as f:
        f["data"] = np.frombuffer((SECRET * 8).encode()[:1600], dtype="<f8")
    path = _h5_lab(tmp_path / "vds.h5")
    layout = h5py.VirtualLayout(shape=(200,), dtype="<f8")
    layout[:] = h5py.VirtualSource(str(source), "data", shape=(200,))
    with h5py.File(path, "a") as f:
        del f["run/y"]
        f["run"].create_virtual_dataset("y", layout)
    _assert_refused(path, "'run/y'", "virtual dataset", "source.h5")


def test_hdf5_external_links_and_soft_links_through_them_are_refused(tmp_path: Path) -> None:
    h5py = _h5py()
    other = _h5_lab(tmp_path / "other.h5")
    path = _h5_lab(tmp_path / "link.h5", elsewhere=h5py.ExternalLink(str(other), "/run"))
    _assert_refused(path, "'elsewhere'", "external link", "other.h5")
    # A soft link whose path runs through an external link (the external link itself in a group of its own).
    path = _h5_lab(tmp_path / "soft.h5")
    with h5py.File(path, "a") as f:
        f.create_group("hidden")["door"] = h5py.ExternalLink(str(other), "/run")
        f["run/alias"] = h5py.SoftLink("/hidden/door/u")
    _assert_refused(path, "external link")
    # A soft link inside the file is harmless: not followed, the file reads.
    path = _h5_lab(tmp_path / "inside.h5", alias=h5py.SoftLink("/run/u"), dangling=h5py.SoftLink("/nowhere"))
    (m,) = bw.load(path)
    assert isinstance(m, Measurement) and len(m) == 200


def test_hdf5_hard_link_cycles_are_walked_once(tmp_path: Path) -> None:
    """Before: 12 groups each holding hard links to all 12 made the walk visit 12^8 groups."""
    import time

    h5py = _h5py()
    path = _h5_lab(tmp_path / "cycle.h5")
    with h5py.File(path, "a") as f:
        groups = [f.create_group(f"g{i}") for i in range(12)]
        for g in groups:
            for j, h in enumerate(groups):
                g[f"to{j}"] = h
            g["root"] = f["/"]
    start = time.perf_counter()
    (m,) = bw.load(path)
    assert time.perf_counter() - start < 5.0
    assert isinstance(m, Measurement) and m.name == "run" and len(m) == 200


def test_hdf5_memory_budget_is_per_file(tmp_path: Path) -> None:
    """Before: the budget held per experiment, so a small compressed file of many groups exhausted memory.

    Twelve experiments of 20,000 samples (a 10 Hz sine at 1 kHz repeats every 100 samples, so gzip keeps
    the file small): each fits a 1 MB budget, the file as a whole (3.8 MB of signals) does not.
    """
    h5py = _h5py()
    path = tmp_path / "many.h5"
    n = 20_000
    period = 2 * np.pi * np.arange(100) / 100
    u, y = np.tile(np.sin(period), n // 100), np.tile(np.cos(period), n // 100)
    with h5py.File(path, "w") as f:
        for i in range(12):
            g = f.create_group(f"run{i:02d}")
            g.create_dataset("u", data=u, compression="gzip", chunks=(n,))
            g.create_dataset("y", data=y, compression="gzip", chunks=(n,))
            g.attrs["sample_rate"] = 1000.0
    limit = 1_000_000
    assert path.stat().st_size < limit // 4 and 2 * n * 8 < limit
    with bw.budget.budget(max_bytes=limit), pytest.raises(bw.BudgetExceededError) as info:
        bw.load(path)
    assert str(path) in str(info.value) and "12 experiment" in str(info.value)
    assert len(bw.load(path)) == 12


# --------------------------------------------------------------------------------------------------
# DAQ text with header lines (issue 19: the shipped MR damper files load as they are)
# --------------------------------------------------------------------------------------------------


def _daq_text(
    path: Path,
    blocks: tuple[int, ...] = (60, 40),
    rate: float = 200.0,
    preamble: dict[str, str] | None = None,
) -> Path:
    """A DAQami-like export: 'Key: value' lines, names, a date column, two raw channels, an event log
    that marks DAQ Start / Pause / Resume (CRLF line ends, fields padded with spaces)."""
    head = {
        "Header Size": "7",
        "Version": "2",
        "Sampling Interval": f"{1 / rate:g}",
        "Sampling Rate": f"{rate:g}",
        "Sample Count": str(sum(blocks)),
        "Device Serial Number": "0",
        **(preamble or {}),
    }
    lines = [f"{k}:  {v}" for k, v in head.items()]
    lines.append("Sample Number, Date/Time, CHANNEL0, CHANNEL1, Events")
    n = 0
    for b, size in enumerate(blocks):
        for k in range(size):
            n += 1
            event = ""
            if k == 0:
                event = ", DAQ Start" if b == 0 else ", DAQ Resume"
            elif k == size - 1 and b < len(blocks) - 1:
                event = ", DAQ Pause"
            disp = -2.99 + 0.1 * math.sin(2 * math.pi * 5 * n / rate)
            force = 0.5 * math.cos(2 * math.pi * 5 * n / rate)
            lines.append(f"{n:>10},   05/13/2022 05:00:{n / rate:06.3f} PM, {disp:.4f}, {force:.4f}{event}")
    path.write_bytes(("\r\n".join(lines) + "\r\n").encode("ascii"))
    return path


def test_daq_text_with_header_lines_loads_one_experiment_per_block(tmp_path: Path) -> None:
    path = _daq_text(tmp_path / "run.txt")
    with pytest.raises(FileFormatError) as info:
        bw.load(path)  # CHANNEL0 / CHANNEL1: which is the input cannot be told from the file
    msg = str(info.value)
    assert str(path) in msg and "which column is the input u" in msg
    assert (
        "'CHANNEL0', 'CHANNEL1' hold numbers" in msg and "columns={'u': 'CHANNEL0', 'y': 'CHANNEL1'}" in msg
    )
    first, second = bw.load(path, columns={"u": "CHANNEL0", "y": "CHANNEL1"})
    assert isinstance(first, Measurement) and isinstance(second, Measurement)
    assert (len(first), len(second)) == (60, 40)
    assert first.name == "run[0]" and second.name == "run[1]"
    assert first.t[1] == 1 / 200.0 and second.t[0] == 0.0  # t = k / (the stated Sampling Rate)
    assert dict(first.channels) == {"u": "CHANNEL0", "y": "CHANNEL1"}
    assert first.metadata["Sampling Rate"] == "200" and first.metadata["block"] == "0"
    assert second.metadata["first_line"] == "68"  # 7 header lines, 60 rows of block 0
    assert first.u[0] == pytest.approx(-2.99 + 0.1 * math.sin(2 * math.pi * 5 / 200), abs=1e-4)
    # read_csv reads one experiment: a file of two blocks is named as such.
    with pytest.raises(FileFormatError, match="2 acquisition blocks"):
        io.read_csv(path, columns={"u": "CHANNEL0", "y": "CHANNEL1"})
    (one,) = bw.load(
        _daq_text(tmp_path / "one.dat", blocks=(80,)), columns={"u": "CHANNEL1", "y": "CHANNEL0"}
    )
    assert isinstance(one, Measurement) and len(one) == 80 and one.name == "one"


def test_daq_text_columns_named_for_their_signal_are_inferred_with_units(tmp_path: Path) -> None:
    k = np.arange(100)
    rows = "\n".join(f"{i / 500:.4f}\t{math.sin(0.2 * i):.6f}\t{math.cos(0.2 * i):.6f}" for i in k)
    path = tmp_path / "mts.txt"
    path.write_text(
        f"Operator: M. Q.\nSpecimen = damper 3\nTime (s)\tDisplacement [mm]\tForce (kN)\n{rows}\n"
    )
    (m,) = bw.load(path)
    assert isinstance(m, Measurement) and len(m) == 100
    assert dict(m.channels) == {"t": "Time (s)", "u": "Displacement [mm]", "y": "Force (kN)"}
    assert dict(m.units) == {"t": "s", "u": "mm", "y": "kN"}
    assert m.metadata["Operator"] == "M. Q." and m.metadata["Specimen"] == "damper 3"
    assert m.sample_rate == pytest.approx(500.0)
    # Two columns that could be the output: named, not guessed.
    two = tmp_path / "two.txt"
    two.write_text(
        "time,disp,Force (N),force [kN]\n" + "\n".join(f"{i},{i},{i},{i}" for i in range(5)) + "\n"
    )
    with pytest.raises(FileFormatError, match=r"'Force \(N\)', 'force \[kN\]' could each be 'y'"):
        bw.load(two)


def test_daq_text_header_faults_are_named_and_skiprows_skips(tmp_path: Path) -> None:
    body = "t,u,y\n" + "\n".join(f"{i / 100},{math.sin(i)},{math.cos(i)}" for i in range(50)) + "\n"
    path = tmp_path / "free.txt"
    path.write_text("MTS test 5 -- damper\nSampling Rate: 100\n" + body)
    with pytest.raises(FileFormatError, match=r"line 1 'MTS test 5 -- damper'.*skiprows"):
        bw.load(path)
    (m,) = bw.load(path, skiprows=2)
    assert len(m.u) == 50 and m.metadata["Sampling Rate"] == "100"
    with pytest.raises(InvalidParameterError, match="skiprows"):
        bw.load(path, skiprows=-1)
    with pytest.raises(FileFormatError, match="skips all"):
        bw.load(path, skiprows=99)
    # A rate and an interval that disagree, a sample count that does not match the rows.
    bad = _daq_text(tmp_path / "rate.txt", preamble={"Sampling Interval": "0.002"})
    with pytest.raises(FileFormatError, match="different sampling rates"):
        bw.load(bad, columns={"u": "CHANNEL0", "y": "CHANNEL1"})
    short = _daq_text(tmp_path / "count.txt", preamble={"Sample Count": "101"})
    with pytest.raises(FileFormatError, match="state 101 samples, the file has 100 rows"):
        bw.load(short, columns={"u": "CHANNEL0", "y": "CHANNEL1"})
    # 'Key: value' lines right above the rows (no line of names): the columns are taken by index.
    bare = tmp_path / "bare.txt"
    bare.write_text(
        "Sampling Rate: 100\n" + "\n".join(f"{math.sin(i)} {math.cos(i)}" for i in range(50)) + "\n"
    )
    (m,) = bw.load(bare, columns={"u": 0, "y": 1})
    assert isinstance(m, Measurement) and len(m) == 50 and m.sample_rate == pytest.approx(100.0)
    # A stated interval with a unit is read in it; a unit not understood is refused, not read as seconds.
    (m,) = bw.load(
        _daq_text(tmp_path / "ms.txt", (80,), preamble={"Sampling Interval": "5 ms"}),
        columns={"u": 2, "y": 3},
    )
    assert isinstance(m, Measurement) and m.sample_rate == pytest.approx(200.0)
    with pytest.raises(FileFormatError, match="unit 'fortnights' not understood"):
        bw.load(
            _daq_text(tmp_path / "odd.txt", preamble={"Sampling Interval": "5 fortnights"}),
            columns={"u": 2, "y": 3},
        )
    # A signal mapped to a text column is named by line and field.
    with pytest.raises(FileFormatError, match=r"line 8, field 2: '05/13/2022"):
        bw.load(_daq_text(tmp_path / "text.txt"), columns={"u": "Date/Time", "y": "CHANNEL1"})


def test_folders_read_daq_text_and_pass_over_notes(tmp_path: Path) -> None:
    _daq_text(tmp_path / "a.txt")
    (tmp_path / "README.txt").write_text("Runs of 13 May.\nChannel 0: displacement, channel 1: force.\n")
    items = bw.load(tmp_path, columns={"u": "CHANNEL0", "y": "CHANNEL1"})
    assert [m.name for m in items if isinstance(m, Measurement)] == ["a[0]", "a[1]"]
    with pytest.raises(FileFormatError, match="line 2 'Channel 0: .* is not a row of numbers"):
        bw.load(tmp_path / "README.txt")  # named, it is read and refused


#: PROVENANCE.md of mr-damper-utfsm: the channel order of each recording session.
MR_SESSION_FILES = {
    ("CHANNEL0", "CHANNEL1"): ("ME10mm2Hz.txt", "ME5mm3Hz.txt", "ME5mm4Hz.txt"),
    ("CHANNEL1", "CHANNEL0"): ("ME25mm0x25Hz.txt", "ME25mm0x5Hz.txt", "ME2mm5Hz.txt"),
}


@pytest.mark.real_data
@pytest.mark.parametrize("channels", list(MR_SESSION_FILES))
def test_shipped_mr_damper_files_load_as_they_are(
    real_data: Path, tmp_path: Path, channels: tuple[str, str]
) -> None:
    """The DAQ exports, read through the CLI's folder path with its --columns, equal the study adapter's
    blocks (which parse the same files by hand and scale them: 10 mm and 980.665 N per raw unit)."""
    import importlib.util
    import sys

    from bouc_wen_id import cli

    folder = real_data / "mr-damper-utfsm"
    spec = importlib.util.spec_from_file_location(
        "_adapters", Path(__file__).parents[1] / "studies/_adapters.py"
    )
    assert spec is not None and spec.loader is not None
    adapters = sys.modules.get("_adapters") or importlib.util.module_from_spec(spec)
    if "_adapters" not in sys.modules:
        sys.modules["_adapters"] = adapters
        spec.loader.exec_module(adapters)
    session = tmp_path / "session"
    session.mkdir()
    for name in MR_SESSION_FILES[channels]:
        (session / name).symlink_to(folder / name)
    u, y = channels
    with pytest.raises(FileFormatError, match="which column is the input u"):
        bw.load(session)
    items = bw.load(session, columns=cli._columns([f"u={u}", f"y={y}"]))
    assert len(items) == 15  # five coil currents per file
    expected = [
        b for name in sorted(MR_SESSION_FILES[channels]) for b in adapters.load_mr_damper(folder / name)
    ]
    for got, ref in zip(items, expected):
        assert isinstance(got, Measurement)
        assert dict(got.channels) == {"u": u, "y": y}
        np.testing.assert_allclose(got.u * 10.0, ref.u, rtol=1e-12)
        np.testing.assert_allclose(got.y * 980.665, ref.y, rtol=1e-12)
        np.testing.assert_allclose(got.t, ref.t, rtol=1e-12, atol=1e-12)
        assert -3.15 < float(np.median(got.u)) < -2.85  # the actuator's -29.9 mm offset: u is displacement
