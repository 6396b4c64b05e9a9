"""Lab formats: pandas frames, NI TDMS and HDF5 files (issue #11 part 4).

Files are written in ``tmp_path`` with the libraries themselves (npTDMS, h5py), the way a lab's software
writes them, then read through ``bouc_wen_id.load`` / the CLI; every malformed file must raise the same
named errors as CSV/NPZ/MAT, naming the file and the fault.
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import bouc_wen_id as bw
import numpy as np
import pytest
from bouc_wen_id import cli, io
from bouc_wen_id.errors import FileFormatError, InvalidParameterError, NonFiniteError, TimeAxisError
from bouc_wen_id.io import _common, _containers

pd = pytest.importorskip("pandas")
nptdms = pytest.importorskip("nptdms")
h5py = pytest.importorskip("h5py")

RATE = 1000.0


def _lab_signals(n: int = 400, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A 7.3 Hz sine and a lagging, noisy response (seeded)."""
    rng = np.random.default_rng(seed)
    k = np.arange(n)
    u = 4.2 * np.sin(2 * np.pi * 7.3 * k / RATE)
    y = 1500.0 * np.sin(2 * np.pi * 7.3 * k / RATE + 1.2) + rng.normal(0.0, 1.0, n)
    return u, y


def _measurement(seed: int = 0, **kw: Any) -> bw.Measurement:
    u, y = _lab_signals(seed=seed)
    args: dict[str, Any] = {
        "nominal_frequency": 2 * np.pi * 7.2,
        "units": {"u": "mm", "y": "N"},
        "channels": {"u": "CHANNEL0", "y": "CHANNEL1"},
        "name": f"run {seed}",
        "metadata": {"operator": "M. Quiroz", "note": 'quotes " and µm Выход'},
    }
    args.update(kw)
    return bw.Measurement.from_rate(RATE, u, y, **args)


@pytest.fixture(scope="module")
def recordings() -> list[bw.Recording]:
    """Two noise-free demo recordings of 32 samples per period (known U and omega)."""
    plan = bw.SinePlan([2.0, 5.0], [0.5, -0.25], settle_periods=1, periods=2, samples_per_period=32, seed=1)
    return bw.simulate(bw.demo_plant(), plan)


def _measurements(items: list[io.Item]) -> list[bw.Measurement]:
    """The items, each checked to be a Measurement (lab data: no header)."""
    out = [m for m in items if isinstance(m, bw.Measurement)]
    assert len(out) == len(items), items
    return out


def _assert_same(a: io.Item, b: io.Item) -> None:
    assert type(a) is type(b)
    for name in ("t", "u", "y", "x", "w"):
        va, vb = getattr(a, name, None), getattr(b, name, None)
        assert (va is None) == (vb is None), name
        if va is not None:
            assert vb is not None and np.array_equal(va, vb), (
                name
            )  # float64 channels: written and read bit for bit
    if isinstance(a, bw.Measurement) and isinstance(b, bw.Measurement):
        assert (a.name, a.nominal_frequency) == (b.name, b.nominal_frequency)
        assert dict(a.units) == dict(b.units) and dict(a.channels) == dict(b.channels)
        assert dict(a.metadata) == dict(b.metadata)
    if isinstance(a, bw.Recording) and isinstance(b, bw.Recording):
        assert (a.amplitude, a.frequency, a.settle_periods) == (b.amplitude, b.frequency, b.settle_periods)
        # load() names a recording after its file unless its header names it; nothing else changes.
        ma, mb = dict(a.metadata), dict(b.metadata)
        na, nb = ma.pop("name", None), mb.pop("name", None)
        assert ma == mb and (na == nb or None in (na, nb))
        assert a.plant is not None and b.plant is not None and a.plant.to_dict() == b.plant.to_dict()


# --------------------------------------------------------------------------------------------------
# Writing lab files the way a lab's software does
# --------------------------------------------------------------------------------------------------


def _write_tdms(path: Path, groups: dict[str, dict[str, tuple[Any, dict[str, Any]]]], **root: Any) -> Path:
    """``groups``: group -> channel -> (data, properties); group properties under the key ``""``."""
    objects: list[Any] = [nptdms.RootObject(root)]
    for g, chans in groups.items():
        objects.append(nptdms.GroupObject(g, chans.get("", (None, {}))[1]))
        for c, (data, props) in chans.items():
            if c:
                objects.append(nptdms.ChannelObject(g, c, np.asarray(data), props))
    with nptdms.TdmsWriter(str(path)) as w:
        w.write_segment(objects)
    return path


def _write_h5(path: Path, datasets: dict[str, Any], attrs: dict[str, dict[str, Any]] | None = None) -> Path:
    """``datasets``: path -> data; ``attrs``: object path ('' for the root) -> attributes."""
    with h5py.File(path, "w") as f:
        for name, data in datasets.items():
            f.create_dataset(name, data=data)
        for name, a in (attrs or {}).items():
            for k, v in a.items():
                (f[name] if name else f).attrs[k] = v
    return path


def _lab_tdms(path: Path, **kw: Any) -> Path:
    """Two runs (groups) of NI waveform channels with units, and a group of other channels."""
    u0, y0 = _lab_signals(seed=0)
    u1, y1 = _lab_signals(seed=1)
    wf = {"wf_increment": 1.0 / RATE, "wf_start_time": np.datetime64("2024-03-01T10:00:00")}
    return _write_tdms(
        path,
        {
            "Run 1": {
                "": (None, {"operator": "A", "nominal_frequency": 2 * np.pi * 7.2, "frequency": 7.3}),
                "Disp": (u0, {**wf, "unit_string": "mm"}),
                "Force": (y0, {**wf, "unit_string": "kN"}),
            },
            "Run 2": {"Disp": (u1, dict(wf)), "Force": (y1, dict(wf))},
            "Environment": {"Temperature": (np.full(3, 21.5), {})},
        },
        **kw,
    )


# --------------------------------------------------------------------------------------------------
# Round trips
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".tdms", ".h5", ".hdf5"])
def test_round_trip_of_measurements_and_recordings(
    tmp_path: Path, suffix: str, recordings: list[bw.Recording]
) -> None:
    items: list[io.Item] = [_measurement(0), recordings[0], _measurement(1, channels={}), recordings[1]]
    path = tmp_path / f"bundle{suffix}"
    assert bw.save(path, items) == [path]
    back = bw.load(path)
    assert len(back) == len(items)
    for a, b in zip(items, back):
        _assert_same(a, b)
    bw.save(tmp_path / f"r{suffix}", recordings)
    _assert_same(bw.load_recordings(tmp_path / f"r{suffix}")[1], recordings[1])


def test_folders_include_tdms_and_hdf5(tmp_path: Path, recordings: list[bw.Recording]) -> None:
    bw.save(tmp_path / "a.tdms", recordings[:1])
    bw.save(tmp_path / "b.h5", recordings[1:])
    bw.save(tmp_path / "c.csv", recordings[0])
    assert [r.frequency for r in bw.load_recordings(tmp_path)] == [2.0, 5.0, 2.0]


# --------------------------------------------------------------------------------------------------
# TDMS lab files: groups, channel mapping, waveform properties
# --------------------------------------------------------------------------------------------------


def test_tdms_lab_file_reads_each_group_with_the_mapped_channels(tmp_path: Path) -> None:
    path = _lab_tdms(tmp_path / "lab.tdms")
    runs = _measurements(bw.load(path, columns={"u": "Disp", "y": "Force"}))
    assert [m.name for m in runs] == ["Run 1", "Run 2"]  # the Environment group holds neither: skipped
    first, second = runs
    assert isinstance(first, bw.Measurement) and isinstance(second, bw.Measurement)
    u0, y0 = _lab_signals(seed=0)
    assert np.array_equal(first.u, u0) and np.array_equal(first.y, y0)
    np.testing.assert_allclose(first.t, np.arange(u0.size) / RATE, rtol=1e-15, atol=0)
    assert dict(first.units) == {"t": "s", "u": "mm", "y": "kN"}  # from unit_string
    assert dict(first.channels) == {"u": "Disp", "y": "Force"}
    assert first.nominal_frequency == pytest.approx(2 * np.pi * 7.2)
    # A lab's 'frequency' property (in Hz here) must not turn the run into a Recording.
    assert first.metadata["operator"] == "A" and "frequency" not in first.metadata
    assert first.metadata["start_time"].startswith("2024-03-01T10:00:00")
    assert np.array_equal(second.u, _lab_signals(seed=1)[0]) and dict(second.units) == {"t": "s"}


def test_tdms_group_channel_path_pins_one_experiment(tmp_path: Path) -> None:
    path = _lab_tdms(tmp_path / "lab.tdms")
    (m,) = bw.load(path, columns={"u": "Run 2/Disp", "y": "Run 2/Force"})
    assert isinstance(m, bw.Measurement) and m.name == "Run 2"
    assert np.array_equal(m.y, _lab_signals(seed=1)[1])


def test_tdms_channel_names_with_a_slash_are_names_not_paths(tmp_path: Path) -> None:
    u, y = _lab_signals()
    wf = {"wf_increment": 1.0 / RATE}
    path = _write_tdms(tmp_path / "s.tdms", {"g": {"Disp/mm": (u, wf), "Force/kN": (y, wf)}})
    (m,) = _measurements(bw.load(path, columns={"u": "Disp/mm", "y": "Force/kN"}))
    assert np.array_equal(m.y, y) and dict(m.channels) == {"u": "Disp/mm", "y": "Force/kN"}
    (same,) = bw.load(path, columns={"u": "g/Disp/mm", "y": "g/Force/kN"})
    assert np.array_equal(same.y, y)


def test_tdms_time_channel_and_sample_rate_argument(tmp_path: Path) -> None:
    u, y = _lab_signals()
    t = 5.0 + np.arange(u.size) / RATE
    path = _write_tdms(tmp_path / "t.tdms", {"g": {"time": (t, {}), "u": (u, {}), "y": (y, {})}})
    (m,) = _measurements(bw.load(path, columns={"t": "time"}))
    assert np.array_equal(m.t, t) and m.channels["t"] == "time"
    bare = _write_tdms(tmp_path / "bare.tdms", {"g": {"u": (u, {}), "y": (y, {})}})
    (m,) = _measurements(bw.load(bare, sample_rate=250.0))
    assert m.sample_rate == pytest.approx(250.0)
    with pytest.raises(FileFormatError, match="disagrees"):
        bw.load(_lab_tdms(tmp_path / "lab.tdms"), columns={"u": "Disp", "y": "Force"}, sample_rate=999.0)


# --------------------------------------------------------------------------------------------------
# HDF5 lab files
# --------------------------------------------------------------------------------------------------


def test_hdf5_root_datasets_with_a_rate_attribute(tmp_path: Path) -> None:
    u, y = _lab_signals()
    path = _write_h5(
        tmp_path / "root.h5",
        {"disp": u, "force": y.reshape(-1, 1)},  # a column matrix reads as a vector
        {"": {"fs": RATE, "rig": "B"}, "disp": {"units": b"mm"}},
    )
    (m,) = bw.load(path, columns={"u": "disp", "y": "force"})
    assert isinstance(m, bw.Measurement) and m.name == "root"
    assert np.array_equal(m.y, y) and m.sample_rate == pytest.approx(RATE)
    assert dict(m.units) == {"t": "s", "u": "mm"}


def test_hdf5_groups_time_dataset_and_paths(tmp_path: Path) -> None:
    u, y = _lab_signals()
    t = np.arange(u.size) / RATE
    path = _write_h5(
        tmp_path / "runs.h5",
        {"runs/a/t": t, "runs/a/u": u, "runs/a/y": y, "runs/b/u": u, "runs/b/y": 2 * y, "info/gain": [1.0]},
        {"runs/b": {"dt": 2.0 / RATE, "operator": "C"}},
    )
    a, b = _measurements(bw.load(path))
    assert (a.name, b.name) == ("a", "b") and np.array_equal(a.t, t)
    assert b.sample_rate == pytest.approx(RATE / 2) and b.metadata == {"operator": "C"}
    (only,) = bw.load(path, columns={"u": "/runs/b/u", "y": "runs/b/y"})
    assert np.array_equal(only.y, 2 * y)


# --------------------------------------------------------------------------------------------------
# Malformed files: the error class, the file and the fault
# --------------------------------------------------------------------------------------------------

Writer = Callable[[Path, dict[str, np.ndarray], dict[str, Any]], Path]


def _tdms_one(path: Path, chans: dict[str, np.ndarray], props: dict[str, Any]) -> Path:
    return _write_tdms(path, {"g": {c: (d, dict(props)) for c, d in chans.items()}})


def _h5_one(path: Path, chans: dict[str, np.ndarray], props: dict[str, Any]) -> Path:
    # h5py stores text as bytes: a lab's string column arrives as an 'S' dataset.
    data = {f"g/{c}": d.astype("S") if d.dtype.kind == "U" else d for c, d in chans.items()}
    return _write_h5(path, data, {f"g/{c}": props for c in chans})


FORMATS: dict[str, Writer] = {".tdms": _tdms_one, ".h5": _h5_one}
RATE_PROPS = {"wf_increment": 1.0 / RATE}


def _good() -> dict[str, np.ndarray]:
    u, y = _lab_signals()
    return {"u": u, "y": y}


# fault -> (how to make the file from the writer, expected error class, words the message must hold)
FAULTS: dict[str, tuple[Callable[[Writer, Path], Path], type[Exception], str]] = {
    "not a container": (
        lambda w, p: (p.write_bytes(b"t,u,y\n0,1,2\n" * 20), p)[1],
        FileFormatError,
        "not a readable",
    ),
    "truncated": (
        lambda w, p: (p.write_bytes(w(p, _good(), RATE_PROPS).read_bytes()[:-1500]), p)[1],
        FileFormatError,
        "",  # the TDMS and HDF5 wordings differ; the file name is still required
    ),
    "empty file": (lambda w, p: (p.write_bytes(b""), p)[1], FileFormatError, ""),
    "missing channel": (
        lambda w, p: w(p, {"u": _good()["u"], "force": _good()["y"]}, RATE_PROPS),
        FileFormatError,
        "'y'",
    ),
    "unequal lengths": (
        lambda w, p: w(p, {"u": _good()["u"], "y": _good()["y"][:-7]}, RATE_PROPS),
        FileFormatError,
        "unequal lengths",
    ),
    "non-numeric": (
        lambda w, p: w(p, {"u": _good()["u"], "y": np.array(["a"] * 400)}, RATE_PROPS),
        FileFormatError,
        "not real numbers",
    ),
    "NaN": (
        lambda w, p: w(
            p, {"u": _good()["u"], "y": np.where(np.arange(400) == 9, np.nan, _good()["y"])}, RATE_PROPS
        ),
        NonFiniteError,
        "non-finite value (nan) at index 9",
    ),
    "missing rate": (lambda w, p: w(p, _good(), {}), FileFormatError, "no sample rate"),
    "bad rate attribute": (
        lambda w, p: w(p, _good(), {"wf_increment": 0.0}),
        FileFormatError,
        "positive step",
    ),
    "time not increasing": (
        lambda w, p: w(p, {**_good(), "t": np.r_[np.arange(399) / RATE, 0.1]}, {}),
        TimeAxisError,
        "",
    ),
}


@pytest.mark.parametrize("fault", sorted(FAULTS))
@pytest.mark.parametrize("suffix", sorted(FORMATS))
def test_malformed_files_raise_named_errors(
    tmp_path: Path, suffix: str, fault: str, capsys: pytest.CaptureFixture[str]
) -> None:
    make, error, words = FAULTS[fault]
    path = make(FORMATS[suffix], tmp_path / f"bad{suffix}")
    with pytest.raises(error) as info:
        bw.load(path)
    message = str(info.value)
    assert str(path) in message and words in message, message
    # The CLI refuses the same file with the same error, on one line (exit status 2), not a traceback.
    assert cli.main(["identify", str(path), "--out", str(tmp_path / "rep")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"error: {type(info.value).__name__}: ") and str(path) in err


def test_channels_at_different_rates_are_refused(tmp_path: Path) -> None:
    u, y = _lab_signals()
    path = _write_tdms(
        tmp_path / "rates.tdms", {"g": {"u": (u, {"wf_increment": 1e-3}), "y": (y, {"wf_increment": 2e-3})}}
    )
    with pytest.raises(FileFormatError, match="different rates") as info:
        bw.load(path)
    assert str(path) in str(info.value)


def test_a_mapped_channel_that_is_missing_lists_what_the_file_has(tmp_path: Path) -> None:
    path = _lab_tdms(tmp_path / "lab.tdms")
    with pytest.raises(FileFormatError) as info:
        bw.load(path, columns={"u": "Displacement", "y": "Force"})
    message = str(info.value)
    assert str(path) in message and "group 'Run 1': no channel 'Displacement'" in message
    assert "the group has 'Disp', 'Force'" in message
    with pytest.raises(FileFormatError, match="no channel 'Run 3/Disp'"):
        bw.load(path, columns={"u": "Run 3/Disp", "y": "Run 1/Force"})
    with pytest.raises(FileFormatError, match="column indices apply to CSV"):
        bw.load(path, columns={"u": 0, "y": 1})


# --------------------------------------------------------------------------------------------------
# End to end: identification from TDMS and HDF5 files
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("suffix", [".tdms", ".h5"])
def test_identification_from_a_file_equals_identification_from_memory(
    tmp_path: Path, suffix: str, recordings: list[bw.Recording]
) -> None:
    path = tmp_path / f"recs{suffix}"
    bw.save(path, recordings)
    from_file = bw.identify(bw.load_recordings(path), method="paper")
    direct = bw.identify(recordings, method="paper")
    assert (from_file.beta, from_file.gamma, from_file.mu) == (direct.beta, direct.gamma, direct.mu)


def test_cli_identifies_lab_measurements_from_tdms_with_a_channel_mapping(tmp_path: Path) -> None:
    """Lab runs (no header, NI waveform channels) through ``bouc-wen-id identify --columns``."""
    plant = bw.demo_plant()
    groups: dict[str, dict[str, tuple[Any, dict[str, Any]]]] = {}
    for i, omega in enumerate((2.0, 5.0)):
        fs = 64 * omega / (2 * np.pi) * 1.013  # not a whole number of samples per period
        t = np.arange(int(10 * 2 * np.pi / omega * fs)) / fs
        amp = float(bw.demo.design_amplitudes(plant, [omega])[0])
        u = amp * np.cos(omega * t)
        y = bw.simulate_input(plant, t, u)[1] + np.random.default_rng(i).normal(0, 0.005, t.size)
        props = {"wf_increment": 1.0 / fs, "unit_string": "mm"}
        groups[f"run {i}"] = {"Disp": (u, props), "Force": (y, {"wf_increment": 1.0 / fs})}
    path = _write_tdms(tmp_path / "lab.tdms", groups)
    out = tmp_path / "rep"
    code = cli.main(["identify", str(path), "--columns", "u=Disp", "y=Force", "--out", str(out)])
    assert code == 0
    result = json.loads((out / "result.json").read_text())
    assert len(result["experiments"]) == 2
    truth = plant.normalized().hysteresis
    assert result["mu"] == pytest.approx(truth.mu, rel=0.05)


# --------------------------------------------------------------------------------------------------
# pandas frames
# --------------------------------------------------------------------------------------------------


def test_measurement_frame_round_trip() -> None:
    m = _measurement(3)
    df = m.to_dataframe()
    assert list(df.columns) == ["u", "y"] and df.index.name == "t"
    df.loc[df.index[0], "u"] = 1e9  # the frame's columns are copies: editing them leaves m alone
    assert m.u[0] != 1e9
    back = bw.Measurement.from_dataframe(m.to_dataframe())
    _assert_same(m, back)


def test_from_dataframe_datetime_index_and_time_columns() -> None:
    u, y = _lab_signals()
    stamps = pd.date_range("2024-03-01 10:00", periods=u.size, freq="1ms", tz="Europe/Madrid")
    lab = pd.DataFrame({"disp": u, "force": y}, index=stamps)
    lab.attrs["units"] = {"disp": "mm", "force": "kN", "other": "V"}
    m = bw.Measurement.from_dataframe(lab, input="disp", output="force", name="run")
    np.testing.assert_allclose(m.t, np.arange(u.size) / RATE, rtol=0, atol=1e-12)
    assert dict(m.units) == {"t": "s", "u": "mm", "y": "kN"}
    assert dict(m.channels) == {"u": "disp", "y": "force"} and m.name == "run"
    flat = lab.reset_index(names="when")
    by_column = bw.Measurement.from_dataframe(flat, input="disp", output="force", time="when")
    assert np.array_equal(by_column.t, m.t) and by_column.channels["t"] == "when"
    seconds = flat.assign(sec=np.arange(u.size) / RATE + 3.0)
    assert bw.Measurement.from_dataframe(seconds, input="disp", output="force", time="sec").t[0] == 3.0
    by_rate = bw.Measurement.from_dataframe(flat, input="disp", output="force", sample_rate=500.0)
    assert by_rate.sample_rate == pytest.approx(500.0)


def test_from_dataframe_leaves_the_frame_unchanged() -> None:
    u, y = _lab_signals()
    lab = pd.DataFrame({"disp": u, "force": y, "note": ["x"] * u.size}, index=np.arange(u.size) / RATE)
    lab.attrs["units"] = {"disp": "mm"}
    before = lab.copy(deep=True)
    attrs = copy.deepcopy(lab.attrs)
    m = bw.Measurement.from_dataframe(lab, input="disp", output="force")
    assert lab.equals(before) and lab.attrs == attrs and list(lab.columns) == ["disp", "force", "note"]
    assert not np.shares_memory(m.u, lab["disp"].to_numpy())


@pytest.mark.parametrize(
    ("frame", "kwargs", "error", "words"),
    [
        ("lab", {"input": "Disp"}, InvalidParameterError, "no column 'Disp' for 'u'"),
        ("lab", {"output": "note"}, InvalidParameterError, "y (column 'note') holds"),
        ("nan", {}, NonFiniteError, "y (column 'force') holds a non-finite value (nan) at index 5"),
        ("range", {}, InvalidParameterError, "RangeIndex"),
        ("filtered", {}, InvalidParameterError, "integers (row numbers, a Index)"),
        ("lab", {"sample_rate": 10.0}, InvalidParameterError, "sample_rate= is for a frame indexed by row"),
        ("shuffled", {}, TimeAxisError, ""),
        ("nat", {"time": "when"}, NonFiniteError, "NaT"),
        ("dup", {}, InvalidParameterError, "more than once"),
    ],
)
def test_from_dataframe_refuses_bad_frames(
    frame: str, kwargs: dict[str, Any], error: type[Exception], words: str
) -> None:
    u, y = _lab_signals()
    lab = pd.DataFrame({"disp": u, "force": y, "note": ["x"] * u.size}, index=np.arange(u.size) / RATE)
    frames = {
        "lab": lab,
        "nan": lab.assign(force=np.where(np.arange(u.size) == 5, np.nan, y)),
        "range": lab.reset_index(drop=True),
        "filtered": lab.reset_index(drop=True).drop(index=3),  # rows dropped: no longer a RangeIndex
        "shuffled": lab.iloc[::-1],
        "nat": lab.reset_index(drop=True).assign(when=pd.NaT),
        "dup": pd.concat([lab[["disp"]], lab[["force"]].rename(columns={"force": "disp"})], axis=1),
    }
    args: dict[str, Any] = {"input": "disp", "output": "force", **kwargs}
    with pytest.raises(error) as info:
        bw.Measurement.from_dataframe(frames[frame], **args)
    assert words in str(info.value)
    with pytest.raises(InvalidParameterError, match="must be a pandas DataFrame"):
        bw.Measurement.from_dataframe(lab.to_dict(), **args)


@pytest.mark.filterwarnings("ignore::bouc_wen_id.errors.IdentifiabilityWarning")  # 2 short periods: the
# table's content is under test, not the data's information
def test_result_to_dataframe(recordings: list[bw.Recording]) -> None:
    result = bw.identify(recordings, method="refined")
    df = result.to_dataframe()
    assert list(df.index) == [0, 1] and df.index.name == "experiment"
    np.testing.assert_array_equal(df["frequency"], result.frequencies)
    np.testing.assert_array_equal(df["gain"], result.gains)
    np.testing.assert_array_equal(df["phase"], result.phases)
    z = bw.validation.z_value(result.confidence)
    for i, e in enumerate(result.experiments):
        assert df.loc[i, "gain_se"] == e.gain_se and df.loc[i, "offset"] == e.offset
        assert e.gain_se is not None
        assert df.loc[i, "gain_high"] - df.loc[i, "gain_low"] == pytest.approx(2 * z * e.gain_se)
    assert result.truth is not None
    np.testing.assert_array_equal(df["gain_true"], result.truth.gain)
    se = result.standard_errors
    assert se is not None
    assert df.attrs["mu"] == result.mu and df.attrs["mu_se"] == se["mu"]
    assert (df.attrs["beta_low"], df.attrs["beta_high"]) == pytest.approx(result.interval("beta"))
    paper = bw.identify(recordings, method="paper").to_dataframe()
    assert paper["gain_se"].isna().all() and np.isnan(paper.attrs["gamma_se"])


# --------------------------------------------------------------------------------------------------
# Optional dependencies
# --------------------------------------------------------------------------------------------------


def test_import_does_not_load_the_optional_packages() -> None:
    code = (
        "import sys, bouc_wen_id; print(sorted(m for m in ('pandas', 'nptdms', 'h5py') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


@pytest.mark.parametrize(
    ("module", "extra", "call"),
    [
        ("nptdms", "tdms", lambda p: bw.load(p / "x.tdms")),
        ("h5py", "hdf5", lambda p: bw.load(p / "x.h5")),
        ("pandas", "pandas", lambda p: _measurement().to_dataframe()),
    ],
)
def test_a_missing_optional_package_says_which_extra_installs_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, module: str, extra: str, call: Callable[[Path], Any]
) -> None:
    (tmp_path / "x.tdms").write_bytes(b"")
    (tmp_path / "x.h5").write_bytes(b"")
    monkeypatch.setitem(sys.modules, module, None)  # import now fails, as if not installed
    with pytest.raises(ImportError, match=rf"pip install 'bouc_wen_id\[{extra}\]'"):
        call(tmp_path)


@pytest.mark.parametrize("suffix", [".tdms", ".h5"])
def test_channel_sizes_are_checked_against_the_budget_before_reading(
    tmp_path: Path, suffix: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = FORMATS[suffix](tmp_path / f"big{suffix}", _good(), RATE_PROPS)
    reads: list[str] = []
    original = _common._array

    def counted(where: str, key: str, value: Any) -> Any:
        reads.append(key)
        return original(where, key, value)

    monkeypatch.setattr(_containers, "_array", counted)  # where the TDMS and HDF5 readers find it
    with bw.budget.budget(max_samples=399), pytest.raises(bw.BudgetExceededError) as info:
        bw.load(path)
    assert str(path) in str(info.value) and reads == []  # refused from the sizes the file declares
    assert len(bw.load(path)[0].u) == 400 and reads
