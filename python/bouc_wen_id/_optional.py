"""Optional dependencies (pandas, npTDMS, h5py, python-control, Dask), imported on first use.

``import bouc_wen_id`` must stay fast and must work without them: only the functions that need one import
it, through :func:`require`, which turns a missing package into an :class:`ImportError` that says which
extra installs it.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["require", "EXTRAS"]

#: Module name -> (distribution name on PyPI, the extra of ``bouc_wen_id`` that installs it).
EXTRAS = {
    "pandas": ("pandas", "pandas"),
    "nptdms": ("npTDMS", "tdms"),
    "h5py": ("h5py", "hdf5"),
    "control": ("control", "control"),
    "distributed": ("dask[distributed]", "dask"),
}


def require(module: str, what: str) -> Any:
    """Import the optional ``module`` (a key of :data:`EXTRAS`) for ``what`` (e.g. ``"reading .tdms"``).

    Raises
    ------
    ImportError
        When the package is not installed, with the ``pip install`` line that installs it.
    """
    dist, extra = EXTRAS[module]
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ImportError(
            f"{what} needs the optional package {dist}: pip install 'bouc_wen_id[{extra}]' (or pip install "
            f"{dist})"
        ) from exc
