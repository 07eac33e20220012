"""Output files of the command line, written whole or not at all.

Every file the command line writes (``contacts --out``, ``classify --out``, ``screenshot
--out``, ``export --out``) goes through :class:`Output`: the path is checked and a temporary
file is created *in the same folder* before any work starts (so a directory, a missing folder
or a read-only place such as ``/proc`` is refused at once, with one line, not after an hour of
work); the data is written to the temporary file, flushed to disk, and renamed over the path
only when complete (:func:`os.replace`: atomic on POSIX). On any exception, Ctrl+C (SIGINT)
and SIGTERM included, the temporary file is removed: the old file, if any, is left exactly as
it was and no partial output is ever visible under the path.

``-`` means standard output (the data is written when complete; nothing else goes to stdout).

Examples:
    >>> import os, tempfile
    >>> d = tempfile.mkdtemp()
    >>> with Output(os.path.join(d, "a.txt")) as f:
    ...     _ = f.write("done")
    >>> open(os.path.join(d, "a.txt")).read(), os.listdir(d)
    ('done', ['a.txt'])
    >>> Output(d)
    Traceback (most recent call last):
    ...
    ValueError: --out ...: is a folder: give a file name
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import IO, Any

__all__ = ["Output", "STDIO", "check_output_path", "uninterrupted"]

STDIO = "-"
"""The file name meaning standard input (readers) or standard output (writers)."""


def check_output_path(path: str | os.PathLike[str], *, option: str = "--out") -> Path:
    """The output path if a file can be created there; a ValueError with one line otherwise.

    Raises:
        ValueError: the path is a folder, its folder does not exist or is not a folder.
    """
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{option} {path}: is a folder: give a file name")
    parent = p.parent
    if not parent.exists():
        raise ValueError(f"{option} {path}: the folder {parent} does not exist")
    if not parent.is_dir():
        raise ValueError(f"{option} {path}: {parent} is not a folder")
    return p


@contextlib.contextmanager
def uninterrupted() -> Iterator[None]:
    """Hold SIGINT and SIGTERM for the few statements inside (delivered right after them).

    Used around the rename and the clean-up, so that a second Ctrl+C cannot leave a temporary
    file behind or a rename half done. Only the main thread can block signals for itself; in
    another thread this does nothing (signals are delivered to the main thread anyway).
    """
    held = {signal.SIGINT, signal.SIGTERM}
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    except (AttributeError, OSError, ValueError):  # not POSIX: nothing to hold
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


class Output:
    """A file written whole or not at all (module docstring); ``-`` is standard output.

    Args:
        path: the file to write, or ``-``.
        binary: bytes (True) or text (False, UTF-8, Unix line ends).
        option: the option's name for messages.

    Raises:
        ValueError: on construction, when the path cannot be written (one line saying why).
    """

    def __init__(self, path: str | os.PathLike[str], *, binary: bool = False, option: str = "--out") -> None:
        self.binary = binary
        self.name = str(path)
        self.stdout = self.name == STDIO
        self._tmp: str | None = None
        self._file: IO[Any] | None = None
        if self.stdout:
            return
        self.path = check_output_path(path, option=option)
        try:
            fd, self._tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".part", dir=self.path.parent)
        except OSError as e:
            raise ValueError(f"{option} {path}: cannot write in {self.path.parent}: {e.strerror}") from None
        self._file = os.fdopen(fd, "wb") if binary else os.fdopen(fd, "w", encoding="utf-8", newline="\n")

    @property
    def temporary(self) -> str | None:
        """The temporary file being written (None for standard output or once finished)."""
        return self._tmp

    def __enter__(self) -> IO[Any]:
        if self.stdout:
            return sys.stdout.buffer if self.binary else sys.stdout
        assert self._file is not None
        return self._file

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if kind is None:
            self.commit()
        else:
            self.discard()

    def commit(self) -> None:
        """Flush the data to disk and rename the temporary file over the path."""
        if self.stdout:
            (sys.stdout.buffer if self.binary else sys.stdout).flush()
            return
        assert self._file is not None and self._tmp is not None
        with uninterrupted():
            try:
                self._file.flush()
                os.fsync(self._file.fileno())
                self._file.close()
                os.chmod(self._tmp, _mode_for(self.path))
                os.replace(self._tmp, self.path)
            except OSError as e:
                self._remove()
                raise ValueError(f"cannot write {self.path}: {e.strerror}") from None
            self._tmp = None

    def discard(self) -> None:
        """Remove the temporary file (the path keeps its old content, or stays absent)."""
        with uninterrupted():
            self._remove()

    def _remove(self) -> None:
        if self._file is not None:
            with contextlib.suppress(OSError):
                self._file.close()
        if self._tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(self._tmp)
            self._tmp = None

    def __del__(self) -> None:  # an Output created and then abandoned (an error before use)
        self._remove()


def _mode_for(path: Path) -> int:
    """Permission bits of the new file: the old file's, or the umask's default for a new one."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask
