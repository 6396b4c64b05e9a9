"""``bouc-wen-id diagnose PATH... --out DIR``: the diagnosis from the command line.

Loads the files as ``identify`` does (CSV/NPZ/MAT, recordings or lab measurements), prints the verdict
first and the evidence after it, and writes ``diagnosis.json`` (before any figure), the figures and
``report.html`` into ``--out``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ..augmented import TERM_NAMES


def add_parser(sub: Any, columns_help: str) -> argparse.ArgumentParser:
    p: argparse.ArgumentParser = sub.add_parser(
        "diagnose",
        help="diagnose what the model leaves out: where, which physics, and the held-out proof",
        description="Fit the plain model and the library's candidate terms jointly; name a term only when "
        "it passes a nested test (Bonferroni over the candidates), explains a material share of the misfit "
        "and improves the fit on held-out experiments. The verdict comes first.",
    )
    p.add_argument("paths", nargs="+", type=Path, help="files or folders of files")
    p.add_argument("--columns", nargs="+", default=None, metavar="ROLE=COLUMN", help=columns_help)
    p.add_argument("--sample-rate", type=float, default=None, help="Hz, for files without a time column")
    p.add_argument(
        "--candidates",
        default=",".join(TERM_NAMES),
        help=f"comma-separated terms to try (default: all of {','.join(TERM_NAMES)})",
    )
    p.add_argument("--alpha", type=float, default=0.05, help="false-alarm level per step (default 0.05)")
    p.add_argument("--no-held-out", action="store_true", help="skip the held-out check (faster, weaker)")
    p.add_argument("--no-figures", action="store_true", help="write the JSON and a text-only HTML page")
    p.add_argument("--out", type=Path, default=Path("bouc_wen_id_diagnosis"), help="report folder")
    return p


def run(args: argparse.Namespace, load_items: Any) -> int:
    from ..measurement import Measurement
    from .report import write_report
    from .run import diagnose

    items = load_items(args)
    units = next((m.units for m in items if isinstance(m, Measurement)), {})
    cands = [c.strip() for c in str(args.candidates).split(",") if c.strip()]
    d = diagnose(
        items,
        candidates=cands,
        alpha=args.alpha,
        held_out_test=not args.no_held_out,
        y_unit=str(units.get("y", "")),
        u_unit=str(units.get("u", "")),
    )
    print(d.summary())
    for f in write_report(d, args.out, figures=not args.no_figures):
        print(f"wrote {f}")
    return 0
