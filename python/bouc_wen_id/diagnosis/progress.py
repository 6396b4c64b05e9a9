"""Progress of a diagnosis on stderr: its stages, and within the selection the candidate being fitted.

The library is quiet by default (``diagnose(progress=None)``); ``progress=True`` reports on stderr (a bar
redrawn in place when stderr is a terminal, one line per stage otherwise, so logs stay readable), and a
callable receives every report itself.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any, Optional, TextIO, Union

from ..errors import InvalidParameterError

#: ``callback(stage, done, total)``: ``stage`` says what runs now; ``done`` of ``total`` units of it are done
#: (candidates of a selection step; 0 of 1 for a stage without parts).
ProgressCallback = Callable[[str, int, int], None]
Progress = Union[None, bool, ProgressCallback]
#: Width of the bar drawn on a terminal.
BAR_WIDTH = 20


class StderrProgress:
    """Reports on a stream (stderr): a bar redrawn in place on a terminal, else one line per stage."""

    def __init__(self, stream: Optional[TextIO] = None, tty: Optional[bool] = None) -> None:
        self.stream = sys.stderr if stream is None else stream
        isatty = getattr(self.stream, "isatty", None)
        self.tty = bool(isatty()) if tty is None and callable(isatty) else bool(tty)
        self.t0 = time.perf_counter()
        self.last = ""

    def __call__(self, stage: str, done: int, total: int) -> None:
        elapsed = time.perf_counter() - self.t0
        if self.tty:
            filled = BAR_WIDTH * done // total if total > 0 else BAR_WIDTH
            bar = "#" * filled + "-" * (BAR_WIDTH - filled)
            text = f"\rdiagnose [{bar}] {elapsed:6.1f} s  {stage} ({done}/{total})"
            pad = max(len(self.last) - len(text), 0)
            self.stream.write(text + " " * pad)
            self.last = text
            if stage == "done":
                self.stream.write("\n")
        else:
            part = f" ({done + 1}/{total})" if total > 1 else ""
            self.stream.write(f"diagnose: {elapsed:6.1f} s  {stage}{part}\n")
        self.stream.flush()


def _silent(stage: str, done: int, total: int) -> None:
    return None


def reporter(progress: Any) -> ProgressCallback:
    """The callback ``progress`` asks for: None/False quiet, True stderr, or the callable itself."""
    if progress is None or progress is False:
        return _silent
    if progress is True:
        return StderrProgress()
    if callable(progress):
        out: ProgressCallback = progress
        return out
    raise InvalidParameterError(
        f"progress = {progress!r} must be None, a bool or a callable(stage, done, total)"
    )


__all__ = ["ProgressCallback", "Progress", "StderrProgress", "reporter"]
