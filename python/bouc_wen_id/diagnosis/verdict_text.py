"""A verdict read in two layers: its headline (the first clause: what is named, or that nothing is) and its
details (every further clause, one per line).

A verdict is one sentence of clauses joined by ``"; "``; a clause may itself hold ``"; "`` inside
parentheses (e.g. what the pair step did at each step), which stays with its clause.
"""

from __future__ import annotations

__all__ = ["after_headline", "clauses", "headline", "details"]


def clauses(verdict: str) -> list[str]:
    """The verdict's top-level clauses, in order: split at ``"; "`` outside parentheses and brackets."""
    out: list[str] = []
    depth, start, i = 0, 0, 0
    while i < len(verdict):
        ch = verdict[i]
        if ch in "([":
            depth += 1
        elif ch in ")]":
            depth = max(depth - 1, 0)
        elif depth == 0 and verdict.startswith("; ", i):
            out.append(verdict[start:i].strip())
            start = i + 2
            i += 1
        i += 1
    out.append(verdict[start:].strip())
    return [c for c in out if c]


def headline(verdict: str) -> str:
    """The verdict's first clause: the named terms with their values and share, or what is left."""
    parts = clauses(verdict)
    return parts[0] if parts else verdict


def after_headline(verdict: str, words: str) -> str:
    """``verdict`` with ``words`` (a caveat, or a clause "; ...") right after its headline."""
    at = verdict.find(headline(verdict)) + len(headline(verdict))
    return verdict[:at] + words + verdict[at:]


def details(verdict: str) -> list[str]:
    """Every clause after the headline (alternatives, what was not named and why, notes on the data)."""
    return clauses(verdict)[1:]
