"""The command line's output (``--out``): only ever our own report, never the user's files (issue #19).

* **Checked before any work** (:func:`check_out`).  ``--out`` is taken for what it is: ``a/b/..`` is ``a``,
  and the last component is not followed (a symbolic link there is a link, not its target).  A new path is
  fine.  An existing one is replaced (with ``--overwrite``) only when it is a folder holding a complete
  report of ours: the marker file :data:`MARKER`, written last.  Never a file, a symbolic link, a device;
  never a folder of other files; never a folder that is, or holds, one of the run's inputs.
* **Built beside it and moved into place whole** (:func:`staged`): the output is written into a hidden
  ``.partial-bouc_wen_id-<pid>-<random>`` folder (a short name, whatever the length of ``--out``'s), then
  renamed onto ``--out``.  A rename of a folder onto a folder that holds files fails, so of two runs into one
  new ``--out`` one wins and the other is refused, by name.
* **Nothing half written is left**: an error, Ctrl-C or SIGTERM (:func:`terminate_on_sigterm`) removes the
  partial folder; one left by a killed run (SIGKILL, a power cut) is removed by the next run into the same
  parent folder, once its process is gone.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import signal
import stat
import tempfile
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import FrameType
from typing import Optional

from .errors import InvalidParameterError

__all__ = [
    "MARKER",
    "EXIT_TERMINATED",
    "Terminated",
    "check_out",
    "identity",
    "staged",
    "shown",
    "terminate_on_sigterm",
]

#: The file that makes a folder a complete report of ours, written after everything else.
MARKER = ".bouc_wen_id-report"
#: The hidden partial folders' prefix; the rest is ``<pid>-<random>`` (short: NAME_MAX is 255 bytes).
PARTIAL_PREFIX = ".partial-bouc_wen_id-"
#: Exit status after SIGTERM (128 + 15, the shell's convention for a process ended by signal 15).
EXIT_TERMINATED = 128 + signal.SIGTERM


class Terminated(BaseException):
    """SIGTERM arrived: unwinds like Ctrl-C (the partial output is removed), then the process exits 143."""


def _on_sigterm(signum: int, frame: Optional[FrameType]) -> None:
    raise Terminated(f"signal {signum}")


def terminate_on_sigterm() -> None:
    """SIGTERM raises :class:`Terminated` in the main thread (also inside a long core call, which polls for
    signals as for Ctrl-C), so that the partial output is cleaned up on the way out."""
    signal.signal(signal.SIGTERM, _on_sigterm)


def _target(out: Path) -> Path:
    """``out`` absolute, its parents resolved (``a/b/..`` is ``a``), its last component not followed."""
    if out.name in ("", ".", ".."):
        return out.resolve()
    return out.parent.resolve() / out.name


def _refuse(flag: str, out: Path, what: str) -> InvalidParameterError:
    return InvalidParameterError(f"{flag} {out}: {what}")


def _is_ours(path: Path) -> bool:
    try:
        return stat.S_ISREG((path / MARKER).lstat().st_mode)
    except OSError:
        return False


def _holds_an_input(target: Path, inputs: Sequence[Path]) -> Optional[Path]:
    for p in inputs:
        try:
            real = Path(p).resolve()
        except (OSError, RuntimeError):
            continue
        if real == target or target in real.parents:
            return Path(p)
    return None


def check_out(
    out: Path, *, overwrite: bool, inputs: Sequence[Path] = (), flag: str = "--out", what: str = "folder"
) -> Path:
    """Where the output goes (``out`` resolved), after refusing any ``out`` that is not ours to write.

    ``inputs`` are the run's input paths (a folder of them is never replaced).  Also removes partial
    folders left beside ``out`` by runs that were killed.  Raises
    :class:`~bouc_wen_id.errors.InvalidParameterError` naming ``flag``.
    """
    check_spelling(out, flag)
    target = _target(out)
    try:
        mode: Optional[int] = target.lstat().st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise _refuse(flag, out, f"cannot be examined ({exc.strerror})") from None
    if mode is not None:
        _check_existing(out, target, mode, overwrite, inputs, flag, what)
    parent = target.parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir() or not os.access(parent, os.W_OK | os.X_OK):
        raise _refuse(flag, out, f"{parent} is not a writable folder")
    clean_stale(target.parent)
    return target


def check_file(out: Path, *, overwrite: bool, flag: str = "--out") -> None:
    """Refuse, by name, a one-file output (``export --out``, ``diagnose-across --json``) that is not ours
    to write: anything but a regular file, or an existing file without ``overwrite``.  Called before the
    work, so a long run never ends in a refusal."""
    if out.exists() and not (overwrite and out.is_file()):
        why = "is not a regular file" if not out.is_file() else "exists; pass --overwrite"
        raise InvalidParameterError(f"{flag} {out} {why}")


def write_file(out: Path, text: str, *, overwrite: bool, flag: str = "--out") -> None:
    """Write ``text`` to ``out`` whole or not at all (a temporary file beside it, renamed), after
    :func:`check_file`."""
    check_file(out, overwrite=overwrite, flag=flag)
    fd, tmp = tempfile.mkstemp(dir=out.parent if str(out.parent) else ".", prefix=f".{out.name}.")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        os.replace(tmp, out)
    except BaseException:
        os.unlink(tmp)
        raise


#: Deepest ``--out`` accepted, in folders: creating each missing one recurses (pathlib, os.makedirs), and
#: no report needs a thousand levels.
MAX_DEPTH = 256


def check_spelling(out: Path, flag: str) -> None:
    """Refuse, by name, an ``out`` no file system takes: a NUL byte, longer than the system's path limit,
    or deeper than :data:`MAX_DEPTH` folders (a raw ValueError and a RecursionError before)."""
    text = str(out)
    if "\x00" in text:
        raise _refuse(flag, Path(text.replace("\x00", "\\0")), "contains a NUL byte, which no path may hold")
    try:
        limit = os.pathconf("/", "PC_PATH_MAX")
    except (OSError, ValueError, AttributeError):  # pragma: no cover - not POSIX
        limit = 4096
    if len(os.fsencode(os.path.abspath(text))) >= limit:
        raise _refuse(
            flag, Path(text[:60] + "..."), f"is longer than the system's path limit ({limit} bytes)"
        )
    if len(out.parts) > MAX_DEPTH:
        raise _refuse(
            flag, Path(text[:60] + "..."), f"is {len(out.parts)} folders deep (at most {MAX_DEPTH})"
        )


def _check_existing(
    out: Path, target: Path, mode: int, overwrite: bool, inputs: Sequence[Path], flag: str, what: str
) -> None:
    if stat.S_ISLNK(mode):
        raise _refuse(flag, out, "is a symbolic link; bouc-wen-id writes only a new path or its own report")
    if not stat.S_ISDIR(mode):
        kind = "file" if stat.S_ISREG(mode) else "special file (a device, a FIFO or a socket)"
        raise _refuse(
            flag,
            out,
            f"a {kind} is there; bouc-wen-id never replaces a file (not even with --overwrite): "
            f"remove it yourself, or choose another {what}",
        )
    held = _holds_an_input(target, inputs)
    if held is not None:
        raise _refuse(flag, out, f"is (or holds) the input {held}; choose another {what} for the report")
    if _holds_an_input(target, [Path.cwd()]) is not None:
        # Replacing it would leave this process (and the user's shell) in a deleted folder.
        raise _refuse(flag, out, f"is (or holds) the current folder; choose another {what}")
    if not any(target.iterdir()):
        return
    if not _is_ours(target):
        raise _refuse(
            flag,
            out,
            f"a folder of other files (not a report of bouc-wen-id: no {MARKER} in it) is there; "
            f"it is never replaced, not even with --overwrite: choose another {what}",
        )
    if not overwrite:
        raise _refuse(
            flag,
            out,
            f"another run's report is there; pass --overwrite to replace it whole, or choose another {what}",
        )


def clean_stale(parent: Path) -> None:
    """Remove the partial folders in ``parent`` whose process is gone (killed before it could clean up)."""
    try:
        entries = [e for e in parent.iterdir() if e.name.startswith(PARTIAL_PREFIX)]
    except OSError:
        return
    for entry in entries:
        pid_text = entry.name[len(PARTIAL_PREFIX) :].split("-", 1)[0]
        try:
            st = entry.lstat()
            mine = not hasattr(os, "getuid") or st.st_uid == os.getuid()
            if not stat.S_ISDIR(st.st_mode) or not mine or _alive(int(pid_text)):
                continue
        except (OSError, ValueError):
            continue
        shutil.rmtree(entry, ignore_errors=True)


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # PermissionError: someone else's process
        return True
    return True


def identity(path: Path) -> Optional[tuple[int, int]]:
    """Which folder is at ``path`` now (device and inode; ``None`` if nothing or not a folder): a report
    is replaced only if it is still the one the check saw (:func:`staged`'s ``replaces``)."""
    try:
        st = path.lstat()
    except OSError:
        return None
    return (st.st_dev, st.st_ino) if stat.S_ISDIR(st.st_mode) else None


@contextmanager
def staged(
    target: Path, *, command: str, replaces: Optional[tuple[int, int]], flag: str = "--out"
) -> Iterator[Path]:
    """A path to write the whole output to (named like ``target``, inside a hidden partial folder beside
    it); on success it replaces ``target`` in one rename (a folder gets the :data:`MARKER` first).

    On any failure (an error, Ctrl-C, SIGTERM) the partial folder is removed and ``target`` is left as it
    was.  ``target`` is what :func:`check_out` returned; ``replaces`` is the :func:`identity` of the report
    there that ``--overwrite`` replaces (``None``: replace nothing).  A report another run put there
    meanwhile is never replaced: this run is refused instead, by name.
    """
    parent = target.parent
    parent.mkdir(parents=True, exist_ok=True)
    stage = Path(tempfile.mkdtemp(prefix=f"{PARTIAL_PREFIX}{os.getpid()}-", dir=parent))
    try:
        staged_out = stage / target.name
        yield staged_out
        if staged_out.is_dir():
            marker = {"format": "bouc_wen_id.report", "command": command}
            (staged_out / MARKER).write_text(json.dumps(marker) + "\n", encoding="utf-8")
        _publish(staged_out, target, stage / ".replaced", replaces, flag)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


def _publish(
    staged_out: Path, target: Path, trash: Path, replaces: Optional[tuple[int, int]], flag: str
) -> None:
    """Move ``staged_out`` onto ``target``; a report of ours already there goes to ``trash`` first."""
    replacing = replaces is not None and identity(target) == replaces and _is_ours(target)
    if replacing:
        try:
            os.rename(target, trash)
        except FileNotFoundError:
            raise _refuse(
                flag, target, "another run replaced it meanwhile; nothing of this run was written"
            ) from None
    try:
        _rename_no_replace(staged_out, target)
    except OSError as exc:
        if replacing:
            try:
                os.rename(trash, target)  # put the previous output back rather than lose it
            except OSError:
                pass
        if exc.errno in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR, errno.EISDIR):
            raise _refuse(
                flag,
                target,
                "another run wrote there meanwhile (it keeps its output; this run's was not "
                "written): choose another --out",
            ) from None
        raise


def _rename_no_replace(src: Path, dst: Path) -> None:
    """``src`` -> ``dst`` in one step, never replacing what another process put at ``dst``: a folder is
    renamed (which fails onto a folder holding files), a file is hard-linked (which fails onto anything)."""
    if src.is_dir():
        os.rename(src, dst)
        return
    try:
        os.link(src, dst)
    except FileExistsError:
        raise
    except OSError:  # a file system without hard links: the check and the rename are two steps there
        if os.path.lexists(dst):
            raise FileExistsError(errno.EEXIST, "exists", str(dst)) from None
        os.rename(src, dst)
        return
    os.unlink(src)


def shown(path: Path, staged_out: Path, out: Path) -> Path:
    """Where a file written under ``staged_out`` ends up (``out`` as the user spelled it)."""
    try:
        return out / path.relative_to(staged_out)
    except ValueError:
        return path
