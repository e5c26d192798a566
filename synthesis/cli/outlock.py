"""One writer per output folder: an exclusive lock on ``DIR/.cspace-tol.lock``.

``cspace-tol synthesize`` holds the lock from before it reads the checkpoint
until it has written its last file, so two runs into one ``--out`` can never
write the same checkpoint and report.  The lock is ``fcntl.flock`` on a file
that holds the owner's pid: the kernel releases it when the owner exits, even by
SIGKILL, so a stale file never blocks a later run.  A run that ends normally
removes the file.  Where ``fcntl`` does not exist (Windows) no lock is taken.
"""

from __future__ import annotations

import os
from pathlib import Path

from cspace.errors import InputError

__all__ = ["OutputLock", "LOCK_NAME"]

LOCK_NAME = ".cspace-tol.lock"


class OutputLock:
    """The exclusive lock of one output folder (a context manager).

    Parameters
    ----------
    folder : Path
        Created if missing.
    what : str
        What holds the lock, for the message a second run gets.

    Raises
    ------
    InputError
        Another process holds the lock; the message names its pid.
    """

    def __init__(self, folder, what: str = "cspace-tol synthesize"):
        self.path = Path(folder) / LOCK_NAME
        self.what = what
        self._fd = None

    def acquire(self) -> "OutputLock":
        try:
            import fcntl
        except ImportError:    # pragma: no cover - not POSIX
            return self
        self.path.parent.mkdir(parents=True, exist_ok=True)
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _read_pid(fd)
                os.close(fd)
                raise InputError(
                    f"{self.path.parent} is in use by another {self.what} run (pid "
                    f"{holder}); wait for it to end or choose another --out",
                    name="--out", value=str(self.path.parent)) from None
            except BaseException:
                os.close(fd)
                raise
            # the file may have been removed by its previous owner between our
            # open and our lock: then the lock is on a file no one else sees
            try:
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        os.ftruncate(fd, 0)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd
        return self

    def release(self) -> None:
        fd, self._fd = self._fd, None
        if fd is None:
            return
        try:
            os.unlink(self.path)       # while still held: no one can lock it meanwhile
        except OSError:
            pass
        os.close(fd)

    def __enter__(self):
        return self.acquire()

    def __exit__(self, *exc):
        self.release()
        return False


def _read_pid(fd) -> str:
    try:
        text = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
    except OSError:
        text = ""
    return text if text.isdigit() else "unknown"
