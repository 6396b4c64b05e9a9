"""Clipped outputs left out of the joint fit across conditions (review 36b, problem 4).

One file whose output clipped at one condition (viscous damping on u, c = 0.008, at three conditions; at
0.5 the slowest experiment's output on its rail) wiped out the finding at every condition: the clipped
experiment stayed in the joint fit, its flat tops failed the joint term's law (one value for all
experiments) and offered "play (backlash)" as a competing reading; the verdict said "nothing named" at the
two clean conditions as well. As the single diagnosis fits values on the experiments whose input is a
sine (:mod:`.clean_value`), the experiments whose recorded output :func:`.output_clip.clipped` finds
clipped are left out of a condition before it is prepared, when at least :data:`.law.MIN_CLEAN` of its
experiments remain (otherwise all stay and the clip is only said, :func:`.across_clean.outputs_text`); the
verdict says which were left out, where, and why.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from .law import MIN_CLEAN
from .output_clip import clipped


def _name(item: Any, i: int) -> str:
    meta = getattr(item, "metadata", None)
    name = getattr(item, "name", "") or (meta.get("name", "") if isinstance(meta, dict) else "")
    return str(name or f"recording {i}")


def unclipped(
    groups: Sequence[Sequence[Any]], own: Sequence[Any], checks: Sequence[Any], labels: Sequence[Any]
) -> tuple[list[list[Any]], list[Any], list[Any], dict[str, list[str]]]:
    """``(groups, own, checks, left)``: each condition's items without those whose output is clipped when
    at least :data:`.law.MIN_CLEAN` remain; ``own`` and ``checks`` (each condition's own diagnosis and its
    stability check, reused when given) with None where items were left out (their fits include them);
    ``left``: condition label -> names left out."""
    out, owns, chks, left = [], list(own), list(checks), {}
    for k, (items, label) in enumerate(zip(groups, labels)):
        items = list(items)
        bad = set(clipped(items))
        keep = [it for i, it in enumerate(items) if _name(it, i) not in bad]
        if bad and len(keep) >= MIN_CLEAN and len(keep) < len(items):
            left[str(label)] = [_name(it, i) for i, it in enumerate(items) if _name(it, i) in bad]
            out.append(keep)
            owns[k] = chks[k] = None
        else:
            out.append(items)
    return out, owns, chks, left


def text(left: dict[str, list[str]]) -> str:
    """The verdict's clause on the experiments left out ('' when none)."""
    out = ""
    for label, names in left.items():
        one = len(names) == 1
        out += (
            f"; at {label}, the measured output of {', '.join(names)} looks clipped (flat tops at "
            f"{'its' if one else 'their'} extremes, as Measurement.check finds them): a sensor or DAQ out of "
            f"range, not device physics, so left out of the joint fit (the "
            f"structure and the values at {label} come from its other experiments)"
        )
    return out


__all__ = ["text", "unclipped"]
