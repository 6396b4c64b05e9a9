"""The text form the result objects share: ``str(result)`` is its ``summary()``, whose warnings come last."""

from __future__ import annotations

from collections.abc import Iterable


class Summarised:
    """A result whose ``str()`` is its :meth:`summary` (the dataclasses keep their own ``repr``)."""

    __slots__ = ()

    def summary(self) -> str:
        raise NotImplementedError

    def __str__(self) -> str:
        return self.summary()


def with_warnings(lines: Iterable[str], warnings: Iterable[str]) -> str:
    """A summary's ``lines`` and then one ``  warning: ...`` line per warning, as one text."""
    return "\n".join([*lines, *(f"  warning: {w}" for w in warnings)])


def item_label(i: int, item: object, kind: str = "item") -> str:
    """How messages name the ``i``-th experiment: ``"item 3 (exp3)"`` when it carries a name (a file's stem,
    set by :func:`bouc_wen_id.io.load`), ``"item 3"`` otherwise."""
    meta = getattr(item, "metadata", None)
    name = meta.get("name") if isinstance(meta, dict) else None
    name = name or getattr(item, "name", None)
    return f"{kind} {i} ({name})" if name else f"{kind} {i}"
