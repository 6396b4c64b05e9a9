"""mu48's before/after table: review 47's driver (``drive47.py --one CASE``) run on the branch's base and on
the branch, each record a JSON file ``DIR/mu48_{before,after}_CASE.json``; prints, per case, the status, the
headline (cut), the named values with their z against the truth, the clause mu48 adds (cut) and CPU s.

Usage: ``python studies/mu48/compare48.py DIR CASE ...``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def _row(path: Path) -> str:
    if not path.exists() or path.stat().st_size == 0:
        return "(not run)"
    d = json.loads(path.read_text())
    named = ", ".join(
        f"{n['term']} {n['value']:.4g}±{n['se']:.2g}"
        + (f" (z {n['z']:.1f})" if n.get("z") is not None else "")
        for n in d["named"]
    )
    text = " ".join([d["headline"], *d["details"]])
    extra = ""
    for mark in ("values read with mu held", "the loop's shape changes with frequency"):
        if mark in text:
            said = text[text.index(mark) :]
            extra = " | " + said.split("conditional on mu: ")[-1][:330]
    return (
        f"{d['status']} | {d['headline'][:150]} | named: {named or '-'} | cpu {d['cpu_seconds']:.1f}{extra}"
    )


def main(argv: list[str]) -> None:
    folder = Path(argv[0])
    for case in argv[1:]:
        print(f"## {case}")
        for tag in ("before", "after"):
            print(f"  {tag}: {_row(folder / f'mu48_{tag}_{case}.json')}")


if __name__ == "__main__":
    main(sys.argv[1:])
