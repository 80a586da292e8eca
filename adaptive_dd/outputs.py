"""Writing results so that nothing is lost: checked up front, atomic files, all-or-marked sets.

* :func:`check_output_dir` / :func:`check_output_file` are called before a long run
  so that a file in the way or a read-only folder is reported before any work.
* :func:`atomic_write` writes one file under a temporary name in the same folder
  and renames it into place (``os.replace``), so the file is either the old or the
  new one, never a truncated mix.
* :class:`OutputSet` writes a set of files into ``OUT/.partial-<pid>/`` and moves
  them into ``OUT`` only when all are written. While they are being moved a file
  ``OUT/PARTIAL`` marks the folder; it is removed last. An interruption before the
  move leaves the previous set untouched; one during the move leaves ``PARTIAL``.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Iterator
from pathlib import Path

from adaptive_dd.errors import OutputError

__all__ = ["PARTIAL_MARKER", "OutputSet", "atomic_write", "check_output_dir", "check_output_file"]

PARTIAL_MARKER = "PARTIAL"
"""Name of the file that marks a folder whose result set is incomplete."""


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def check_output_dir(folder: str | Path) -> Path:
    """Create ``folder`` if needed and check that a file can be written in it.

    Raises
    ------
    OutputError
        If a file is in the way, a parent cannot be created, or the folder is not writable.
    """
    folder = Path(folder)
    for p in (folder, *folder.parents):
        if p.exists() and not p.is_dir():
            raise OutputError(f"{folder}: cannot create the output folder: {p} is a file")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        probe = folder / f".write-test-{os.getpid()}"
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as exc:
        raise OutputError(f"{folder}: output folder is not writable: {_reason(exc)}") from None
    return folder


def check_output_file(path: str | Path) -> Path:
    """Check that ``path`` can be written (its folder writable, not a folder itself)."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"{path}: is a folder, expected a file name")
    try:
        check_output_dir(path.parent)
    except OutputError as exc:
        raise OutputError(f"{path}: cannot write the file: {exc}") from None
    return path


def _tmp_name(path: Path) -> Path:
    return path.with_name(f".{path.stem}.tmp-{os.getpid()}{path.suffix}")


@contextlib.contextmanager
def atomic_write(path: str | Path, mode: str = "w", **open_kw) -> Iterator:
    """Open a temporary file beside ``path``; on success rename it onto ``path``.

    On an exception (or ``KeyboardInterrupt``) the temporary file is removed and
    ``path`` keeps its previous content.
    """
    path = Path(path)
    tmp = _tmp_name(path)
    try:
        with open(tmp, mode, **open_kw) as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


class OutputSet:
    """Files written together into ``folder``: all of them or a marked partial set.

    Write each file to ``out.path(name)`` (files outside the folder: ``out.extra(target)``),
    then call :meth:`commit`. Used as a context manager, the set is committed at the
    end of the block and discarded on an exception.
    """

    def __init__(self, folder: str | Path, extras: tuple[str | Path, ...] = ()) -> None:
        self.folder = check_output_dir(folder)
        for e in extras:
            check_output_file(e)
        self.staging = self.folder / f".partial-{os.getpid()}"
        try:
            self.staging.mkdir(exist_ok=True)
        except OSError as exc:
            raise OutputError(f"{self.staging}: cannot create: {_reason(exc)}") from None
        self._files: dict[Path, Path] = {}

    def path(self, name: str) -> Path:
        """Where to write the file that will become ``folder/name``."""
        staged = self.staging / name
        self._files[staged] = self.folder / name
        return staged

    def extra(self, target: str | Path) -> Path:
        """Where to write the file that will become ``target`` (outside the folder)."""
        target = Path(target)
        staged = _tmp_name(target)
        self._files[staged] = target
        return staged

    def commit(self) -> list[Path]:
        """Move every written file into place; returns the final paths."""
        missing = [str(s) for s in self._files if not s.is_file()]
        if missing:
            raise RuntimeError(f"output files announced but not written: {missing}")
        marker = self.folder / PARTIAL_MARKER
        names = ", ".join(str(t) for t in self._files.values())
        with atomic_write(marker) as fh:
            fh.write(f"An interrupted adaptive-dd run left this folder partly updated: {names}\n")
        done = []
        for staged, target in self._files.items():
            os.replace(staged, target)
            done.append(target)
        shutil.rmtree(self.staging, ignore_errors=True)
        marker.unlink()
        return done

    def discard(self) -> None:
        """Remove the staged files; the folder keeps its previous content."""
        for staged in self._files:
            with contextlib.suppress(OSError):
                staged.unlink()
        shutil.rmtree(self.staging, ignore_errors=True)

    def __enter__(self) -> OutputSet:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is not None:
            self.discard()
        else:
            self.commit()
