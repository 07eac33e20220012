"""Output files of the command line, written whole or not at all.

Every file the command line writes (``contacts --out``, ``classify --out``, ``screenshot
--out``, ``export --out``, ``sweep --out``) goes through :class:`Output`: the path is checked and
a temporary file is created *in the same folder* before any work starts (so a directory, a
missing folder or a read-only place such as ``/proc`` is refused at once, with one line, not
after an hour of work); the data is written to the temporary file, flushed to disk, and renamed
over the path only when complete (:func:`os.replace`: atomic on POSIX). On any exception,
Ctrl+C (SIGINT) and SIGTERM included, the temporary file is removed: the old file, if any, is
left exactly as it was and no partial output is ever visible under the path.

What the path is, is respected:

* a **symbolic link** is followed: its target is replaced (atomically, as above) and the link
  stays; a dangling link creates its target.
* an existing **character device, FIFO or socket** (``/dev/null``, ``/dev/stdout``, a named
  pipe, a listening Unix socket) is opened and written directly, as a shell's ``>`` does: no
  temporary file, no rename (the device node stays). Such a stream cannot be taken back: a
  failed run leaves there what was written before the failure. A FIFO without a reader is
  waited for (a line on stderr says so). A block device (a disk) is refused.
* ``-`` means standard output (the data is written when complete; nothing else goes to stdout).

A temporary file is named ``.<name>.<pid>.<random>.part`` and locked (:func:`fcntl.flock`) by
its writer while it exists. One left behind by a writer killed with SIGKILL (or a power cut) is
removed by the next :class:`Output` of the same path (:func:`remove_stale_temporaries`): only
files of that pattern, owned by this user, whose writer process is gone and whose lock is free.

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
import errno
import fcntl
import os
import signal
import socket
import stat
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from types import TracebackType
from typing import IO, Any

from .interrupt import check

__all__ = ["Output", "STDIO", "check_output_path", "remove_stale_temporaries", "special_kind", "uninterrupted"]

STDIO = "-"
"""The file name meaning standard input (readers) or standard output (writers)."""

_SUFFIX = ".part"
"""Suffix of the temporary files (``.<name>.<pid>.<random>.part``)."""


def check_output_path(path: str | os.PathLike[str], *, option: str = "--out") -> Path:
    """The output path if a file can be created there; a ValueError with one line otherwise.

    A symbolic link is checked as its target (the file that will be replaced).

    Raises:
        ValueError: the path is a folder, its folder does not exist or is not a folder, a loop
            of symbolic links.
    """
    p = Path(path)
    if p.is_dir():
        raise ValueError(f"{option} {path}: is a folder: give a file name")
    target = _target(p, option)
    parent = target.parent
    link = f" (the target of the link {path})" if target != p else ""
    if not parent.exists():
        raise ValueError(f"{option} {path}: the folder {parent} does not exist{link}")
    if not parent.is_dir():
        raise ValueError(f"{option} {path}: {parent} is not a folder{link}")
    return p


def _target(p: Path, option: str) -> Path:
    """The file a write to ``p`` replaces: ``p``, or the final target of a symbolic link."""
    if not p.is_symlink():
        return p
    try:
        os.stat(p)
    except OSError as e:
        if e.errno == errno.ELOOP:
            raise ValueError(f"{option} {p}: a loop of symbolic links") from None
    return Path(os.path.realpath(p))


def special_kind(path: str | os.PathLike[str]) -> str | None:
    """What an existing path is, when it is written in place: "character device", "FIFO", "socket"; else None.

    Links are followed. A block device (a disk) is "block device" (refused by :class:`Output`).
    """
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return None
    if stat.S_ISCHR(mode):
        return "character device"
    if stat.S_ISFIFO(mode):
        return "FIFO"
    if stat.S_ISSOCK(mode):
        return "socket"
    if stat.S_ISBLK(mode):
        return "block device"
    return None


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
        make_folders: create the file's missing folders first (``export``, ``screenshot``).

    Raises:
        ValueError: on construction, when the path cannot be written (one line saying why).
    """

    def __init__(
        self, path: str | os.PathLike[str], *, binary: bool = False, option: str = "--out", make_folders: bool = False
    ) -> None:
        self.binary = binary
        self.name = str(path)
        self.stdout = self.name == STDIO
        self.direct = False
        """Whether the path is a device, FIFO or socket written in place (no temporary file)."""
        self._tmp: str | None = None
        self._file: IO[Any] | None = None
        if self.stdout:
            return
        self.path = Path(path)
        kind = special_kind(path)
        if kind is not None:
            self.target = self.path
            self.direct = True
            self._file = self._wrap(_open_special(self.name, kind, option))
            return
        if make_folders and not self.path.is_dir():
            folder = _target(self.path, option).parent
            try:
                folder.mkdir(parents=True, exist_ok=True)
            except OSError as e:
                raise ValueError(f"{option} {path}: cannot create the folder {folder}: {e.strerror}") from None
        check_output_path(path, option=option)
        self.target = _target(self.path, option)
        """The file renamed over: the path, or the target of a symbolic link."""
        remove_stale_temporaries(self.target)
        try:
            fd, self._tmp = tempfile.mkstemp(prefix=f".{self.target.name}.{os.getpid()}.", suffix=_SUFFIX, dir=self.target.parent)
        except OSError as e:
            raise ValueError(f"{option} {path}: cannot write in {self.target.parent}: {e.strerror}") from None
        with contextlib.suppress(OSError):  # the lock tells a living writer from a dead one (a file system without locks: the pid does)
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        self._file = self._wrap(fd)

    def _wrap(self, fd: int) -> IO[Any]:
        return os.fdopen(fd, "wb") if self.binary else os.fdopen(fd, "w", encoding="utf-8", newline="\n")

    @property
    def temporary(self) -> str | None:
        """The temporary file being written (None for standard output, a device, or once finished)."""
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
        """Flush the data to disk and rename the temporary file over the path (a device: flush and close)."""
        if self.stdout:
            (sys.stdout.buffer if self.binary else sys.stdout).flush()
            return
        assert self._file is not None
        if self.direct:
            file, self._file = self._file, None
            file.close()  # flushes; a reader gone raises BrokenPipeError (exit 141)
            return
        assert self._tmp is not None
        try:
            check()  # a stop that a C caller swallowed (app.interrupt): no file, the old one kept
        except BaseException:
            self.discard()
            raise
        with uninterrupted():
            try:
                self._file.flush()
                fd = self._file.fileno()
                os.fsync(fd)
                os.fchmod(fd, _mode_for(self.target))
                os.replace(self._tmp, self.target)  # still open and locked: never seen unlocked under its name
            except OSError as e:
                self._remove()
                raise ValueError(f"cannot write {self.path}: {e.strerror}") from None
            self._tmp = None
            file, self._file = self._file, None
            with contextlib.suppress(OSError):
                file.close()

    def discard(self) -> None:
        """Remove the temporary file (the path keeps its old content, or stays absent)."""
        with uninterrupted():
            self._remove()

    def _remove(self) -> None:
        if self._tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(self._tmp)  # before the close: the file is locked until it is gone
            self._tmp = None
        if self._file is not None:
            file, self._file = self._file, None
            with contextlib.suppress(OSError):
                file.close()

    def __del__(self) -> None:  # an Output created and then abandoned (an error before use)
        self._remove()


def _open_special(path: str, kind: str, option: str) -> int:
    """A descriptor open for writing on a character device, FIFO or socket (module docstring)."""
    if kind == "block device":
        raise ValueError(f"{option} {path}: is a block device (a disk): give a file name")
    st = os.stat(path)
    for std in (1, 2):  # /dev/stdout, /dev/stderr, /proc/self/fd/1: the stream this process already has
        with contextlib.suppress(OSError):
            s = os.fstat(std)
            if (s.st_dev, s.st_ino) == (st.st_dev, st.st_ino):
                return os.dup(std)
    try:
        if kind == "FIFO":
            try:  # a reader waiting: open now; none yet: say so, then wait like a shell's ">" does
                fd = os.open(path, os.O_WRONLY | os.O_NONBLOCK | os.O_CLOEXEC)
            except OSError as e:
                if e.errno != errno.ENXIO:
                    raise
                print(f"{option} {path}: waiting for a reader of the FIFO", file=sys.stderr, flush=True)
                return os.open(path, os.O_WRONLY | os.O_CLOEXEC)
            os.set_blocking(fd, True)
            return fd
        if kind == "socket":
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            try:
                sock.connect(path)
            except OSError:
                sock.close()
                raise
            return sock.detach()
        return os.open(path, os.O_WRONLY | os.O_NOCTTY | os.O_CLOEXEC)
    except OSError as e:
        raise ValueError(f"{option} {path}: cannot write to this {kind}: {e.strerror}") from None


def remove_stale_temporaries(target: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files of ``target`` left by writers that are gone; returns those removed.

    A file is removed only when all of these hold (anything else is left alone): its name is
    ``.<target name>.<pid>.<random>.part`` (what :class:`Output` creates), it is a regular file
    (not a link) owned by this user, no process ``pid`` runs, and no one holds its lock (a
    writer holds it for as long as the file exists, and the kernel drops it when the writer dies).
    """
    target = Path(target)
    prefix = f".{target.name}."
    removed: list[Path] = []
    try:
        entries = list(os.scandir(target.parent))
    except OSError:
        return removed
    for entry in entries:
        name = entry.name
        if not (name.startswith(prefix) and name.endswith(_SUFFIX)):
            continue
        pid, dot, rest = name[len(prefix) : -len(_SUFFIX)].partition(".")
        if not (pid.isdigit() and dot and rest and "." not in rest) or _running(int(pid)):
            continue
        path = target.parent / name
        with contextlib.suppress(OSError):
            _remove_if_free(path)
            removed.append(path)
    return removed


def _remove_if_free(path: Path) -> None:
    """Unlink ``path`` if it is our regular file and its lock is free (OSError otherwise)."""
    fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_CLOEXEC)
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode) or st.st_uid != os.geteuid():
            raise PermissionError(errno.EPERM, "not ours")
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # BlockingIOError: a writer holds it
        now = os.lstat(path)
        if (now.st_dev, now.st_ino) != (st.st_dev, st.st_ino):  # renamed or replaced meanwhile
            raise FileNotFoundError(errno.ENOENT, "replaced")
        os.unlink(path)
    finally:
        os.close(fd)


def _running(pid: int) -> bool:
    """Whether a process ``pid`` exists (one of another user's counts; pid 0 and ours count)."""
    if pid == 0 or pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # EPERM: it exists
        return True
    return True


def _mode_for(path: Path) -> int:
    """Permission bits of the new file: the old file's, or the umask's default for a new one."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask
