"""``bouc-wen-id export``: a saved model as self-contained C99 or as a versioned model JSON document.

The model is read from a model document (:func:`bouc_wen_id.save_model`) or a plant JSON file (the
``WienerPlant.to_dict`` form ``simulate --plant`` takes); the output goes to ``--out`` (an existing file is
replaced only with ``--overwrite``) or to stdout.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from . import _output
from .errors import FileFormatError
from .model import WienerPlant

__all__ = ["add_export_parser", "run_export"]

#: Largest model file read (a model is a few hundred bytes).
MAX_MODEL_BYTES = 1 << 20


def add_export_parser(sub: Any) -> None:
    """The ``export`` sub-parser."""
    p = sub.add_parser(
        "export",
        help="write a saved model as C99 source or as a versioned model JSON document",
        description="Export the whole model (plain or with terms): --to c writes one C99 function "
        "(fixed-step RK4, no allocation) that reproduces simulate_input; --to json writes the model document "
        "that bouc_wen_id.load_model reads back exactly.",
    )
    p.add_argument("model", type=Path, help="a model document (save_model) or a plant JSON file")
    p.add_argument("--to", choices=("c", "json"), required=True, help="the output form")
    p.add_argument("--name", default="bouc_wen_model", help="the C function's name (--to c)")
    p.add_argument("--out", type=Path, default=None, help="the file to write (default: stdout)")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out file")


def _read(path: Path) -> WienerPlant:
    from .export import MODEL_FORMAT, load_model  # the exporters load with the command, not the parser

    if not path.is_file():
        raise FileFormatError(f"{path}: no such regular file")
    if path.stat().st_size > MAX_MODEL_BYTES:
        raise FileFormatError(f"{path}: {path.stat().st_size} bytes is no model file")
    text = path.read_text(encoding="utf-8")
    try:
        doc = json.loads(text)
    except ValueError as exc:
        raise FileFormatError(f"{path}: not JSON ({exc})") from None
    if isinstance(doc, dict) and "format" in doc:
        if doc["format"] != MODEL_FORMAT:
            raise FileFormatError(
                f"{path}: format {doc['format']!r} is not a model document ({MODEL_FORMAT!r})"
            )
        return load_model(path)
    if isinstance(doc, dict) and {"verdict", "named"} <= set(doc):
        raise FileFormatError(
            f"{path}: a diagnosis report, not a model: it holds no G (its fits have one gain and phase per "
            "experiment); run `bouc-wen-id diagnose FILES --model` to also fit and write OUT/model.json (G "
            "with the named terms), and export that"
        )
    if not isinstance(doc, dict) or not {"linear", "hysteresis"} <= set(doc):
        from ._diagnosis_json import HINT, looks_like

        if looks_like(doc):
            raise FileFormatError(f"{path}: {HINT}")
        raise FileFormatError(
            f"{path}: neither a model document (save_model) nor a plant JSON file with 'linear' and "
            "'hysteresis'"
        )
    try:
        return WienerPlant.from_dict(doc)
    except (KeyError, TypeError) as exc:
        raise FileFormatError(f"{path}: not a plant JSON file ({type(exc).__name__}: {exc})") from None


def run_export(args: argparse.Namespace) -> int:
    """Run ``export``: read, convert, write; errors are the library's named ones."""
    from .export import model_to_json, to_c

    plant = _read(args.model)
    text = to_c(plant, name=args.name) if args.to == "c" else model_to_json(plant) + "\n"
    if args.out is None:
        sys.stdout.write(text)
        return 0
    _output.write_file(args.out, text, overwrite=args.overwrite)
    print(f"wrote {args.out}")
    return 0
