"""``bouc-wen-id validate``: an identified model simulated on records it was not fitted to (issue #20).

``bouc-wen-id validate --model MODEL.json RECORD...`` prints, per record, the NRMSE, the RMSE in the units
of y and the largest error; ``--out DIR`` also writes ``validation.json`` and one residual plot per record.
A record whose file states other units than the model was fitted in is converted to the model's (a warning
on stderr, a note under the table) or refused when no scale relates them (exit 2, naming the file and both
units); a model saved without units is noted (the records' units cannot be checked against it).
``MODEL.json`` is a plant (``WienerPlant.to_dict``: ``{"linear": ..., "hysteresis": ..., "terms": ...}``) or
any JSON object holding one under ``"plant"`` (``TimeDomainFit.to_dict``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from . import _output
from .errors import BoucWenIdError, FileFormatError, InvalidParameterError
from .export import model_from_json
from .model import WienerPlant
from .units import against_model, harmonise, model_units, units_of

__all__ = ["add_validate_parser", "cmd_validate"]


def add_validate_parser(sub: Any) -> None:
    """The ``validate`` sub-parser."""
    p = sub.add_parser(
        "validate",
        help="simulate an identified model on records it was not fitted to: NRMSE, RMSE, residual plots",
        description="Simulate the model (a plant JSON, or a fit JSON holding one under 'plant') on each "
        "record from rest and compare with the measured output.",
    )
    p.add_argument("paths", nargs="+", type=Path, help="record files or folders (t, u, y columns)")
    p.add_argument("--model", type=Path, required=True, help="plant or fit JSON file")
    p.add_argument(
        "--columns", nargs="+", default=None, metavar="ROLE=COLUMN", help="which column is t, u, y"
    )
    p.add_argument("--sample-rate", type=float, default=None, help="Hz, for files without a time column")
    p.add_argument("--lead-in", type=float, default=None, help="seconds at each record's start left out")
    p.add_argument("--substeps", type=int, default=4, help="RK4 steps per sample interval")
    p.add_argument(
        "--units",
        default="",
        help="unit of y of records whose files do not state it (checked against the model's; default: "
        "the model's)",
    )
    p.add_argument("--out", type=Path, default=None, help="write validation.json and residual plots here")
    p.add_argument("--overwrite", action="store_true", help="replace a previous report folder at --out")


def _load_model(path: Path) -> WienerPlant:
    """A model document (:func:`bw.save_model`), a plant JSON, or an object holding one under ``plant``;
    every failure a :class:`FileFormatError`."""
    if not path.is_file():
        raise FileFormatError(f"--model {path}: no such regular file")
    if path.stat().st_size > 1 << 20:
        raise FileFormatError(f"--model {path}: {path.stat().st_size} bytes is no model JSON file")
    try:
        text = path.read_text(encoding="utf-8")
        spec = json.loads(text)
        if isinstance(spec, dict) and "format" in spec:  # a versioned model document (bw.save_model)
            return model_from_json(text)
        if isinstance(spec, dict) and isinstance(spec.get("plant"), dict):
            spec = spec["plant"]
        if not isinstance(spec, dict):
            raise TypeError(f"a JSON {type(spec).__name__}, not an object")
        return WienerPlant.from_dict(spec)
    except BoucWenIdError:
        raise
    except (OSError, ValueError, TypeError, KeyError, AttributeError) as exc:
        raise FileFormatError(
            f"--model {path}: not a plant or fit JSON file ({type(exc).__name__}: {exc})"
        ) from None


def cmd_validate(args: argparse.Namespace) -> int:
    """Run ``validate``; 0 when every record was simulated."""
    from .timedomain import validate

    if args.substeps < 1:
        raise InvalidParameterError(f"--substeps = {args.substeps} must be >= 1")
    target = None
    if args.out is not None:
        target = _output.check_out(
            args.out, overwrite=args.overwrite, inputs=args.paths, what="report folder"
        )
        replaces = _output.identity(target) if args.overwrite else None
    plant = _load_model(args.model)
    items, names = _records(args)
    if not model_units(plant) and len(items) > 1:
        items = harmonise(items, names).items
    reports = []
    checked = []
    for name, item in zip(names, items):  # every record's units checked before any is simulated
        stated = units_of(item)
        if args.units and "y" not in stated:
            stated["y"] = args.units
        checked.append((name, item, stated))
        against_model(plant, stated, name, warn=False)
    print(f"{'record':<28} {'samples':>8} {'NRMSE':>9} {'RMSE':>11} {'max |e|':>11}")
    notes: list[str] = []
    for name, item, stated in checked:
        rep = validate(
            plant,
            item.t,
            item.u,
            item.y,
            lead_in=args.lead_in,
            substeps=args.substeps,
            data_units=stated,
            name=name,
        )
        notes += [n for n in rep.notes if n not in notes]
        reports.append((name, rep))
        print(f"{name[:28]:<28} {rep.t.size:>8} {rep.nrmse:>9.4g} {rep.rmse:>11.4g} {rep.max_error:>11.4g}")
    if reports and reports[0][1].units:
        print(f"(RMSE and max |e| in {reports[0][1].units})")
    for note in notes:
        print(f"note: {note}")
    if target is not None:
        import matplotlib

        matplotlib.use("Agg")
        with _output.staged(target, command="validate", replaces=replaces) as staged:
            staged.mkdir()
            table = [{"record": n, **r.to_dict()} for n, r in reports]
            (staged / "validation.json").write_text(json.dumps(table, indent=2) + "\n", encoding="utf-8")
            for i, (_, rep) in enumerate(reports):
                rep.plot().savefig(staged / f"residuals_{i:03d}.png", dpi=110)
        print(f"wrote {args.out}")
    return 0


def _records(args: argparse.Namespace) -> tuple[list[Any], list[str]]:
    """The records of ``args.paths``, each named by its file (``file.csv[2]`` for a block of one); in
    one unit per quantity across the files when the model states none to convert them to."""
    from .io import load
    from .io._load import _files

    items: list[Any] = []
    names: list[str] = []
    columns = _columns(args.columns)
    for f in _files(args.paths):
        read = load(f, columns=columns, sample_rate=args.sample_rate)
        items += read
        names += [f.name if len(read) == 1 else f"{f.name}[{b}]" for b in range(len(read))]
    return items, names


def _columns(specs: Any) -> Any:
    """``["u=disp", "y=3"]`` -> ``{"u": "disp", "y": 3}``."""
    if not specs:
        return None
    out: dict[str, Any] = {}
    for spec in specs:
        role, sep, col = str(spec).partition("=")
        if not sep or not col:
            raise InvalidParameterError(f"--columns {spec!r}: expected ROLE=COLUMN, e.g. u=disp_mm")
        out[role.strip()] = int(col) if col.strip().isdigit() else col.strip()
    return out
