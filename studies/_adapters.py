"""Adapters: the raw files of the four real data sets under ``shared/data/real`` as Measurements.

One small function per data set turns its files into :class:`bouc_wen_id.Measurement` objects (t in s,
``u`` the excitation, ``y`` the response, units, original channel names, the nominal frequency in rad/s as
a hint, provenance in ``metadata``).  Everything the folders' ``PROVENANCE.md`` say about columns, scales,
channel order and sampling is encoded here, and nothing else: the steady periods, the true frequency,
offsets and noise are left to :mod:`bouc_wen_id.signal`.

The data files are read in place; none of them is copied into the project (only the MR damper files are
MIT-licensed; the friction damper is CC BY-SA 4.0; the other two state no license).

``studies/`` is not a package: the studies and benches import this file by name with ``studies/`` on
``sys.path`` (a study puts its own folder there); tests load it by path (``importlib``) under the same name.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Optional

import numpy as np
from bouc_wen_id import FileFormatError, Measurement
from numpy.typing import NDArray

__all__ = [
    "DATASETS",
    "MR_FILES",
    "MR_CURRENTS",
    "MR_SCALE_FORCE",
    "MR_SCALE_DISPLACEMENT",
    "FRICTION_FILES",
    "WIRE_ROPE_FILES",
    "WIRE_ROPE_RATE",
    "WIRE_ROPE_SKIP",
    "BH_FILES",
    "BH_STEPS",
    "default_data_dir",
    "load_mr_damper",
    "load_friction_damper",
    "load_wire_rope",
    "BHRecord",
    "load_bh_raw",
    "integrate_derivative",
    "load_bh_loop",
]

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi

#: Folder of each data set under the data directory.
DATASETS = {
    "mr-damper": "mr-damper-utfsm",
    "friction-damper": "friction-damper-brfd",
    "wire-rope": "wire-rope-isolator",
    "bh-microwire": "bh-loop-microwire",
}


def default_data_dir() -> Path:
    """``../shared/data/real`` relative to the repository root (the parent of ``examples/``)."""
    return Path(__file__).resolve().parents[1].parent / "shared" / "data" / "real"


# ------------------------------------------------------------------------------------------------------
# MR damper (UTFSM thesis data, MIT)

#: The six raw files, in order of frequency.
MR_FILES = (
    "ME25mm0x25Hz.txt",
    "ME25mm0x5Hz.txt",
    "ME10mm2Hz.txt",
    "ME5mm3Hz.txt",
    "ME5mm4Hz.txt",
    "ME2mm5Hz.txt",
)
#: Coil current (A) of the five DAQ blocks of every file, in record order (PROVENANCE.md).
MR_CURRENTS = (0.0, 0.25, 0.5, 0.75, 1.0)
#: force [N] = channel x 980.665; displacement [mm] = channel x 10 (the repo's sincronize.m).
MR_SCALE_FORCE = 980.665
MR_SCALE_DISPLACEMENT = 10.0
#: The channel order per recording session (date of the first sample): (displacement, force).
MR_SESSIONS = {
    "04/29/2022": ("CHANNEL1", "CHANNEL0"),
    "05/13/2022": ("CHANNEL0", "CHANNEL1"),
}
MR_HEADER_LINES = 7
_MR_NAME = re.compile(r"^ME(?P<stroke>[0-9x]+)mm(?P<freq>[0-9x]+)Hz\.txt$")
_MR_PROVENANCE = {
    "source": "DanielMaurelE/vRTHS_AMBC_MRdamper @ 08753ffd7abd5b19053f7e79149c3a68f49bf73c",
    "license": "MIT, Copyright (c) 2022 mequiroz",
    "device": "MR damper in an MTS uniaxial machine, displacement control (UTFSM thesis, M. Quiroz)",
}


def _mr_nominal(name: str) -> tuple[float, float]:
    """Nominal stroke (mm) and frequency (Hz) from a file name such as ``ME25mm0x25Hz.txt``."""
    m = _MR_NAME.match(name)
    if m is None:
        raise FileFormatError(f"{name}: not an MR damper file name of the form ME<stroke>mm<freq>Hz.txt")
    return float(m["stroke"].replace("x", ".")), float(m["freq"].replace("x", "."))


def load_mr_damper(path: Path) -> list[Measurement]:
    """One MR damper file as five Measurements, one per DAQ block (coil currents 0, 0.25, ... 1 A).

    The blocks are the samples from ``DAQ Start``/``DAQ Resume`` to the next ``DAQ Pause``: the DAQ clock
    stops between them (the timestamp jumps by 15-60 s while the sample number keeps counting), so a
    uniform time axis exists within a block only.  Each block's ``t`` starts at 0 and steps by the header's
    sampling interval; the wall-clock start of the block is kept in the metadata.  Displacement (mm) and
    force (N) come from the session's channel order (``MR_SESSIONS``) and the repo's scales.
    """
    path = Path(path)
    stroke, f_nom = _mr_nominal(path.name)
    with path.open("r", encoding="ascii", newline="") as fh:
        header = [fh.readline().strip() for _ in range(MR_HEADER_LINES)]
        rows = fh.read().splitlines()
    fields = dict(h.split(":", 1) for h in header[:-1] if ":" in h)
    try:
        dt = float(fields["Sampling Interval"])
        count = int(fields["Sample Count"])
    except (KeyError, ValueError) as exc:
        raise FileFormatError(f"{path.name}: bad header {header!r}") from exc
    columns = [c.strip() for c in header[-1].split(",")]
    if columns != ["Sample Number", "Date/Time", "CHANNEL0", "CHANNEL1", "Events"]:
        raise FileFormatError(f"{path.name}: unexpected columns {columns}")
    number = np.empty(len(rows), dtype=np.int64)
    chan = np.empty((len(rows), 2))
    stamps: list[str] = []
    starts: list[int] = []
    stops: list[int] = []
    for i, row in enumerate(rows):
        parts = [p.strip() for p in row.split(",")]
        number[i] = int(parts[0])
        chan[i] = float(parts[2]), float(parts[3])
        stamps.append(parts[1])
        event = parts[4] if len(parts) > 4 else ""
        if event in ("DAQ Start", "DAQ Resume"):
            starts.append(i)
        elif event == "DAQ Pause":
            stops.append(i + 1)
    if number.size != count or not np.all(np.diff(number) == 1):
        raise FileFormatError(f"{path.name}: {number.size} rows, header says {count}, or a sample is missing")
    if len(starts) != len(MR_CURRENTS) or len(stops) != len(starts):
        raise FileFormatError(
            f"{path.name}: {len(starts)} DAQ starts/resumes and {len(stops)} pauses, expected "
            f"{len(MR_CURRENTS)} blocks"
        )
    session = stamps[0].split()[0]
    if session not in MR_SESSIONS:
        raise FileFormatError(f"{path.name}: unknown session {session}; channel order unknown")
    disp_ch, force_ch = MR_SESSIONS[session]
    disp = chan[:, int(disp_ch[-1])] * MR_SCALE_DISPLACEMENT
    force = chan[:, int(force_ch[-1])] * MR_SCALE_FORCE
    out = []
    for b, (a, e) in enumerate(zip(starts, stops)):
        if not a < e:
            raise FileFormatError(f"{path.name}: block {b} is empty")
        n = e - a
        current = MR_CURRENTS[b]
        out.append(
            Measurement(
                np.arange(n) * dt,
                disp[a:e],
                force[a:e],
                nominal_frequency=TWO_PI * f_nom,
                units={"u": "mm", "y": "N"},
                channels={"u": disp_ch, "y": force_ch},
                name=f"{path.stem} {current:g} A",
                metadata={
                    **_MR_PROVENANCE,
                    "file": path.name,
                    "block": str(b),
                    "coil_current_A": f"{current:g}",
                    "session": session,
                    "nominal_stroke_mm": f"{stroke:g}",
                    "nominal_hz": f"{f_nom:g}",
                    "samples": f"{int(number[a])}-{int(number[e - 1])}",
                    "block_start": stamps[a],
                    "scaling": f"u = {disp_ch} x {MR_SCALE_DISPLACEMENT:g} mm, y = {force_ch} x "
                    f"{MR_SCALE_FORCE:g} N",
                },
            )
        )
    return out


# ------------------------------------------------------------------------------------------------------
# Friction damper with backlash (ARTS-Lab BRFD, CC BY-SA 4.0)

FRICTION_FILES = (
    "0.25Hz30lbtension0.5amplitude.json",
    "0.5Hz30lbtension0.5amplitude.json",
    "1Hz30lbtension0.5amplitude.json",
    "2Hz30lbtension0.5amplitude.json",
    "1Hz30lbtension1amplitude.json",
    "1Hz30lbtension1.5amplitude.json",
)
_FRICTION_NAME = re.compile(
    r"^(?P<freq>[0-9.]+)Hz(?P<tension>[0-9]+)lbtension(?P<amp>[0-9.]+)amplitude\.json$"
)
_FRICTION_PROVENANCE = {
    "source": "ARTS-Laboratory/Dataset-Friction-Damper-with-Backlash @ "
    "0e09aa9d950760277e31c08cd93fd01f39a5af09",
    "license": "CC BY-SA 4.0 (Coble, Huggins, Cao, Ricles, Downey, ARTS-Lab 2022); not redistributed here",
    "device": "banded rotary friction damper (band brake) with backlash, hydraulic actuator, dataset 2",
}


def load_friction_damper(path: Path) -> Measurement:
    """One friction damper test: u = imposed displacement (in), y = friction force (kip), 1024 Hz.

    Rows are ``[time, displacement, friction force, velocity, actuator force 1, actuator force 2]``; the
    time column is used as it is (uniform, ``dt = 1/1024`` s).
    """
    path = Path(path)
    m = _FRICTION_NAME.match(path.name)
    if m is None:
        raise FileFormatError(f"{path.name}: not a friction damper file name")
    with path.open("r", encoding="utf-8") as fh:
        doc = json.load(fh)
    try:
        data = np.asarray(doc["data"], dtype=np.float64)
        dt = float(doc["dt"])
        units = (doc["time units"], doc["displacement units"], doc["friction force units"])
    except (KeyError, TypeError, ValueError) as exc:
        raise FileFormatError(f"{path.name}: not the BRFD JSON layout ({exc})") from exc
    if data.ndim != 2 or data.shape[1] != 6 or units != ("s", "in", "kip"):
        raise FileFormatError(f"{path.name}: data of shape {data.shape}, units {units}")
    if not np.allclose(np.diff(data[:, 0]), dt, rtol=1e-6, atol=0.0):
        raise FileFormatError(f"{path.name}: the time column does not step by dt = {dt}")
    f_nom = float(m["freq"])
    return Measurement(
        data[:, 0],
        data[:, 1],
        data[:, 2],
        nominal_frequency=TWO_PI * f_nom,
        units={"u": "in", "y": "kip"},
        channels={"t": "data[:, 0] time", "u": "data[:, 1] displacement", "y": "data[:, 2] friction force"},
        name=path.stem,
        metadata={
            **_FRICTION_PROVENANCE,
            "file": path.name,
            "nominal_hz": f"{f_nom:g}",
            "nominal_amplitude_in": m["amp"],
            "band_tension_lb": m["tension"],
            "sampling_rate_hz": f"{1.0 / dt:g}",
        },
    )


# ------------------------------------------------------------------------------------------------------
# Wire-rope isolator (SUPMECA student project, no license: read in place only)

WIRE_ROPE_FILES = ("16Hz_A2.txt", "18Hz_A2.txt", "20Hz_A2.txt", "22Hz_A2.txt", "18Hz_A4.txt", "22Hz_A4.txt")
#: Sampling rate (Hz) stated by the repo's sweep-analysis script.
WIRE_ROPE_RATE = 10240.0
#: Leading seconds that belong to the previous amplitude level of the stepped test (PROVENANCE.md).
WIRE_ROPE_SKIP = 1.2
_WIRE_NAME = re.compile(r"^(?P<freq>[0-9]+)Hz_A(?P<level>[0-9])\.txt$")
_WIRE_PROVENANCE = {
    "source": "deepfe/Wire_rope_isolators @ d30c5f4ce07f765dabf36a070fce0804177ad66d",
    "license": "none stated (default copyright): read in place, not redistributed",
    "device": "wire-rope isolator on an electrodynamic shaker, sine dwell (SUPMECA project)",
}


def load_wire_rope(path: Path, skip: float = WIRE_ROPE_SKIP) -> Measurement:
    """One wire-rope isolator file: u = -(raw displacement), y = force, both uncalibrated, 10240 Hz.

    The file has no time column: ``t = k / 10240`` s.  The first ``skip`` seconds (default 1.2) belong to the
    previous level of the stepped test and are dropped.  The displacement's sign is flipped as in the
    repo's own script (its "correct system of reference"); its x100 "cm to mm" factor is not applied, the
    scale being inconsistent and undocumented (units stay raw).
    """
    path = Path(path)
    m = _WIRE_NAME.match(path.name)
    if m is None:
        raise FileFormatError(f"{path.name}: not a wire-rope file name such as 16Hz_A2.txt")
    try:
        data = np.loadtxt(path, dtype=np.float64)
    except ValueError as exc:
        raise FileFormatError(f"{path.name}: {exc}") from exc
    if data.ndim != 2 or data.shape[1] != 2:
        raise FileFormatError(f"{path.name}: expected 2 columns, got shape {data.shape}")
    first = int(round(skip * WIRE_ROPE_RATE))
    f_nom = float(m["freq"])
    return Measurement.from_rate(
        WIRE_ROPE_RATE,
        -data[first:, 1],
        data[first:, 0],
        nominal_frequency=TWO_PI * f_nom,
        units={"u": "raw (sign flipped)", "y": "raw ('N', uncalibrated)"},
        channels={"u": "column 1 (displacement, raw) x -1", "y": "column 0 (force)"},
        name=path.stem,
        metadata={
            **_WIRE_PROVENANCE,
            "file": path.name,
            "nominal_hz": f"{f_nom:g}",
            "amplitude_level": f"A{m['level']}",
            "dropped_leading_s": f"{skip:g}",
            "first_sample": str(first),
            "sampling_rate_hz": f"{WIRE_ROPE_RATE:g}",
        },
    )


# ------------------------------------------------------------------------------------------------------
# B-H loops of an amorphous microwire (DYK-Team, no license: read in place only)

BH_FILES = ("50kHz.csv", "100kHz.csv", "200kHz.csv", "250kHz.csv")
#: Scope sampling interval (s) per file (README of the source repo, PROVENANCE.md table).
BH_STEPS = {"50kHz.csv": 5e-8, "100kHz.csv": 2e-8, "200kHz.csv": 1e-8, "250kHz.csv": 1e-8}
_BH_PROVENANCE = {
    "source": "DYK-Team/Digital_BH-loop_algorithm @ d570f56bcdd6661fa845a4161e04306ef9ed7afc",
    "license": "none stated (default copyright): read in place, not redistributed",
    "device": "amorphous ferromagnetic microwire, circular magnetisation, bridge output "
    "(RIGOL DS1104, 8 bit)",
}


@dataclass(frozen=True)
class BHRecord:
    """The raw B-H capture: ``dbdt`` (col 0, bridge voltage ~ dB/dt) and ``h`` (col 1, reference ~ H)."""

    name: str
    dt: float
    dbdt: FloatArray
    h: FloatArray
    nominal_hz: float

    @property
    def t(self) -> FloatArray:
        out: FloatArray = np.arange(self.dbdt.size, dtype=np.float64) * self.dt
        return out


def load_bh_raw(path: Path) -> BHRecord:
    """The two columns of a B-H capture as they are (no time column; ``dt`` from ``BH_STEPS``)."""
    path = Path(path)
    if path.name not in BH_STEPS:
        raise FileFormatError(f"{path.name}: no sampling interval is documented for this file")
    try:
        data = np.loadtxt(path, delimiter=",", dtype=np.float64)
    except ValueError as exc:
        raise FileFormatError(f"{path.name}: {exc}") from exc
    if data.ndim != 2 or data.shape[1] != 2:
        raise FileFormatError(f"{path.name}: expected 2 columns, got shape {data.shape}")
    nominal = float(path.stem.removesuffix("kHz")) * 1e3
    return BHRecord(path.stem, BH_STEPS[path.name], data[:, 0].copy(), data[:, 1].copy(), nominal)


def integrate_derivative(t: FloatArray, dydt: FloatArray, omega: float, harmonics: int = 10) -> FloatArray:
    """Integrate a derivative signal of a periodic quantity, without drift.

    A periodic ``B`` has a derivative of zero mean over whole periods; the record's DC (bridge offset,
    scope zero) is estimated jointly with harmonics ``1..harmonics`` of ``omega`` by least squares (a plain
    mean is biased over a non-integer number of periods) and removed.  The rest is integrated by the
    trapezoidal rule, and what linear drift remains (noise, quantisation) is removed by fitting ``[1, t]``
    jointly with the same harmonics.  The result has no DC: the constant of its harmonic fit is zero (its
    plain mean over a non-integer number of periods need not be).
    """
    tau = t - t[0]
    k = max(1, min(harmonics, int(math.pi / (omega * float(t[1] - t[0]))) - 1))
    cols = [np.ones_like(tau)]
    for j in range(1, k + 1):
        cols += [np.cos(j * omega * tau), np.sin(j * omega * tau)]
    basis = np.column_stack(cols)
    coef = np.linalg.lstsq(basis, dydt, rcond=None)[0]
    centred = dydt - coef[0]
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (centred[1:] + centred[:-1]) * np.diff(tau))])
    basis2 = np.column_stack([basis, tau])
    coef2 = np.linalg.lstsq(basis2, integral, rcond=None)[0]
    out: FloatArray = integral - coef2[0] - coef2[-1] * tau
    return out


def load_bh_loop(path: Path, frequency: Optional[float] = None) -> Measurement:
    """A B-H capture as a Measurement of ``B`` (relative) against ``H`` (relative).

    ``y`` is the time integral of the bridge voltage (col 0, ~ dB/dt) with its DC and drift removed
    (:func:`integrate_derivative`) at ``frequency`` (rad/s; default: the reference channel's fitted tone),
    in V s; ``u`` is the reference channel (col 1, ~ H), in V.  Both are relative (no bridge or geometry
    calibration exists).  A residual bridge imbalance adds ``k * integral(I)``, a term in quadrature
    with H, to the integrated B: it cannot be told apart from hysteresis loss with these data.
    """
    from bouc_wen_id import analyse_sine

    rec = load_bh_raw(path)
    t = rec.t
    omega = analyse_sine(t, rec.h, nominal_frequency=TWO_PI * rec.nominal_hz).frequency
    if frequency is not None:
        omega = float(frequency)
    b = integrate_derivative(t, rec.dbdt, omega)
    return Measurement(
        t,
        rec.h,
        b,
        nominal_frequency=TWO_PI * rec.nominal_hz,
        units={"u": "V", "y": "V s"},
        channels={
            "u": "column 1: reference voltage ~ current ~ H (relative)",
            "y": "time integral of column 0: bridge voltage ~ dB/dt, so ~ B (relative)",
        },
        name=f"{rec.name} (B integrated)",
        metadata={
            **_BH_PROVENANCE,
            "file": Path(path).name,
            "nominal_hz": f"{rec.nominal_hz:g}",
            "dt_s": f"{rec.dt:g}",
            "output_processing": "y = trapezoidal integral of col 0 after removing its DC (fitted jointly "
            "with 10 harmonics of the reference tone), then linear drift removed",
            "integration_frequency_hz": f"{omega / TWO_PI:.6g}",
        },
    )
