"""Property-based fuzzing: random and malformed inputs to the loaders, Measurement, the core and identify.

The only outcomes allowed are a correct result or a named error (a :class:`bouc_wen_id.BoucWenIdError`
subclass): never a Rust panic (pyo3 raises it as ``pyo3_runtime.PanicException``, a ``BaseException``, so
the harness catches ``BaseException``), never another exception type, never a warning escaping the library
(pytest turns warnings into errors), never a silent NaN in an output that claims success, never a hang
(sizes are small).  Failures found by this fuzzing that are not fixed yet are pinned below as strict xfails
with their exact inputs.

Every test is derandomized (the same examples on every run, no example database written);
``BOUC_WEN_ID_FUZZ=<factor>`` multiplies the example counts and draws fresh random examples, for a deeper
run by hand.
"""

from __future__ import annotations

import io as _stdio
import json
import math
import os
import struct
import tempfile
import warnings
import zlib
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable

import bouc_wen_id as bw
import hypothesis.extra.numpy as hnp
import numpy as np
import pytest
import scipy.io  # type: ignore[import-untyped]
from bouc_wen_id import _core, io
from bouc_wen_id.errors import (
    BoucWenIdError,
    ClippingError,
    ConvergenceWarning,
    DistortedInputWarning,
    IdentifiabilityWarning,
    InvalidParameterError,
    ZeroAmplitudeError,
)
from bouc_wen_id.measurement import RESERVED_KEYS, Measurement, clipping_check
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

FACTOR = float(os.environ.get("BOUC_WEN_ID_FUZZ", "0") or 0)


def fuzz(examples: int) -> Callable[[Callable[..., None]], Callable[..., None]]:
    """Hypothesis settings: bounded, no deadline, no database, derandomized unless BOUC_WEN_ID_FUZZ is set."""
    return settings(
        max_examples=max(1, int(examples * FACTOR)) if FACTOR else examples,
        deadline=None,
        database=None,
        derandomize=not FACTOR,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much],
    )


def call(fn: Callable[..., Any], *args: Any, **kwargs: Any) -> tuple[bool, Any]:
    """``(True, result)``, or ``(False, error)`` for a named error; anything else fails the example.

    Warnings the library raises on purpose about the data (identifiability, distorted input, a refinement
    stopped at its cap) are allowed;
    any other warning (e.g. a NumPy overflow) is an error, as under pytest's filterwarnings=error.
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            warnings.simplefilter("ignore", IdentifiabilityWarning)
            warnings.simplefilter("ignore", DistortedInputWarning)
            warnings.simplefilter("ignore", ConvergenceWarning)
            return True, fn(*args, **kwargs)
    except BoucWenIdError as exc:
        return False, exc
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as exc:  # pyo3's PanicException derives from BaseException
        shown = ", ".join([_short(a) for a in args] + [f"{k}={_short(v)}" for k, v in kwargs.items()])
        kind = f"{type(exc).__module__}.{type(exc).__name__}"
        raise AssertionError(f"{getattr(fn, '__name__', fn)}({shown}) raised {kind}: {exc}") from exc


def _short(v: Any) -> str:
    if isinstance(v, np.ndarray):
        return f"array(shape={v.shape}, dtype={v.dtype}, head={np.array2string(v.ravel()[:6])})"
    text = repr(v)
    return text if len(text) < 200 else text[:200] + "..."


def finite(*values: Any) -> bool:
    return all(bool(np.all(np.isfinite(np.asarray(v, dtype=np.float64)))) for v in values)


@contextmanager
def scratch() -> Iterator[Path]:
    with tempfile.TemporaryDirectory() as d:
        yield Path(d)


def check_items(items: Any) -> None:
    """What a loader returns on success: valid experiments with finite, equally long, frozen arrays."""
    assert isinstance(items, list)
    for item in items:
        assert isinstance(item, (bw.Recording, Measurement)), type(item)
        assert item.t.size == item.u.size == item.y.size >= 2
        assert finite(item.t, item.u, item.y)
        assert np.all(np.diff(item.t) > 0)
        assert not item.u.flags.writeable


# --------------------------------------------------------------------------------------------------
# Strategies
# --------------------------------------------------------------------------------------------------

SPECIAL = [math.nan, math.inf, -math.inf, 0.0, -0.0, 5e-324, -1e-310, 1e308, -1e308]
#: Finite values of a scale that does not overflow the arithmetic of a loop (see the xfails below).
BOUNDED = st.floats(-1e100, 1e100, allow_nan=False, allow_infinity=False)
ANY_FLOAT = st.one_of(st.floats(), st.sampled_from(SPECIAL))
#: Parameters of the core routines: any scale up to 1e100, and the non-finite values (named errors).
PARAM = st.one_of(BOUNDED, st.sampled_from([math.nan, math.inf, -math.inf, 0.0, -0.0, 5e-324]))
JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(st.text(max_size=6), inner, max_size=3),
    max_leaves=6,
)
HEADER_KEYS = sorted(RESERVED_KEYS) + ["note", "operator", "units", "name", "t", "u"]
CELLS = st.one_of(
    BOUNDED.map(lambda v: f"{v!r}"),
    st.integers(-(10**6), 10**6).map(str),
    st.sampled_from(["nan", "inf", "-inf", "", "abc", "1e999", "0x10", "1_0", " 3 ", '"4"', "#", "1,2"]),
)
COLUMN_NAMES = st.sampled_from(["t", "u", "y", "x", "w", "disp", "force", "", '"u"', "t"])
DELIMITERS = st.sampled_from([",", ";", "\t", " "])
COLUMNS_ARG = st.one_of(
    st.none(),
    st.dictionaries(
        st.sampled_from(["t", "u", "y", "x", "w", "force"]),
        st.one_of(st.sampled_from(["t", "u", "y", "disp", "force", "nope"]), st.integers(-1, 6)),
        max_size=3,
    ),
)
RATE_ARG = st.one_of(st.none(), st.floats(), st.sampled_from([1000.0, 0.0, -5.0]))


@st.composite
def csv_texts(draw: st.DrawFn) -> str:
    """CSV-ish text: header lines (valid JSON or not), a column line (or none), rows of odd cells."""
    lines: list[str] = []
    for _ in range(draw(st.integers(0, 5))):
        if draw(st.booleans()):
            lines.append(f"# {draw(st.sampled_from(HEADER_KEYS))}: {json.dumps(draw(JSON))}")
        else:
            lines.append("#" + draw(st.text(max_size=20)))
    delim = draw(DELIMITERS)
    if draw(st.booleans()):
        lines.append(delim.join(draw(st.lists(COLUMN_NAMES, max_size=5))))
    width = draw(st.integers(0, 5))
    for _ in range(draw(st.integers(0, 25))):
        n = width if draw(st.integers(0, 9)) else draw(st.integers(0, 6))  # mostly rectangular
        lines.append(delim.join(draw(st.lists(CELLS, min_size=n, max_size=n))))
    return draw(st.sampled_from(["\n", "\r\n"])).join(lines) + draw(st.sampled_from(["", "\n"]))


def float_arrays(
    max_size: int = 40, elements: st.SearchStrategy[float] = ANY_FLOAT
) -> st.SearchStrategy[Any]:
    return hnp.arrays(np.float64, st.integers(0, max_size), elements=elements)


CONTAINER_VALUES = st.one_of(
    float_arrays(),
    hnp.arrays(np.int16, st.integers(0, 30)),
    hnp.arrays(np.float64, st.tuples(st.integers(1, 4), st.integers(1, 8)), elements=BOUNDED),
    st.just(np.array(["a", "bc"])),
    st.just(np.float64(1000.0)),
    st.just(np.arange(25.0) * 0.01),
    st.just(np.sin(np.arange(25.0))),
)
CONTAINER_NAMES = st.sampled_from(["t", "u", "y", "x", "w", "t_0", "u_0", "y_0", "u_1", "y_1", "fs", "disp"])


@st.composite
def metas(draw: st.DrawFn) -> str:
    """A ``meta`` JSON string: a list of headers, one header, or anything JSON (or not JSON at all)."""
    header = st.dictionaries(st.sampled_from(HEADER_KEYS), JSON, max_size=4)
    choice = draw(st.integers(0, 3))
    if choice == 0:
        return json.dumps(draw(st.lists(header, max_size=3)))
    if choice == 1:
        return json.dumps(draw(header))
    if choice == 2:
        return json.dumps(draw(JSON))
    return draw(st.text(max_size=20))


# --------------------------------------------------------------------------------------------------
# Loaders
# --------------------------------------------------------------------------------------------------


def _valid_files() -> dict[str, bytes]:
    """Bytes of valid files of every format, to be mutated."""
    t = np.arange(24) * 0.01
    m = Measurement(t, np.sin(t), np.cos(t), units={"u": "mm"}, name="seed", metadata={"k": "v"})
    out: dict[str, bytes] = {}
    with scratch() as d:
        io.write_csv(d / "a.csv", m)
        io.write_npz(d / "a.npz", [m, m])
        io.write_mat(d / "a.mat", [m])
        io.write_mat(d / "b.mat", [m, m])
        scipy.io.savemat(d / "c.mat", {"u": np.sin(t), "y": np.cos(t), "fs": 100.0}, do_compression=False)
        for f in sorted(d.iterdir()):
            out[f.name] = f.read_bytes()
    return out


VALID = _valid_files()


def _mutate_inflated(data: bytes, edits: list[tuple[int, int]], cut: int | None) -> bytes:
    out, pos = bytearray(data[:128]), 128
    while pos + 8 <= len(data):
        code, count = struct.unpack_from("<II", data, pos)
        raw = bytearray(zlib.decompress(data[pos + 8 : pos + 8 + count]))
        for at, byte in edits:
            raw[at % len(raw)] = byte
        if cut is not None:
            raw = raw[: cut % (len(raw) + 1)]
        body = zlib.compress(bytes(raw))
        out += struct.pack("<II", code, len(body)) + body
        pos += 8 + count
    return bytes(out)


@fuzz(150)
@given(blob=st.binary(max_size=1024), suffix=st.sampled_from([".csv", ".npz", ".mat"]))
def test_random_bytes(blob: bytes, suffix: str) -> None:
    with scratch() as d:
        path = d / f"f{suffix}"
        path.write_bytes(blob)
        ok, out = call(io.load, path)
        if ok:
            check_items(out)


@fuzz(200)
@given(
    name=st.sampled_from(sorted(VALID)),
    edits=st.lists(
        st.tuples(
            st.integers(0, 10**6), st.one_of(st.integers(0, 255), st.sampled_from([0, 1, 8, 10, 14, 15]))
        ),
        max_size=8,
    ),
    cut=st.one_of(st.none(), st.integers(0, 10**6)),
)
def test_mutated_valid_files(name: str, edits: list[tuple[int, int]], cut: int | None) -> None:
    data = bytearray(VALID[name])
    if name.endswith(".mat") and data[128:132] == bytes([15, 0, 0, 0]):
        # Compressed MAT: corrupt the inflated variables and recompress, or zlib catches every edit.
        data = bytearray(_mutate_inflated(bytes(data), edits, cut))
    else:
        for pos, byte in edits:
            data[pos % len(data)] = byte
        if cut is not None:
            data = data[: cut % (len(data) + 1)]
    with scratch() as d:
        path = d / name
        path.write_bytes(bytes(data))
        ok, out = call(io.load, path)
        if ok:
            check_items(out)


@fuzz(250)
@given(text=st.one_of(csv_texts(), st.text(max_size=200)), columns=COLUMNS_ARG, rate=RATE_ARG)
def test_csv_like_text(text: str, columns: Any, rate: Any) -> None:
    with scratch() as d:
        path = d / "f.csv"
        path.write_text(text, encoding="utf-8")
        ok, out = call(io.load, path, columns=columns, sample_rate=rate)
        if ok:
            check_items(out)


@fuzz(120)
@given(
    arrays=st.dictionaries(CONTAINER_NAMES, CONTAINER_VALUES, max_size=5),
    meta=st.one_of(st.none(), metas()),
    columns=COLUMNS_ARG,
    rate=RATE_ARG,
)
def test_npz_contents(arrays: dict[str, Any], meta: str | None, columns: Any, rate: Any) -> None:
    if meta is not None:
        arrays = {**arrays, "meta": np.array(meta)}
    buf = _stdio.BytesIO()
    np.savez(buf, **arrays)
    with scratch() as d:
        path = d / "f.npz"
        path.write_bytes(buf.getvalue())
        ok, out = call(io.load, path, columns=columns, sample_rate=rate)
        if ok:
            check_items(out)


@fuzz(100)
@given(
    variables=st.dictionaries(
        st.sampled_from(["t", "u", "y", "x", "fs", "sample_rate", "disp"]), CONTAINER_VALUES
    ),
    meta=st.one_of(st.none(), metas()),
    experiments=st.one_of(
        st.none(),
        st.lists(
            st.dictionaries(
                st.sampled_from(["t", "u", "y", "fs", "meta"]),
                st.one_of(CONTAINER_VALUES, metas()),
                min_size=1,
                max_size=4,
            ),
            max_size=3,
        ),
    ),
    columns=COLUMNS_ARG,
)
def test_mat_contents(
    variables: dict[str, Any], meta: str | None, experiments: list[dict[str, Any]] | None, columns: Any
) -> None:
    contents: dict[str, Any] = dict(variables)
    if meta is not None:
        contents["meta"] = meta
    if experiments is not None:
        cell = np.empty((1, len(experiments)), dtype=object)
        for i, e in enumerate(experiments):
            cell[0, i] = e
        contents["experiments"] = cell
    with scratch() as d:
        path = d / "f.mat"
        scipy.io.savemat(path, contents)
        ok, out = call(io.load, path, columns=columns)
        if ok:
            check_items(out)


# --------------------------------------------------------------------------------------------------
# Round trips of arbitrary valid measurements
# --------------------------------------------------------------------------------------------------

TEXT = st.text(max_size=12)
META_KEYS = st.text(min_size=1, max_size=10).filter(
    lambda k: k == k.strip() and ":" not in k and k.isprintable() and k not in RESERVED_KEYS
)


@st.composite
def measurements(draw: st.DrawFn) -> tuple[Measurement, float]:
    """A valid measurement of any values and labels, and its sample rate."""
    n = draw(st.integers(2, 40))
    values = st.floats(allow_nan=False, allow_infinity=False)
    rate = draw(st.floats(1e-3, 1e7))
    return Measurement.from_rate(
        rate,
        draw(hnp.arrays(np.float64, n, elements=values)),
        draw(hnp.arrays(np.float64, n, elements=values)),
        nominal_frequency=draw(st.one_of(st.none(), st.floats(1e-6, 1e9))),
        units=draw(st.dictionaries(st.sampled_from(["u", "y"]), TEXT, max_size=2)),
        channels=draw(st.dictionaries(st.sampled_from(["t", "u", "y"]), TEXT, max_size=3)),
        name=draw(TEXT),
        metadata=draw(st.dictionaries(META_KEYS, TEXT, max_size=3)),
    ), rate


@fuzz(60)
@given(mr=measurements(), target=st.sampled_from(["m.csv", "rate.csv", "m.npz", "m.mat", "b.mat"]))
def test_any_measurement_round_trips_exactly(mr: tuple[Measurement, float], target: str) -> None:
    m, rate = mr
    with scratch() as d:
        path = d / target
        if target == "rate.csv":
            io.write_csv(path, m, sample_rate=rate)
        elif target == "b.mat":
            io.write_mat(path, [m], bundle=True)
        else:
            io.save(path, [m])
        (back,) = io.load(path)
    assert isinstance(back, Measurement)
    for name in ("t", "u", "y"):
        assert np.array_equal(getattr(back, name), getattr(m, name)), name
    assert (back.name, back.nominal_frequency) == (m.name, m.nominal_frequency)
    assert dict(back.units) == dict(m.units) and dict(back.channels) == dict(m.channels)
    assert dict(back.metadata) == dict(m.metadata)


# --------------------------------------------------------------------------------------------------
# Measurement and the clipping check
# --------------------------------------------------------------------------------------------------


@st.composite
def time_axes(draw: st.DrawFn) -> Any:
    n = draw(st.integers(0, 40))
    kind = draw(st.integers(0, 3))
    if kind == 0:  # uniform, with a small or large jitter
        dt = draw(st.floats(1e-9, 1e3))
        jitter = draw(hnp.arrays(np.float64, n, elements=st.floats(-0.03, 0.03))) * dt
        return draw(st.floats(-1e6, 1e6)) + np.arange(n) * dt + jitter
    if kind == 1:
        return np.sort(draw(hnp.arrays(np.float64, n, elements=ANY_FLOAT)))
    return draw(hnp.arrays(np.float64, n, elements=ANY_FLOAT))


@fuzz(200)
@given(
    t=time_axes(),
    u=float_arrays(),
    y=float_arrays(),
    same_length=st.booleans(),
    nominal=st.one_of(st.none(), ANY_FLOAT, st.just(True), st.just("2 Hz")),
    units=st.one_of(
        st.none(), st.dictionaries(st.sampled_from(["t", "u", "y", "v"]), st.one_of(TEXT, st.just(3)))
    ),
    metadata=st.one_of(st.none(), st.dictionaries(st.text(max_size=6), st.one_of(TEXT, st.integers()))),
)
def test_measurement_constructor(
    t: Any, u: Any, y: Any, same_length: bool, nominal: Any, units: Any, metadata: Any
) -> None:
    if same_length:
        u, y = np.resize(u, t.shape) if u.size else np.zeros(t.shape), np.resize(y, t.shape) if y.size else t
    ok, m = call(Measurement, t, u, y, nominal_frequency=nominal, units=units, metadata=metadata)
    if not ok:
        return
    check_items([m])
    dt = np.diff(m.t)
    assert np.max(np.abs(dt - np.median(dt))) <= 0.01 * np.median(dt)
    assert m.nominal_frequency is None or (math.isfinite(m.nominal_frequency) and m.nominal_frequency > 0)
    assert math.isfinite(m.sample_rate) and m.sample_rate > 0
    ok, _ = call(m.check)


@fuzz(150)
@given(x=float_arrays(max_size=300, elements=BOUNDED), levels=st.one_of(st.none(), st.integers(2, 300)))
def test_clipping_check(x: Any, levels: int | None) -> None:
    if levels is not None and x.size and np.ptp(x) > 0:
        q = np.ptp(x) / levels
        x = np.round(x / q) * q
    call(clipping_check, x, "x")


@st.composite
def sines(
    draw: st.DrawFn, min_p: float = 12.0, min_levels: int = 8, coherent: bool = True
) -> tuple[Any, float]:
    """A sampled sine (any phase and offset; samples per period whole numbers too when ``coherent``) and
    its quantisation step."""
    whole = st.integers(int(min_p), 2000).map(float)
    fractional = st.floats(min_p, 2000.0).filter(lambda v: v != round(v))
    p = draw(st.one_of(fractional, whole) if coherent else fractional)
    n = int(p * draw(st.floats(4.0, 25.0)))
    levels = draw(st.sampled_from([v for v in (8, 16, 78, 256, 1024, 4096, 65536) if v >= min_levels]))
    q = 2.0 / levels
    k = np.arange(n)
    x = np.cos(2 * np.pi * k / p + draw(st.floats(0, 7))) + draw(st.floats(-3, 3))
    noise = draw(st.sampled_from([0.0, 0.1, 0.3, 1.0, 3.0])) * q
    x = x + noise * np.random.default_rng(draw(st.integers(0, 2**32 - 1))).standard_normal(n)
    return x, q


@fuzz(60)
@given(sine=sines())
def test_quantised_noisy_sines_are_never_called_clipped(sine: tuple[Any, float]) -> None:
    x, q = sine
    clipping_check(np.round(x / q) * q, "quantised sine")
    clipping_check(x, "sine")


@fuzz(60)
@given(sine=sines(min_p=64.0, min_levels=1024, coherent=False), rail=st.floats(0.5, 0.9), both=st.booleans())
def test_clipped_sines_are_caught(sine: tuple[Any, float], rail: float, both: bool) -> None:
    # A heavy clip of a coherently sampled sine (a whole number of samples per period, few distinct values)
    # is left out: there the sampling alone explains flat stretches (see clipping_check).
    x, q = sine
    mid = 0.5 * (x.max() + x.min())
    x = np.clip(x, mid - rail if both else -np.inf, mid + rail)
    with pytest.raises(ClippingError):
        clipping_check(np.round(x / q) * q, "clipped")


# --------------------------------------------------------------------------------------------------
# The core estimators
# --------------------------------------------------------------------------------------------------

SMALL_INT = st.integers(-3, 70)


@fuzz(200)
@given(
    y=float_arrays(200, elements=st.one_of(BOUNDED, st.sampled_from(SPECIAL[:3]))),
    p=SMALL_INT,
    s=st.integers(-2, 10),
    n=st.integers(-2, 20),
)
def test_periodic_average(y: Any, p: int, s: int, n: int) -> None:
    ok, ybar = call(_core.periodic_average, y, p, s, n)
    if ok:
        ybar = np.asarray(ybar)
        assert ybar.shape == (p,)
        window = y[s * p : (s + n) * p]
        assert finite(ybar) or not finite(window)
        if finite(window):
            np.testing.assert_allclose(ybar, window.reshape(n, p).mean(axis=0), rtol=1e-12, atol=1e-300)


@fuzz(150)
@given(ybar=float_arrays(80))
def test_phase_from_max(ybar: Any) -> None:
    ok, phi = call(_core.phase_from_max, ybar)
    if ok:
        assert math.isfinite(phi) and 0.0 <= phi < 2 * math.pi


@fuzz(200)
@given(
    ybar=float_arrays(80, elements=st.one_of(BOUNDED, st.sampled_from(SPECIAL[:3]))),
    omega=st.one_of(st.floats(1e-3, 1e3), PARAM),
    harmonics=st.integers(-2, 45),
)
def test_spectral_derivative(ybar: Any, omega: float, harmonics: int) -> None:
    ok, ydot = call(_core.spectral_derivative, ybar, omega, harmonics)
    if ok:
        assert np.asarray(ydot).shape == ybar.shape
        assert finite(ydot), "a finite input gave a non-finite derivative"


@st.composite
def loops(draw: st.DrawFn) -> tuple[Any, Any]:
    """An averaged period and its derivative: random, or a hysteresis-like loop with noise."""
    p = draw(st.integers(0, 48))
    if draw(st.booleans()):
        return (
            draw(hnp.arrays(np.float64, p, elements=st.one_of(BOUNDED, st.sampled_from(SPECIAL[:3])))),
            draw(hnp.arrays(np.float64, p, elements=st.one_of(BOUNDED, st.sampled_from(SPECIAL[:3])))),
        )
    p = max(p, 8)
    k = np.arange(p)
    ybar = np.tanh(draw(st.floats(0.1, 10)) * np.cos(2 * np.pi * k / p - draw(st.floats(0, 7))))
    ybar = ybar + draw(hnp.arrays(np.float64, p, elements=st.floats(-0.2, 0.2)))
    return ybar, np.asarray(_core.spectral_derivative(ybar, 1.0, (p - 1) // 2))


@fuzz(150)
@given(
    loop=loops(),
    amplitude=st.one_of(st.floats(-10, 10), PARAM),
    omega=st.one_of(st.floats(1e-2, 1e2), PARAM),
    phi=st.one_of(st.floats(-10, 10), PARAM),
    lo=st.floats(0.5, 4.0),
    width=st.floats(-1.0, 10.0),
    tol=st.floats(1e-12, 1.0),
    max_iter=st.integers(0, 120),
)
def test_sls_search(
    loop: tuple[Any, Any],
    amplitude: float,
    omega: float,
    phi: float,
    lo: float,
    width: float,
    tol: float,
    max_iter: int,
) -> None:
    ybar, ydot = loop
    hi = lo + width
    ok, out = call(_core.sls_search, ybar, ydot, amplitude, omega, phi, lo, hi, tol, max_iter)
    if ok:
        mu, theta, cost, iterations = out
        assert lo <= mu <= hi
        assert finite(mu, theta, cost) and cost >= 0 and 1 <= iterations <= max_iter


@fuzz(200)
@given(
    amplitude=st.one_of(st.floats(-20, 20), PARAM),
    beta=st.one_of(st.floats(-2, 10), PARAM),
    gamma=st.one_of(st.floats(-10, 10), PARAM),
    mu=st.one_of(st.floats(0.5, 12), PARAM),
    phi=st.one_of(st.floats(-50, 50), PARAM),
    p=st.integers(-2, 256),
    substeps=st.integers(-1, 6),
)
def test_steady_loop(
    amplitude: float, beta: float, gamma: float, mu: float, phi: float, p: int, substeps: int
) -> None:
    ok, out = call(_core.steady_loop, amplitude, beta, gamma, mu, phi, p, substeps)
    if ok:
        w, jac, w_top, iterations = out
        assert np.asarray(w).shape == (p,) and np.asarray(jac).shape == (p, 5)
        assert finite(w, jac, w_top), "success claimed with a non-finite loop or sensitivity"
        if beta >= abs(gamma) and p * substeps >= 256:
            # Proposition 1: the steady |w| stays below (1 / (beta + gamma))^(1/mu) (alpha = 1), up to the
            # RK4 error (a coarse step, e.g. 4 samples of 1 substep, overshoots it by a few per cent).
            bound = (1.0 / (beta + gamma)) ** (1.0 / mu)
            assert np.max(np.abs(w)) <= bound * (1 + 1e-6) + 1e-12


# --------------------------------------------------------------------------------------------------
# identify on random short recordings
# --------------------------------------------------------------------------------------------------


@st.composite
def recordings(draw: st.DrawFn) -> list[bw.Recording]:
    out = []
    for _ in range(draw(st.integers(1, 2))):
        p = draw(st.integers(8, 40))  # a Recording needs 8 samples
        periods = draw(st.integers(1, 4))
        settle = draw(st.integers(0, 1))
        omega = draw(st.floats(0.05, 50.0))
        amplitude = draw(st.sampled_from([1.0, -2.0, 1e-3, 40.0]))
        t = np.arange(p * (periods + settle)) * (2 * math.pi / omega / p)
        noise = draw(st.sampled_from([0.0, 1e-3, 0.1]))
        u = amplitude * np.cos(omega * t) + noise * abs(amplitude) * np.sin(3.7 * omega * t)
        scale = draw(st.floats(1e-4, 1e4))
        shape = draw(st.sampled_from(["random", "loop", "constant", "square"]))
        if shape == "random":
            y = scale * draw(hnp.arrays(np.float64, t.size, elements=st.floats(-1, 1)))
        elif shape == "loop":
            y = scale * np.tanh(draw(st.floats(0.1, 10)) * np.cos(omega * t - draw(st.floats(0, 7))))
            y = y + noise * scale * np.cos(5.3 * omega * t + 0.2)
        elif shape == "constant":
            y = np.full(t.size, scale)
        else:
            y = scale * np.sign(np.sin(omega * t))
        out.append(bw.Recording(t, u, y, amplitude, omega, settle_periods=settle))
    return out


@fuzz(40)
@given(recs=recordings(), method=st.sampled_from(["paper", "profile", "refined"]))
def test_identify_on_random_recordings(recs: list[bw.Recording], method: str) -> None:
    ok, result = call(bw.identify, recs, method=method)
    if not ok:
        return
    assert finite(result.beta, result.gamma, result.mu, result.gains, result.phases, result.cost)
    assert np.all(result.gains >= 0) and np.all((result.phases >= 0) & (result.phases < 2 * math.pi))
    if result.standard_errors is not None and not finite(list(result.standard_errors.values())):
        # A singular Fisher matrix: allowed only with the warning that says so.
        assert result.warnings, "NaN standard errors without an identifiability warning"


# --------------------------------------------------------------------------------------------------
# Failures this fuzzing found (since fixed), pinned with their exact inputs
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(("p", "substeps"), [(2**62, 1), (2**40, 1), (2**20, 2**20)])
def test_steady_loop_huge_grid_is_a_named_error(p: int, substeps: int) -> None:
    # Was a Rust panic (capacity overflow) at 2**62 and an abort (failed 16 TiB allocation) at 2**40.
    ok, err = call(_core.steady_loop, 1.0, 1.0, 0.5, 2.0, 0.0, p, substeps)
    assert not ok and isinstance(err, InvalidParameterError), err


@pytest.mark.parametrize("search", ["golden", "sls"])
def test_golden_tolerance_below_float_resolution_is_a_named_error(search: str) -> None:
    # Was: the search ran all max_iter iterations on rounding noise (a hang for a huge max_iter).
    if search == "golden":
        ok, err = call(_core.golden_section, lambda v: (v - 2.0) ** 2, 1.0, 3.0, 1e-300, 10**12)
    else:
        t = np.arange(64) * (2 * math.pi / 64)
        ybar, ydot = np.tanh(np.cos(t)), -np.sin(t)
        ok, err = call(_core.sls_search, ybar, ydot, 1.0, 1.0, 0.0, 1.0, 3.0, 1e-300, 10**12)
    assert not ok and isinstance(err, InvalidParameterError), err


def test_spectral_derivative_does_not_overflow_silently() -> None:
    ok, ydot = call(_core.spectral_derivative, np.full(16, 1e308), 1e300, 7)
    assert not ok or finite(ydot), f"finite input, success claimed, output {ydot}"


@pytest.mark.parametrize("method", ["paper", "profile", "refined"])
def test_identify_on_a_tiny_output_is_a_named_error(method: str) -> None:
    t = np.arange(8) * (2 * math.pi / 8)
    rec = bw.Recording(t, np.cos(t), np.full(8, 4.44e-194), 1.0, 1.0)
    ok, err = call(bw.identify, [rec], method=method)  # was a ZeroDivisionError: noise_var / s_y**2
    assert not ok and isinstance(err, ZeroAmplitudeError), err


def test_steady_loop_extreme_beta_is_finite_or_a_named_error() -> None:
    ok, out = call(_core.steady_loop, 6.1457403761690284e-96, 4.49423283715579e307, 0.0, 4.0, 0.0, 4, 1)
    assert not ok or finite(out[0], out[1]), f"success claimed with jac = {out[1]}"


def test_recording_with_infinite_settle_periods_is_a_named_error() -> None:
    t = np.arange(16) * 0.1
    for bad in (math.inf, math.nan, 1.5, -1):
        ok, err = call(bw.Recording, t, np.cos(t), np.sin(t), 1.0, 2 * math.pi / 1.6, settle_periods=bad)
        assert not ok, f"settle_periods={bad} accepted"


def test_recording_with_a_non_numeric_amplitude_is_a_named_error() -> None:
    t = np.arange(16) * 0.1
    for bad in ("x", 1j, None, [1.0]):
        ok, err = call(bw.Recording, t, np.cos(t), np.sin(t), bad, 2 * math.pi / 1.6)
        assert not ok and isinstance(err, InvalidParameterError), f"amplitude={bad!r}: {err}"


def test_recording_with_complex_input_is_a_named_error() -> None:
    t = np.arange(16) * 0.1
    ok, err = call(bw.Recording, t, np.cos(t) + 0j, np.sin(t), 1.0, 2 * math.pi / 1.6)
    assert not ok and isinstance(err, InvalidParameterError), err
