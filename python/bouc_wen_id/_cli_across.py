"""``bouc-wen-id diagnose-across``: one named structure for experiments at several conditions (issue 18).

``bouc-wen-id diagnose-across --group 0 a.csv b.csv --group 0.5 c.csv d.csv`` diagnoses each group (one
condition: a coil current, a temperature) with the same candidate terms added at every condition at once,
their values free per condition (:func:`bouc_wen_id.diagnose_across`), and prints the verdict, each named
term's value per condition with its se and smoothness in the condition, and each condition's fit;
``--compare`` also diagnoses each group on its own and prints its held-out NRMSE beside; ``--json PATH``
writes the result.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path
from typing import Any, Optional

from . import _output
from .errors import InvalidParameterError

__all__ = ["add_across_parser", "cmd_across"]


def add_across_parser(sub: Any) -> None:
    """The ``diagnose-across`` sub-parser."""
    p = sub.add_parser(
        "diagnose-across",
        help="one named structure for experiments at several conditions, its values free per condition",
        description="Add each candidate term at every condition at once (its value free per condition), name "
        "it by the combined F test (Bonferroni over the candidates), the summed share of the misfit and the "
        "summed held-out gain; report its value per condition and how it moves with the condition.",
    )
    p.add_argument(
        "--group",
        nargs="+",
        action="append",
        required=True,
        metavar="CONDITION FILE",
        help="a condition's value followed by its files or folders; repeat for each condition (at least 2)",
    )
    p.add_argument(
        "--columns", nargs="+", default=None, metavar="ROLE=COLUMN", help="which column is t, u, y"
    )
    p.add_argument("--sample-rate", type=float, default=None, help="Hz, for files without a time column")
    p.add_argument(
        "--candidates", default=None, help="comma-separated terms to try (default: all steady ones)"
    )
    p.add_argument("--alpha", type=float, default=0.05, help="false-alarm level per step (default 0.05)")
    p.add_argument("--no-held-out", action="store_true", help="skip the held-out check (faster, weaker)")
    p.add_argument("--compare", action="store_true", help="also diagnose each condition on its own, beside")
    p.add_argument("--json", type=Path, default=None, help="write the result as JSON to this (new) file")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --json file")


def _groups(specs: list[list[str]]) -> tuple[list[float], list[list[Path]]]:
    conds, paths = [], []
    for spec in specs:
        if len(spec) < 2:
            raise InvalidParameterError(
                f"--group {' '.join(spec)}: give the condition's value, then its files"
            )
        try:
            conds.append(float(spec[0]))
        except ValueError:
            raise InvalidParameterError(f"--group {' '.join(spec)}: {spec[0]!r} is not a number") from None
        paths.append([Path(s) for s in spec[1:]])
    return conds, paths


def _columns(specs: Optional[list[str]]) -> Optional[dict[str, Any]]:
    if not specs:
        return None
    out: dict[str, Any] = {}
    for s in specs:
        role, sep, col = s.partition("=")
        if not sep or role not in ("t", "u", "y"):
            raise InvalidParameterError(f"--columns {s!r}: give ROLE=COLUMN with ROLE t, u or y")
        out[role] = int(col) if col.lstrip("-").isdigit() else col
    return out


def cmd_across(args: argparse.Namespace) -> int:
    """Load each group's files, diagnose across the conditions, print the summary (and write the JSON)."""
    from .diagnosis import diagnose
    from .diagnosis.across import diagnose_across
    from .io import load
    from .units import harmonise_groups

    conds, paths = _groups(args.group)
    if args.json is not None:  # refused before the run, never after it
        _output.check_file(args.json, overwrite=args.overwrite, flag="--json")
    cols = _columns(args.columns)
    groups = [list(load(ps, columns=cols, sample_rate=args.sample_rate)) for ps in paths]
    groups = harmonise_groups(groups)[0]  # one unit across the conditions, before any group is fitted
    cands = None if args.candidates is None else [c.strip() for c in args.candidates.split(",") if c.strip()]
    own = None
    if args.compare:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            own = [
                diagnose(g, candidates=cands, alpha=args.alpha, held_out_test=not args.no_held_out)
                for g in groups
            ]
    a = diagnose_across(
        groups,
        conds,
        candidates=cands,
        alpha=args.alpha,
        held_out_test=not args.no_held_out,
        per_condition=own,
        progress=True,
    )
    print(a.summary())
    if args.json is not None:
        from .diagnosis.result import clean

        text = json.dumps(clean(a.to_dict()), indent=1, allow_nan=False)
        _output.write_file(args.json, text, overwrite=args.overwrite, flag="--json")
        print(f"wrote {args.json}", file=sys.stderr)
    return 0
