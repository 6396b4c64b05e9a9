"""Choose the implementation of the core routines: the Rust extension or the NumPy reference."""

from __future__ import annotations

from types import ModuleType
from typing import Literal

from .errors import InvalidParameterError

Backend = Literal["rust", "numpy"]

__all__ = ["Backend", "get_backend"]


def get_backend(name: str) -> ModuleType:
    """Return the module holding the core routines for ``name`` ("rust" or "numpy").

    Both modules expose the same functions with the same signatures and errors.
    """
    if name == "rust":
        from . import _core

        return _core
    if name == "numpy":
        from . import reference

        return reference
    raise InvalidParameterError(f"backend must be 'rust' or 'numpy', got {name!r}")
